//! Spawn shapes: where a particle starts. Each shape's WGSL (`ShapeIr::emit_wgsl`, inside an
//! emitter's `emit_E` function) and its f64 twin (`ShapeIr::sample`) sit side by side and read
//! the same draws: the POSITION stream's three uniform numbers, a mesh's or a box surface's
//! picking word, or the emitter's own spawn counter k.

use std::f64::consts::PI;
use std::sync::Arc;

use glam::DVec3;

use crate::base::rng::{stream, wgsl_unit3, ParticleDraws};
use crate::base::writer::{f32_lit, u32_lit, vec3_lit, Writer};
use crate::expr::Expr;
use crate::features::emitter::Basis;
use crate::features::mesh_emission::MeshSurface;

/// Spawn shape in the IR.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum ShapeIr {
    /// One point.
    Point(DVec3),
    /// Uniform in a ball.
    Sphere {
        /// Centre.
        center: DVec3,
        /// Radius.
        radius: f64,
    },
    /// Uniform on a sphere's surface.
    SphereSurface {
        /// Centre.
        center: DVec3,
        /// Radius.
        radius: f64,
    },
    /// Uniform in a box.
    Box {
        /// Lower corner.
        min: DVec3,
        /// Upper corner.
        max: DVec3,
    },
    /// Uniform by area on a box's six faces.
    BoxSurface {
        /// Lower corner.
        min: DVec3,
        /// Upper corner.
        max: DVec3,
        /// Per face but the last (−x, +x, −y, +y, −z: see [`box_face_thresholds`]), the 32-bit
        /// word below which the faces up to it are picked; 2^32 where no word is.
        thresholds: [u64; 5],
    },
    /// Uniform in a disc.
    Disc {
        /// Centre.
        center: DVec3,
        /// Radius.
        radius: f64,
        /// Tangents of the disc's plane.
        basis: Basis,
    },
    /// Uniform by angle on a circle.
    Circle {
        /// Centre.
        center: DVec3,
        /// Radius.
        radius: f64,
        /// Tangents of the circle's plane.
        basis: Basis,
    },
    /// Uniform in a cone's volume (a frustum), or on its side.
    Cone(ConeIr),
    /// Uniform in a torus's volume, or by area on its surface.
    Torus(super::torus::TorusIr),
    /// Lattice: point (ix, iy, iz) is `origin + i * step` per axis.
    Grid {
        /// Position of lattice point (0, 0, 0).
        origin: DVec3,
        /// Spacing per axis (0 on an axis with one point).
        step: DVec3,
        /// Points per axis.
        counts: [u32; 3],
    },
    /// Listed points, in order.
    Points(Vec<DVec3>),
    /// On a mesh's surface or in its volume.
    Mesh(Arc<MeshSurface>),
    /// An expression of the spawn's time and random numbers.
    Custom {
        /// The typed, folded expression.
        expr: Expr,
        /// The farthest a sample of its spawns lies from the origin.
        extent: f64,
    },
}

/// The face thresholds of a box surface between `min` and `max`: for faces −x, +x, −y, +y, −z
/// (+z last), T_i = ⌊2³² (a_0 + … + a_i) / A⌋ with a_i the faces' areas and A their sum, so
/// that the face picked by a word r is the number of i with r >= T_i (T_i = 2³² never
/// counts). None when the box has no area (a point or a segment: its volume is its surface).
pub(crate) fn box_face_thresholds(min: DVec3, max: DVec3) -> Option<[u64; 5]> {
    let d = max - min;
    let areas = [
        d.y * d.z,
        d.y * d.z,
        d.x * d.z,
        d.x * d.z,
        d.x * d.y,
        d.x * d.y,
    ];
    let total: f64 = areas.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let mut thresholds = [0u64; 5];
    let mut sum = 0.0;
    for (i, t) in thresholds.iter_mut().enumerate() {
        sum += areas[i];
        *t = ((sum / total) * 4_294_967_296.0)
            .floor()
            .min(4_294_967_296.0) as u64;
    }
    Some(thresholds)
}

impl ShapeIr {
    /// The centre that radial velocities point away from.
    pub(crate) fn center(&self) -> DVec3 {
        match self {
            ShapeIr::Point(p) => *p,
            ShapeIr::Sphere { center, .. }
            | ShapeIr::SphereSurface { center, .. }
            | ShapeIr::Disc { center, .. }
            | ShapeIr::Circle { center, .. } => *center,
            ShapeIr::Box { min, max } | ShapeIr::BoxSurface { min, max, .. } => (*min + *max) * 0.5,
            ShapeIr::Cone(c) => c.base + c.axis * (0.5 * c.height),
            ShapeIr::Torus(t) => t.center,
            ShapeIr::Grid {
                origin,
                step,
                counts,
            } => {
                let n = DVec3::new(
                    f64::from(counts[0] - 1),
                    f64::from(counts[1] - 1),
                    f64::from(counts[2] - 1),
                );
                *origin + *step * n * 0.5
            }
            ShapeIr::Points(ps) => ps.iter().copied().sum::<DVec3>() / ps.len().max(1) as f64,
            ShapeIr::Mesh(m) => m.center,
            // Written freely: Radial and Tangent velocities take the origin as its centre.
            ShapeIr::Custom { .. } => DVec3::ZERO,
        }
    }

    /// Below this squared distance (m²) from the shape's centre, a Radial velocity has no
    /// direction and draws a random one. Relative to the shape's size, so that the GPU's f32
    /// positions (off by a few ulps of the coordinates) and the reference's f64 ones make the
    /// same choice: a Grid or Points spawn at the centre itself is never pushed by f32 rounding.
    pub(crate) fn radial_center_eps2(&self) -> f64 {
        (4e-6 * self.extent().max(1.0)).powi(2)
    }

    /// The farthest any spawn position lies from the origin (for precision warnings).
    pub(crate) fn extent(&self) -> f64 {
        match self {
            ShapeIr::Point(p) => p.abs().max_element(),
            ShapeIr::Sphere { center, radius }
            | ShapeIr::SphereSurface { center, radius }
            | ShapeIr::Disc { center, radius, .. }
            | ShapeIr::Circle { center, radius, .. } => center.abs().max_element() + radius,
            ShapeIr::Box { min, max } | ShapeIr::BoxSurface { min, max, .. } => {
                min.abs().max(max.abs()).max_element()
            }
            ShapeIr::Cone(c) => {
                c.base
                    .abs()
                    .max((c.base + c.axis * c.height).abs())
                    .max_element()
                    + c.wide
            }
            ShapeIr::Torus(t) => t.center.abs().max_element() + t.radius + t.tube,
            ShapeIr::Grid {
                origin,
                step,
                counts,
            } => {
                let last = *origin
                    + *step
                        * DVec3::new(
                            f64::from(counts[0] - 1),
                            f64::from(counts[1] - 1),
                            f64::from(counts[2] - 1),
                        );
                origin.abs().max(last.abs()).max_element()
            }
            ShapeIr::Points(ps) => ps.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max),
            ShapeIr::Mesh(m) => m.extent,
            ShapeIr::Custom { extent, .. } => *extent,
        }
    }

    /// Emits what emitter `e`'s shape needs at the module's top level, before its `emit_e`
    /// function: a mesh's picking function (its data at `data_offset` in `spawn_data`) or the
    /// listed points.
    pub(crate) fn emit_items(&self, w: &mut Writer, e: usize, data_offset: u32) {
        match self {
            ShapeIr::Mesh(m) => m.emit(w, e, data_offset),
            ShapeIr::Points(ps) => {
                let items: Vec<String> = ps.iter().map(|p| vec3_lit(*p)).collect();
                w.line(format!(
                    "const POINTS_{e} = array<vec3<f32>, {}>({});",
                    ps.len(),
                    items.join(", ")
                ));
            }
            _ => {}
        }
    }

    /// Emits the statements that set `s.x` (and, on a mesh, `surface_normal`) inside emitter
    /// `e`'s `emit_e(id, k, step)`, for steps of `dt`: the WGSL twin of [`Self::sample`].
    pub(crate) fn emit_wgsl(&self, w: &mut Writer, e: usize, dt: f64) {
        let two_pi = f32_lit(2.0 * PI);
        let pi = f32_lit(PI);
        match self {
            ShapeIr::Custom { expr, .. } => super::expression::emit(w, expr, "s.x", dt),
            ShapeIr::Point(p) => w.line(format!("s.x = {};", vec3_lit(*p))),
            ShapeIr::Sphere { center, radius } => emit_sphere(w, *center, *radius, false),
            ShapeIr::SphereSurface { center, radius } => emit_sphere(w, *center, *radius, true),
            ShapeIr::Box { min, max } => {
                w.line(format!(
                    "s.x = {} + {} * {};",
                    vec3_lit(*min),
                    vec3_lit(*max - *min),
                    wgsl_unit3(stream::POSITION)
                ));
            }
            ShapeIr::BoxSurface {
                min,
                max,
                thresholds,
            } => {
                w.comment("A face by area (integer thresholds), then uniform on it.");
                w.line(format!("let pick = rand_u32(id, {}u);", stream::FACE_PICK));
                let counted: Vec<String> = thresholds
                    .iter()
                    .filter(|&&t| t < 1 << 32)
                    .map(|&t| format!("u32(pick >= {})", u32_lit(t as u32)))
                    .collect();
                match counted.is_empty() {
                    true => w.line("let face = 0u;"),
                    false => w.line(format!("let face = {};", counted.join(" + "))),
                }
                w.line(format!("var f = {};", wgsl_unit3(stream::POSITION)));
                w.line("f[face / 2u] = f32(face % 2u);");
                w.line(format!(
                    "s.x = {} + {} * f;",
                    vec3_lit(*min),
                    vec3_lit(*max - *min)
                ));
            }
            ShapeIr::Disc {
                center,
                radius,
                basis,
            } => {
                w.comment("Uniform in the disc: radius ~ sqrt(u).");
                w.line(format!("let u = {};", wgsl_unit3(stream::POSITION)));
                w.line(format!("let r = {} * sqrt(u.x);", f32_lit(*radius)));
                w.line(format!("let phi = {two_pi} * u.y - {pi};"));
                w.line(format!(
                    "s.x = {} + r * (cos(phi) * {} + sin(phi) * {});",
                    vec3_lit(*center),
                    vec3_lit(basis.t1),
                    vec3_lit(basis.t2)
                ));
            }
            ShapeIr::Circle {
                center,
                radius,
                basis,
            } => {
                w.comment("Uniform by angle on the circle.");
                w.line(format!(
                    "let phi = {two_pi} * rand_unit(id, {}u) - {pi};",
                    stream::POSITION + 1
                ));
                w.line(format!(
                    "s.x = {} + {} * (cos(phi) * {} + sin(phi) * {});",
                    vec3_lit(*center),
                    f32_lit(*radius),
                    vec3_lit(basis.t1),
                    vec3_lit(basis.t2)
                ));
            }
            ShapeIr::Cone(c) => c.emit_wgsl(w),
            ShapeIr::Torus(t) => t.emit_wgsl(w),
            ShapeIr::Grid {
                origin,
                step,
                counts,
            } => {
                let [nx, ny, nz] = *counts;
                w.comment("Lattice point k (mod the lattice size): x fastest, then y, then z.");
                w.line(format!(
                    "let g = k % {};",
                    u32_lit(nx.wrapping_mul(ny).wrapping_mul(nz))
                ));
                w.line(format!(
                    "let gi = vec3<u32>(g % {nx}u, (g / {nx}u) % {ny}u, g / {});",
                    u32_lit(nx * ny)
                ));
                w.line(format!(
                    "s.x = {} + vec3<f32>(gi) * {};",
                    vec3_lit(*origin),
                    vec3_lit(*step)
                ));
            }
            ShapeIr::Points(ps) => {
                w.line(format!("s.x = POINTS_{e}[k % {}u];", ps.len()));
            }
            ShapeIr::Mesh(_) => {
                w.line(format!(
                    "let on_mesh = mesh_spawn_{e}(rand_u32(id, {}u), {});",
                    stream::MESH_PICK,
                    wgsl_unit3(stream::POSITION)
                ));
                w.line("s.x = on_mesh[0];");
                w.line("let surface_normal = on_mesh[1];");
            }
        }
    }

    /// The spawn position of the particle drawing `d`, the `k`-th of its emitter, spawned at
    /// time `t` in a frame at `origin`, and on a mesh the surface's normal there (zero elsewhere): the f64 twin of
    /// `emit_wgsl`.
    pub(crate) fn sample(
        &self,
        d: &ParticleDraws,
        k: u32,
        (t, origin): (f64, DVec3),
    ) -> (DVec3, DVec3) {
        let x = match self {
            ShapeIr::Custom { expr, .. } => {
                super::expression::value(expr, d.seed_mix, (d.id, k), (t, origin), DVec3::ZERO)
            }
            ShapeIr::Mesh(m) => {
                return m.spawn(d.word(stream::MESH_PICK), d.unit3(stream::POSITION));
            }
            ShapeIr::Point(p) => *p,
            ShapeIr::Sphere { center, radius } => {
                let u = d.unit3(stream::POSITION);
                let cz = 1.0 - 2.0 * u.x;
                let phi = 2.0 * PI * u.y - PI;
                let sz = (1.0 - cz * cz).max(0.0).sqrt();
                let r = radius * u.z.max(1e-30).cbrt();
                *center + r * DVec3::new(sz * phi.cos(), sz * phi.sin(), cz)
            }
            ShapeIr::SphereSurface { center, radius } => {
                let u = d.unit3(stream::POSITION);
                let cz = 1.0 - 2.0 * u.x;
                let phi = 2.0 * PI * u.y - PI;
                let sz = (1.0 - cz * cz).max(0.0).sqrt();
                *center + *radius * DVec3::new(sz * phi.cos(), sz * phi.sin(), cz)
            }
            ShapeIr::Box { min, max } => *min + (*max - *min) * d.unit3(stream::POSITION),
            ShapeIr::BoxSurface {
                min,
                max,
                thresholds,
            } => {
                let pick = u64::from(d.word(stream::FACE_PICK));
                let face = thresholds.iter().filter(|&&t| pick >= t).count();
                let mut f = d.unit3(stream::POSITION);
                f[face / 2] = (face % 2) as f64;
                *min + (*max - *min) * f
            }
            ShapeIr::Disc {
                center,
                radius,
                basis,
            } => {
                let u = d.unit3(stream::POSITION);
                let r = radius * u.x.sqrt();
                let phi = 2.0 * PI * u.y - PI;
                *center + r * (phi.cos() * basis.t1 + phi.sin() * basis.t2)
            }
            ShapeIr::Circle {
                center,
                radius,
                basis,
            } => {
                let phi = 2.0 * PI * d.unit(stream::POSITION + 1) - PI;
                *center + *radius * (phi.cos() * basis.t1 + phi.sin() * basis.t2)
            }
            ShapeIr::Cone(c) => c.sample(d),
            ShapeIr::Torus(t) => t.sample(d),
            ShapeIr::Grid {
                origin,
                step,
                counts,
            } => {
                let [nx, ny, nz] = *counts;
                let g = k % nx.wrapping_mul(ny).wrapping_mul(nz);
                let gi = DVec3::new(
                    f64::from(g % nx),
                    f64::from((g / nx) % ny),
                    f64::from(g / (nx * ny)),
                );
                *origin + gi * *step
            }
            ShapeIr::Points(ps) => ps[(k % ps.len() as u32) as usize],
        };
        (x, DVec3::ZERO)
    }
}

/// Emits the statements that set `s.x` uniform in a ball (`surface` false) or on its sphere:
/// cos(polar) uniform, and in the ball the radius as a cube root.
fn emit_sphere(w: &mut Writer, center: DVec3, radius: f64, surface: bool) {
    w.comment(match surface {
        false => "Uniform in the ball: cos(polar) uniform, radius ~ cube root.",
        true => "Uniform on the sphere: cos(polar) uniform.",
    });
    w.line(format!("let u = {};", wgsl_unit3(stream::POSITION)));
    w.line("let cz = 1.0 - 2.0 * u.x;");
    w.line(format!(
        "let phi = {} * u.y - {};",
        f32_lit(2.0 * PI),
        f32_lit(PI)
    ));
    w.line("let sz = sqrt(max(0.0, 1.0 - cz * cz));");
    let r = match surface {
        false => {
            w.line(format!(
                "let r = {} * pow(max(u.z, 1e-30), {});",
                f32_lit(radius),
                f32_lit(1.0 / 3.0)
            ));
            "r".to_string()
        }
        true => f32_lit(radius),
    };
    w.line(format!(
        "s.x = {} + {r} * vec3<f32>(sz * cos(phi), sz * sin(phi), cz);",
        vec3_lit(center)
    ));
}

/// A cone's spawn volume or side: a frustum along a unit axis from its base.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ConeIr {
    /// Centre of the base.
    pub base: DVec3,
    /// Unit axis from the base to the top.
    pub axis: DVec3,
    /// Tangents of the axis.
    pub basis: Basis,
    /// Distance from the base to the top.
    pub height: f64,
    /// The larger of the two radii.
    pub wide: f64,
    /// The smaller radius over the larger (1 when both are 0).
    pub ratio: f64,
    /// Whether the narrow end is the top (the base is wider).
    pub(crate) narrow_top: bool,
    /// On the side instead of in the volume.
    pub surface: bool,
}

impl ConeIr {
    /// Emits the statements that set `s.x`: the WGSL twin of [`Self::sample`].
    fn emit_wgsl(&self, w: &mut Writer) {
        let two_pi = f32_lit(2.0 * PI);
        let pi = f32_lit(PI);
        let a = f32_lit(self.ratio);
        w.line(format!("let u = {};", wgsl_unit3(stream::POSITION)));
        if self.surface {
            w.comment("On the side, uniform by area: the radius (over the wide one) ρ has");
            w.comment("ρ² uniform in [a², 1]; the height from the narrow end is (ρ − a)/(1 − a),");
            w.comment("written u (1 + a)/(ρ + a), which has no cancellation as a nears 1.");
            w.line(format!(
                "let rho = sqrt({a} * {a} + u.x * {});",
                f32_lit(1.0 - self.ratio * self.ratio)
            ));
            w.line(format!(
                "let t = u.x * {} / max(rho + {a}, 1e-30);",
                f32_lit(1.0 + self.ratio)
            ));
            w.line(format!("let r = {} * rho;", f32_lit(self.wide)));
        } else {
            w.comment("In the volume: the radius (over the wide one) ρ has ρ³ uniform in");
            w.comment("[a³, 1]; the height from the narrow end is (ρ − a)/(1 − a), written");
            w.comment("u (1 + a + a²)/(ρ² + aρ + a²); then uniform in that disc.");
            w.line(format!(
                "let rho = pow(max({} + u.x * {}, 1e-30), {});",
                f32_lit(self.ratio.powi(3)),
                f32_lit(1.0 - self.ratio.powi(3)),
                f32_lit(1.0 / 3.0)
            ));
            w.line(format!(
                "let t = u.x * {} / (rho * rho + {a} * rho + {});",
                f32_lit(1.0 + self.ratio + self.ratio * self.ratio),
                f32_lit(self.ratio * self.ratio)
            ));
            w.line(format!("let r = {} * rho * sqrt(u.z);", f32_lit(self.wide)));
        }
        let along = match self.narrow_top {
            true => "1.0 - t",
            false => "t",
        };
        w.line(format!("let phi = {two_pi} * u.y - {pi};"));
        w.line(format!(
            "s.x = {} + ({along}) * {} + r * (cos(phi) * {} + sin(phi) * {});",
            vec3_lit(self.base),
            vec3_lit(self.axis * self.height),
            vec3_lit(self.basis.t1),
            vec3_lit(self.basis.t2)
        ));
    }

    /// The spawn position of the particle drawing `d`.
    fn sample(&self, d: &ParticleDraws) -> DVec3 {
        let u = d.unit3(stream::POSITION);
        let a = self.ratio;
        let (t, r) = if self.surface {
            let rho = (a * a + u.x * (1.0 - a * a)).sqrt();
            (u.x * (1.0 + a) / (rho + a).max(1e-30), self.wide * rho)
        } else {
            let rho = (a.powi(3) + u.x * (1.0 - a.powi(3))).max(1e-30).cbrt();
            let t = u.x * (1.0 + a + a * a) / (rho * rho + a * rho + a * a);
            (t, self.wide * rho * u.z.sqrt())
        };
        let along = if self.narrow_top { 1.0 - t } else { t };
        let phi = 2.0 * PI * u.y - PI;
        self.base
            + along * (self.axis * self.height)
            + r * (phi.cos() * self.basis.t1 + phi.sin() * self.basis.t2)
    }
}
