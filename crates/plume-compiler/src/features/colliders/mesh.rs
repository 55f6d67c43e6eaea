//! `Mesh`: a closed triangle mesh from an OBJ file, placed in the world by `offset`, `scale`
//! and `rotation`; particles stay outside it. The mesh is baked once into a signed distance
//! field (`crate::base::sdf`) whose f32 values the GPU (the `collider_data` binding) and the f64
//! reference both interpolate, so both collide with the very same surface: the field's zero
//! level, which is the mesh to within its resolution (a cell is the mesh's longest side over
//! `resolution`).
//!
//! **Swept.** The test marches the substep's segment through the field's box: a step may not
//! be longer than the field's value over the largest rate at which the trilinear field can
//! change along the segment (|dx| + |dy| + |dz| in cells, since neighbouring nodes differ by at
//! most a cell), so no crossing of the field is stepped over, except that a step is never
//! shorter than an eighth of a cell (so that a segment grazing the surface ends): a wall two
//! cells thick, which the field holds, is never passed through at any speed. A crossing is
//! then bisected (20 halvings) to the last point outside; its normal is the field's gradient
//! there (central differences half a cell wide).
//!
//! **Inside.** A particle found inside (spawned there) is moved out along the gradient by the
//! field's depth, up to four times.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DMat3, DVec3};

use serde::Deserialize;

use super::{check_bounce, collider_path, Collider, ColliderIr, Hit, Surface};
use crate::base::check::Checker;
use crate::base::mesh::TriMesh;
use crate::base::path::ValuePath;
use crate::base::sdf::{read_and_bake, Sdf, MAX_RESOLUTION};
use crate::base::values::Vec3;
use crate::base::writer::{f32_lit, Writer};

/// The resolution when the file gives none.
pub(crate) const DEFAULT_RESOLUTION: u32 = 32;

/// The fewest cells along the mesh's longest side.
pub(crate) const MIN_RESOLUTION: u32 = 4;

/// Bisection halvings of a crossing.
const BISECTIONS: u32 = 20;

/// The shortest march step, in cells.
const MIN_STEP_CELLS: f64 = 0.125;

/// Push-out tries for a particle found inside.
const PUSH_TRIES: u32 = 4;

/// A segment this short (in cells) does not move.
const TINY: f64 = 1e-30;

/// A mesh read from its file and its baked field (both in the mesh's own coordinates).
#[derive(Clone, Debug, PartialEq)]
pub struct Baked {
    /// The signed distance field particles collide with.
    pub(crate) sdf: Sdf,
    /// The mesh itself, for drawing the scene.
    pub(crate) mesh: TriMesh,
}

/// A mesh collider in the IR: the baked field and where it sits.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshIr {
    /// The mesh file as the effect names it.
    pub file: String,
    /// Where the mesh's origin sits in the world.
    pub offset: DVec3,
    /// The mesh's size against the world's.
    pub scale: f64,
    /// The mesh's rotation (its axes in world coordinates, as columns).
    pub rotation: DMat3,
    /// The mesh and its baked field, in the mesh's own coordinates.
    pub baked: Arc<Baked>,
}

/// The rotation `rotation` (degrees about x, then y, then z) stands for.
pub(crate) fn rotation_matrix(rotation: Vec3) -> DMat3 {
    crate::base::mesh::rotation_degrees(rotation.d())
}

/// `Mesh(...)` as effect files write it: a closed triangle mesh from an OBJ file, baked into
/// a signed distance field; particles stay outside it.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mesh {
    /// The OBJ file, relative to the effect file.
    pub file: String,
    /// Where the mesh's origin sits in the world (m).
    #[serde(default = "crate::base::values::origin")]
    pub offset: Vec3,
    /// The mesh's size against the world's (> 0).
    #[serde(default = "crate::base::values::unit_scale")]
    pub scale: f64,
    /// Degrees about x, then y, then z (the world's axes).
    #[serde(default = "crate::base::values::origin")]
    pub rotation: Vec3,
    /// Field cells along the mesh's longest side (4 to 128).
    #[serde(default = "default_resolution")]
    pub resolution: u32,
    /// Fraction of normal speed kept on a bounce, in [0, 1].
    pub restitution: f64,
    /// Fraction of tangential speed lost on a bounce, in [0, 1].
    pub friction: f64,
    /// The mesh and its baked field, made by `read_meshes` before the checks.
    #[serde(skip)]
    pub baked: Option<Arc<Baked>>,
}

/// The fields of [`Mesh`].
pub(crate) const FIELDS: &[&str] = &[
    "file",
    "offset",
    "scale",
    "rotation",
    "resolution",
    "restitution",
    "friction",
];

fn default_resolution() -> u32 {
    DEFAULT_RESOLUTION
}

impl Mesh {
    /// Checks the placement, the resolution (the file was read before) and the bounce; `path`
    /// names the variant.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        check_placement_and_resolution(
            path,
            c,
            (self.offset, self.scale, self.rotation, self.resolution),
            self.baked.is_some(),
        );
        check_bounce(path, c, self.restitution, self.friction);
    }

    /// Lowers the checked mesh collider.
    pub(crate) fn lower(&self) -> ColliderIr {
        ColliderIr {
            surface: Surface::Mesh(MeshIr {
                file: self.file.clone(),
                offset: self.offset.d(),
                scale: self.scale,
                rotation: rotation_matrix(self.rotation),
                baked: self
                    .baked
                    .clone()
                    .expect("the checks refuse a mesh collider not read"),
            }),
            restitution: self.restitution,
            friction: self.friction,
        }
    }
}

/// Checks a mesh collider's placement and resolution (its file was read before).
fn check_placement_and_resolution(
    path: &ValuePath,
    c: &mut Checker,
    (offset, scale, rotation, resolution): (Vec3, f64, Vec3, u32),
    baked: bool,
) {
    crate::base::mesh::check_placement(path, c, (offset, scale, rotation));
    if !(MIN_RESOLUTION..=MAX_RESOLUTION).contains(&resolution) {
        c.error(
            &path.field("resolution"),
            format!(
                "resolution is the cells along the mesh's longest side, {MIN_RESOLUTION} to {MAX_RESOLUTION}, got {resolution}"
            ),
        );
    } else if !baked {
        c.error(&path.field("file"), "the mesh was not read");
    }
}

/// Reads every `Mesh` collider's file and bakes (or loads from the cache) its field, files
/// relative to `base_dir`; what is wrong is recorded in `c` at the collider's `file`: an
/// unreadable or empty mesh, a NaN vertex, a mesh that is not closed.
pub(crate) fn read_meshes(collide: &mut [Collider], base_dir: Option<&Path>, c: &mut Checker) {
    for (i, collider) in collide.iter_mut().enumerate() {
        let path = collider_path(i, collider);
        let Collider::Mesh(Mesh {
            file,
            resolution,
            baked,
            ..
        }) = collider
        else {
            continue;
        };
        if !(MIN_RESOLUTION..=MAX_RESOLUTION).contains(resolution) {
            continue; // the checks say why
        }
        let full = base_dir.map_or_else(|| PathBuf::from(&*file), |dir| dir.join(&*file));
        match bake_file(&full, *resolution) {
            Ok(read) => *baked = Some(Arc::new(read)),
            Err(message) => c.error(&path.field("file"), message),
        }
    }
}

fn bake_file(path: &Path, resolution: u32) -> Result<Baked, String> {
    let (sdf, mesh) = read_and_bake(path, resolution)?;
    Ok(Baked { sdf, mesh })
}

impl MeshIr {
    /// The mesh's triangles placed in the world.
    pub(crate) fn world_triangles(&self) -> impl Iterator<Item = [DVec3; 3]> + '_ {
        self.baked
            .mesh
            .placed_triangles(self.offset, self.scale, self.rotation)
    }

    /// World `x` in grid coordinates (cells from node 0).
    fn grid(&self, x: DVec3) -> DVec3 {
        let local = self.rotation.transpose() * (x - self.offset) / self.scale;
        (local - self.baked.sdf.min) / self.baked.sdf.cell
    }

    fn in_box(&self, g: DVec3) -> bool {
        g.cmpge(DVec3::ZERO).all() && g.cmple(self.baked.sdf.last()).all()
    }

    /// The field's value at grid point `g`, in cells.
    fn cells(&self, g: DVec3) -> f64 {
        self.baked.sdf.value(g) / self.baked.sdf.cell
    }

    /// The world normal at grid point `g` (`fallback` where the gradient vanishes).
    fn normal(&self, g: DVec3, fallback: DVec3) -> DVec3 {
        let n = self.rotation * self.baked.sdf.gradient(g);
        let l = n.length();
        if l > 1e-12 {
            n / l
        } else {
            fallback
        }
    }

    /// The first contact of segment `a` -> `b` (see the module doc).
    pub fn hit(&self, a: DVec3, b: DVec3) -> Option<Hit> {
        let ga = self.grid(a);
        let d = self.grid(b) - ga;
        let last = self.baked.sdf.last();
        let (mut s0, mut s1) = (0.0_f64, 1.0_f64);
        for axis in 0..3 {
            let (p, dp, hi) = (ga[axis], d[axis], last[axis]);
            if dp.abs() <= TINY {
                if p < 0.0 || p > hi {
                    return None;
                }
            } else {
                let (t1, t2) = (-p / dp, (hi - p) / dp);
                s0 = s0.max(t1.min(t2));
                s1 = s1.min(t1.max(t2));
            }
        }
        let rate = d.x.abs() + d.y.abs() + d.z.abs();
        if s0 > s1 || rate <= TINY {
            return None;
        }
        let min_step = MIN_STEP_CELLS / d.abs().max_element();
        let mut s = s0;
        let mut f = self.cells(ga + d * s);
        if f <= 0.0 {
            return None; // inside already: the push-out moves it
        }
        for _ in 0..self.march_limit() {
            let next = (s + (f / rate).max(min_step)).min(s1);
            let f_next = self.cells(ga + d * next);
            if f_next <= 0.0 {
                let (mut lo, mut hi) = (s, next);
                for _ in 0..BISECTIONS {
                    let mid = 0.5 * (lo + hi);
                    if self.cells(ga + d * mid) > 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                let fallback = crate::features::forces::safe_normalize(a - b);
                return Some(Hit {
                    s: lo,
                    normal: self.normal(ga + d * lo, fallback),
                });
            }
            if next >= s1 {
                return None;
            }
            s = next;
            f = f_next;
        }
        None
    }

    /// Steps that cover any segment through the box at the shortest step.
    fn march_limit(&self) -> u32 {
        (8 * self.baked.sdf.counts.iter().max().copied().unwrap_or(2)) + 2
    }

    /// A point inside moved out along the gradient, `margin` beyond the surface.
    pub(crate) fn push_out(&self, mut x: DVec3, margin: f64) -> DVec3 {
        let mut g = self.grid(x);
        if !self.in_box(g) {
            return x;
        }
        let mut depth = self.baked.sdf.value(g) * self.scale;
        for _ in 0..PUSH_TRIES {
            if depth >= 0.0 {
                break;
            }
            x += self.normal(g, DVec3::Y) * (margin - depth);
            g = self.grid(x);
            depth = self.baked.sdf.value(g) * self.scale;
        }
        x
    }

    /// Whether `x` is on the allowed side (outside the field's zero level).
    pub fn allows(&self, x: DVec3) -> bool {
        let g = self.grid(x);
        !self.in_box(g) || self.baked.sdf.value(g) >= 0.0
    }

    /// The largest coordinate magnitude the placed field reaches (for the margin).
    pub fn scale(&self) -> f64 {
        let sdf = &self.baked.sdf;
        let far = sdf
            .min
            .abs()
            .max((sdf.min + sdf.last() * sdf.cell).abs())
            .length();
        self.offset.abs().max_element() + self.scale * far
    }

    /// The field's cell in the world, the finest feature it holds.
    pub fn cell(&self) -> f64 {
        self.baked.sdf.cell * self.scale
    }

    /// One line for `--emit ir`.
    pub fn describe(&self) -> String {
        let [nx, ny, nz] = self.baked.sdf.counts;
        format!(
            "Mesh `{}` offset ({}, {}, {}) scale {}: {nx} x {ny} x {nz} field nodes, cell {} m",
            self.file,
            self.offset.x,
            self.offset.y,
            self.offset.z,
            self.scale,
            self.cell()
        )
    }

    /// The WGSL twins of [`MeshIr::hit`] and `push_out`, reading the field from
    /// `collider_data` at `offset`.
    pub(crate) fn emit(&self, w: &mut Writer, i: usize, offset: u32) {
        let [nx, ny, _] = self.baked.sdf.counts;
        let v3 = |v: DVec3| {
            format!(
                "vec3<f32>({}, {}, {})",
                f32_lit(v.x),
                f32_lit(v.y),
                f32_lit(v.z)
            )
        };
        // grid = to_grid · (x − offset) − min / cell; rows of Rᵀ / (scale · cell).
        let to_grid = self.rotation.transpose() / (self.scale * self.baked.sdf.cell);
        let last = self.baked.sdf.last();
        w.block(format!("fn mesh{i}_grid(x: vec3<f32>) -> vec3<f32>"), |w| {
            w.line(format!("let p = x - {};", v3(self.offset)));
            w.line(format!(
                "return vec3<f32>(dot({}, p), dot({}, p), dot({}, p)) - {};",
                v3(to_grid.row(0)),
                v3(to_grid.row(1)),
                v3(to_grid.row(2)),
                v3(self.baked.sdf.min / self.baked.sdf.cell)
            ));
        });
        w.block(format!("fn mesh{i}_at(c: vec3<u32>) -> f32"), |w| {
            w.line(format!(
                "return collider_data[{offset}u + (c.z * {ny}u + c.y) * {nx}u + c.x];"
            ))
        });
        w.comment("The trilinear field at grid point g, clamped to the grid (in mesh units).");
        w.block(format!("fn mesh{i}_value(g: vec3<f32>) -> f32"), |w| {
            w.line(format!("let gc = clamp(g, vec3<f32>(0.0), {});", v3(last)));
            w.line(format!(
                "let base = min(floor(gc), {});",
                v3(last - DVec3::ONE)
            ));
            w.line("let f = gc - base;");
            w.line("let c = vec3<u32>(base);");
            w.line(format!("let a000 = mesh{i}_at(c);"));
            for (name, off) in [
                ("a100", "1u, 0u, 0u"),
                ("a010", "0u, 1u, 0u"),
                ("a110", "1u, 1u, 0u"),
                ("a001", "0u, 0u, 1u"),
                ("a101", "1u, 0u, 1u"),
                ("a011", "0u, 1u, 1u"),
                ("a111", "1u, 1u, 1u"),
            ] {
                w.line(format!("let {name} = mesh{i}_at(c + vec3<u32>({off}));"));
            }
            w.line("let x00 = a000 + (a100 - a000) * f.x;");
            w.line("let x10 = a010 + (a110 - a010) * f.x;");
            w.line("let x01 = a001 + (a101 - a001) * f.x;");
            w.line("let x11 = a011 + (a111 - a011) * f.x;");
            w.line("let y0 = x00 + (x10 - x00) * f.y;");
            w.line("let y1 = x01 + (x11 - x01) * f.y;");
            w.line("return y0 + (y1 - y0) * f.z;");
        });
        w.block(
            format!("fn mesh{i}_normal(g: vec3<f32>, fallback: vec3<f32>) -> vec3<f32>"),
            |w| {
                w.line(format!(
                    "let d = vec3<f32>(mesh{i}_value(g + vec3<f32>(0.5, 0.0, 0.0)) - mesh{i}_value(g - vec3<f32>(0.5, 0.0, 0.0)), mesh{i}_value(g + vec3<f32>(0.0, 0.5, 0.0)) - mesh{i}_value(g - vec3<f32>(0.0, 0.5, 0.0)), mesh{i}_value(g + vec3<f32>(0.0, 0.0, 0.5)) - mesh{i}_value(g - vec3<f32>(0.0, 0.0, 0.5)));"
                ));
                let r = self.rotation;
                w.line(format!(
                    "let n = d.x * {} + d.y * {} + d.z * {};",
                    v3(r.x_axis),
                    v3(r.y_axis),
                    v3(r.z_axis)
                ));
                w.line("let l = length(n);");
                w.line("return select(fallback, n / l, l > 1e-12);");
            },
        );
        let inv_cell = f32_lit(1.0 / self.baked.sdf.cell);
        w.block(
            format!("fn collider_hit_{i}(a: vec3<f32>, b: vec3<f32>) -> vec4<f32>"),
            |w| {
                w.line("let none = vec4<f32>(2.0, 0.0, 1.0, 0.0);");
                w.line(format!("let ga = mesh{i}_grid(a);"));
                w.line(format!("let d = mesh{i}_grid(b) - ga;"));
                w.line(format!("let last = {};", v3(last)));
                w.line("var s0 = 0.0;");
                w.line("var s1 = 1.0;");
                for c in ["x", "y", "z"] {
                    w.block(format!("if (abs(d.{c}) <= {})", f32_lit(TINY)), |w| {
                        w.block(format!("if (ga.{c} < 0.0 || ga.{c} > last.{c})"), |w| {
                            w.line("return none;")
                        });
                    });
                    w.block("else", |w| {
                        w.line(format!("let t1 = -ga.{c} / d.{c};"));
                        w.line(format!("let t2 = (last.{c} - ga.{c}) / d.{c};"));
                        w.line("s0 = max(s0, min(t1, t2));");
                        w.line("s1 = min(s1, max(t1, t2));");
                    });
                }
                w.line("let rate = abs(d.x) + abs(d.y) + abs(d.z);");
                w.block(format!("if (s0 > s1 || rate <= {})", f32_lit(TINY)), |w| {
                    w.line("return none;")
                });
                w.line(format!(
                    "let min_step = {} / max(abs(d.x), max(abs(d.y), abs(d.z)));",
                    f32_lit(MIN_STEP_CELLS)
                ));
                w.line("var s = s0;");
                w.line(format!("var f = mesh{i}_value(ga + d * s) * {inv_cell};"));
                w.block("if (f <= 0.0)", |w| w.line("return none;"));
                w.block(
                    format!("for (var it = 0u; it < {}u; it++)", self.march_limit()),
                    |w| {
                        w.line("let next = min(s + max(f / rate, min_step), s1);");
                        w.line(format!(
                            "let f_next = mesh{i}_value(ga + d * next) * {inv_cell};"
                        ));
                        w.block("if (f_next <= 0.0)", |w| {
                            w.line("var lo = s;");
                            w.line("var hi = next;");
                            w.block(format!("for (var k = 0u; k < {BISECTIONS}u; k++)"), |w| {
                                w.line("let mid = 0.5 * (lo + hi);");
                                w.block(
                                    format!("if (mesh{i}_value(ga + d * mid) * {inv_cell} > 0.0)"),
                                    |w| w.line("lo = mid;"),
                                );
                                w.block("else", |w| w.line("hi = mid;"));
                            });
                            w.line("let back = a - b;");
                            w.line("let bl = length(back);");
                            w.line("let fallback = select(vec3<f32>(0.0), back / bl, bl > 1e-10);");
                            w.line(format!(
                                "return vec4<f32>(lo, mesh{i}_normal(ga + d * lo, fallback));"
                            ));
                        });
                        w.block("if (next >= s1)", |w| w.line("return none;"));
                        w.line("s = next;");
                        w.line("f = f_next;");
                    },
                );
                w.line("return none;");
            },
        );
        w.block(
            format!("fn collider_push_{i}(x_in: vec3<f32>, margin: f32) -> vec3<f32>"),
            |w| {
                w.line("var x = x_in;");
                w.line(format!("var g = mesh{i}_grid(x);"));
                w.block(
                    format!("if (any(g < vec3<f32>(0.0)) || any(g > {}))", v3(last)),
                    |w| w.line("return x;"),
                );
                let scale = f32_lit(self.scale);
                w.line(format!("var depth = mesh{i}_value(g) * {scale};"));
                w.block(format!("for (var k = 0u; k < {PUSH_TRIES}u; k++)"), |w| {
                    w.block("if (depth >= 0.0)", |w| w.line("break;"));
                    w.line(format!(
                        "x = x + mesh{i}_normal(g, vec3<f32>(0.0, 1.0, 0.0)) * (margin - depth);"
                    ));
                    w.line(format!("g = mesh{i}_grid(x);"));
                    w.line(format!("depth = mesh{i}_value(g) * {scale};"));
                });
                w.line("return x;");
            },
        );
    }
}
