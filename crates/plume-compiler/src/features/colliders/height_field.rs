//! `HeightField`: terrain given as heights on a regular grid over an x-z rectangle, bilinear
//! between samples; particles over the rectangle stay above it (outside it the field does not
//! exist). The swept test walks the cells the segment's x-z shadow crosses, in order; within a
//! cell the bilinear height along the segment is a quadratic in the segment parameter, so the
//! first crossing is found exactly (no sampling: a ridge between two steps is still hit).
//! The heights reach the GPU through the `collider_data` binding.

use glam::DVec3;
use serde::Deserialize;

use super::{check_bounce, ColliderIr, Hit, Surface};
use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::writer::{f32_lit, Writer};

/// A displacement component at most this small does not cross a cell boundary.
const TINY: f64 = 1e-30;

/// The most samples a height field may have (the storage binding stays small).
pub(crate) const MAX_SAMPLES: usize = 1 << 20;

/// A height field collider.
#[derive(Clone, Debug, PartialEq)]
pub struct HeightFieldIr {
    /// (x, z) of the first sample.
    pub min: (f64, f64),
    /// (x, z) of the last sample.
    pub max: (f64, f64),
    /// Samples along x.
    pub nx: u32,
    /// Samples along z.
    pub nz: u32,
    /// Heights, row by row (z), x fastest.
    pub heights: Vec<f64>,
}

/// `HeightField(...)` as effect files write it: terrain, heights on a regular grid over an x-z
/// rectangle, bilinear between samples; particles over the rectangle are kept above it.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeightField {
    /// The rectangle's (x, z) corner where the first row's first height sits.
    pub min: (f64, f64),
    /// The opposite (x, z) corner.
    pub max: (f64, f64),
    /// Heights (y, in metres): one row per z sample from min to max, each row one height per
    /// x sample from min to max; at least 2 x 2, every row the same length. Empty when
    /// `image` gives them.
    #[serde(default)]
    pub heights: Vec<Vec<f64>>,
    /// An 8- or 16-bit greyscale PNG whose pixels are the heights instead (top row first,
    /// relative to the effect file; see [`super::height_image`]).
    #[serde(default)]
    pub image: Option<String>,
    /// With `image`: the heights (m) of black and of white.
    #[serde(default)]
    pub height: Option<(f64, f64)>,
    /// Fraction of normal speed kept on a bounce, in [0, 1].
    pub restitution: f64,
    /// Fraction of tangential speed lost on a bounce, in [0, 1].
    pub friction: f64,
}

/// The fields of [`HeightField`].
pub(crate) const FIELDS: &[&str] = &[
    "min",
    "max",
    "heights",
    "image",
    "height",
    "restitution",
    "friction",
];

impl HeightField {
    /// Checks the rectangle, the grid (an image's already read into it) and the bounce; `path`
    /// names the variant.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        check_grid(path, c, self.min, self.max, &self.heights);
        check_bounce(path, c, self.restitution, self.friction);
    }

    /// Lowers the checked height field.
    pub(crate) fn lower(&self) -> ColliderIr {
        ColliderIr {
            surface: Surface::HeightField(HeightFieldIr::new(self.min, self.max, &self.heights)),
            restitution: self.restitution,
            friction: self.friction,
        }
    }
}

/// Checks the rectangle and the grid: finite, min < max, at least 2 x 2 samples, rows of one
/// length.
fn check_grid(
    path: &ValuePath,
    c: &mut Checker,
    min: (f64, f64),
    max: (f64, f64),
    heights: &[Vec<f64>],
) {
    let mut ok = true;
    for (field, v) in [("min", min), ("max", max)] {
        ok &= c.finite(&path.field(field).component(0, "x"), v.0);
        ok &= c.finite(&path.field(field).component(1, "z"), v.1);
    }
    if ok && (min.0 >= max.0 || min.1 >= max.1) {
        c.error(
            &path.field("min"),
            format!(
                "min must be < max in x and z, got min ({}, {}) and max ({}, {})",
                min.0, min.1, max.0, max.1
            ),
        );
    }
    let rows = path.field("heights");
    if heights.len() < 2 {
        c.error(
            &rows,
            format!(
                "needs at least 2 rows (z samples) of at least 2 heights, got {} row(s) (or give an `image` and its `height`)",
                heights.len()
            ),
        );
        return;
    }
    let width = heights[0].len();
    if width < 2 {
        c.error(
            &rows.index(0),
            format!("a row needs at least 2 heights (x samples), got {width}"),
        );
        return;
    }
    if width * heights.len() > MAX_SAMPLES {
        c.error(
            &rows,
            format!(
                "{} x {} samples is more than the {MAX_SAMPLES} a height field may have",
                width,
                heights.len()
            ),
        );
        return;
    }
    for (r, row) in heights.iter().enumerate() {
        if row.len() != width {
            c.error(
                &rows.index(r),
                format!(
                    "every row must have as many heights as the first ({width}), this one has {}",
                    row.len()
                ),
            );
            continue;
        }
        for (k, &h) in row.iter().enumerate() {
            c.finite(&rows.index(r).index(k), h);
        }
    }
}

impl HeightFieldIr {
    /// The IR of a checked grid.
    pub fn new(min: (f64, f64), max: (f64, f64), heights: &[Vec<f64>]) -> Self {
        Self {
            min,
            max,
            nx: heights[0].len() as u32,
            nz: heights.len() as u32,
            heights: heights.iter().flatten().copied().collect(),
        }
    }

    fn cell_size(&self) -> (f64, f64) {
        (
            (self.max.0 - self.min.0) / f64::from(self.nx - 1),
            (self.max.1 - self.min.1) / f64::from(self.nz - 1),
        )
    }

    fn at(&self, i: i64, k: i64) -> f64 {
        self.heights[(k * i64::from(self.nx) + i) as usize]
    }

    /// The four corner heights of cell (i, k) as (h00, h10 - h00, h01 - h00, the twist).
    fn coefficients(&self, i: i64, k: i64) -> (f64, f64, f64, f64) {
        let (h00, h10) = (self.at(i, k), self.at(i + 1, k));
        let (h01, h11) = (self.at(i, k + 1), self.at(i + 1, k + 1));
        (h00, h10 - h00, h01 - h00, h00 - h10 - h01 + h11)
    }

    fn cell_of(&self, x: f64, z: f64) -> (i64, i64) {
        let (cw, cd) = self.cell_size();
        let i = ((x - self.min.0) / cw)
            .floor()
            .clamp(0.0, f64::from(self.nx - 2));
        let k = ((z - self.min.1) / cd)
            .floor()
            .clamp(0.0, f64::from(self.nz - 2));
        (i as i64, k as i64)
    }

    fn over(&self, x: DVec3) -> bool {
        x.x >= self.min.0 && x.x <= self.max.0 && x.z >= self.min.1 && x.z <= self.max.1
    }

    /// The bilinear height under (x, z) (the rectangle's edge cells extended).
    pub fn height(&self, x: f64, z: f64) -> f64 {
        let (cw, cd) = self.cell_size();
        let (i, k) = self.cell_of(x, z);
        let u = (x - (self.min.0 + i as f64 * cw)) / cw;
        let w = (z - (self.min.1 + k as f64 * cd)) / cd;
        let (a, b, c, e) = self.coefficients(i, k);
        a + b * u + c * w + e * u * w
    }

    /// The first crossing within cell (i, k) for segment parameters [sa, sb].
    fn cell_hit(&self, i: i64, k: i64, a: DVec3, d: DVec3, sa: f64, sb: f64) -> Option<Hit> {
        let (cw, cd) = self.cell_size();
        let p = a + d * sa;
        let u0 = (p.x - (self.min.0 + i as f64 * cw)) / cw;
        let w0 = (p.z - (self.min.1 + k as f64 * cd)) / cd;
        let (du, dw) = (d.x / cw, d.z / cd);
        let (h00, b, c, e) = self.coefficients(i, k);
        // f(σ) = y - H along the segment from p: C + B σ + A σ².
        let cc = p.y - (h00 + b * u0 + c * w0 + e * u0 * w0);
        let bb = d.y - (b * du + c * dw + e * (u0 * dw + w0 * du));
        let aa = -e * du * dw;
        let len = (sb - sa).max(0.0);
        let sigma = if cc < 0.0 {
            0.0
        } else {
            let disc = bb * bb - 4.0 * aa * cc;
            if disc.is_nan() || disc < 0.0 {
                return None;
            }
            let q = -0.5 * (bb + if bb >= 0.0 { 1.0 } else { -1.0 } * disc.sqrt());
            let r1 = if aa != 0.0 { q / aa } else { f64::INFINITY };
            let r2 = if q != 0.0 { cc / q } else { f64::INFINITY };
            let pick = |r: f64| {
                if r >= 0.0 && r <= len {
                    r
                } else {
                    f64::INFINITY
                }
            };
            let r = pick(r1).min(pick(r2));
            if r == f64::INFINITY {
                return None;
            }
            r
        };
        let u = (u0 + sigma * du).clamp(0.0, 1.0);
        let w = (w0 + sigma * dw).clamp(0.0, 1.0);
        let n = DVec3::new(-(b + e * w) / cw, 1.0, -(c + e * u) / cd);
        Some(Hit {
            s: sa + sigma,
            normal: n / n.length(),
        })
    }

    /// The first contact of segment `a` -> `b`: clip to the rectangle, then walk the cells.
    pub fn hit(&self, a: DVec3, b: DVec3) -> Option<Hit> {
        let d = b - a;
        let (mut s0, mut s1) = (0.0_f64, 1.0_f64);
        for (p, dp, lo, hi) in [
            (a.x, d.x, self.min.0, self.max.0),
            (a.z, d.z, self.min.1, self.max.1),
        ] {
            if dp.abs() <= TINY {
                if p < lo || p > hi {
                    return None;
                }
            } else {
                let (t1, t2) = ((lo - p) / dp, (hi - p) / dp);
                s0 = s0.max(t1.min(t2));
                s1 = s1.min(t1.max(t2));
            }
        }
        if s0 > s1 {
            return None;
        }
        let (cw, cd) = self.cell_size();
        let start = a + d * s0;
        let (mut i, mut k) = self.cell_of(start.x, start.z);
        let step = |x: f64| {
            if x > TINY {
                1
            } else if x < -TINY {
                -1
            } else {
                0
            }
        };
        let (si, sk) = (step(d.x), step(d.z));
        let mut s = s0;
        for _ in 0..self.nx + self.nz {
            let next = |c: i64, sc: i64, lo: f64, size: f64, p: f64, dp: f64| match sc {
                1 => (lo + (c + 1) as f64 * size - p) / dp,
                -1 => (lo + c as f64 * size - p) / dp,
                _ => f64::INFINITY,
            };
            let nx = next(i, si, self.min.0, cw, a.x, d.x);
            let nz = next(k, sk, self.min.1, cd, a.z, d.z);
            let end = s1.min(nx).min(nz).max(s);
            if let Some(hit) = self.cell_hit(i, k, a, d, s, end) {
                return Some(hit);
            }
            if end >= s1 {
                break;
            }
            if nx <= nz {
                i += si;
            } else {
                k += sk;
            }
            if i < 0 || i > i64::from(self.nx) - 2 || k < 0 || k > i64::from(self.nz) - 2 {
                break;
            }
            s = end;
        }
        None
    }

    /// A point under the field lifted onto it, `margin` above.
    pub(crate) fn push_out(&self, x: DVec3, margin: f64) -> DVec3 {
        if !self.over(x) {
            return x;
        }
        let h = self.height(x.x, x.z);
        if x.y < h {
            DVec3::new(x.x, h + margin, x.z)
        } else {
            x
        }
    }

    /// Whether `x` is on the allowed side.
    pub fn allows(&self, x: DVec3) -> bool {
        !self.over(x) || x.y >= self.height(x.x, x.z)
    }

    /// The largest coordinate magnitude (for the margin).
    pub fn scale(&self) -> f64 {
        let h = self.heights.iter().fold(0.0_f64, |m, h| m.max(h.abs()));
        h.max(self.min.0.abs())
            .max(self.min.1.abs())
            .max(self.max.0.abs())
            .max(self.max.1.abs())
    }

    /// One line for `--emit ir`.
    pub fn describe(&self) -> String {
        let (lo, hi) = self
            .heights
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &h| {
                (lo.min(h), hi.max(h))
            });
        format!(
            "HeightField x [{}, {}] z [{}, {}] {} x {} samples, heights [{lo}, {hi}]",
            self.min.0, self.max.0, self.min.1, self.max.1, self.nx, self.nz
        )
    }

    /// The WGSL twins of [`HeightFieldIr::hit`] and `push_out`, reading the
    /// heights from `collider_data` at `offset`.
    pub fn emit(&self, w: &mut Writer, i: usize, offset: u32) {
        let (cw, cd) = self.cell_size();
        let (x0, z0) = (f32_lit(self.min.0), f32_lit(self.min.1));
        let (x1, z1) = (f32_lit(self.max.0), f32_lit(self.max.1));
        let (cw_l, cd_l) = (f32_lit(cw), f32_lit(cd));
        let (nx, nz) = (self.nx, self.nz);
        let tiny = f32_lit(TINY);
        w.block(format!("fn hf{i}_at(ci: i32, ck: i32) -> f32"), |w| {
            w.line(format!(
                "return collider_data[{offset}u + u32(ck) * {nx}u + u32(ci)];"
            ))
        });
        w.comment("(h00, h10 - h00, h01 - h00, twist) of cell (ci, ck).");
        w.block(
            format!("fn hf{i}_coefficients(ci: i32, ck: i32) -> vec4<f32>"),
            |w| {
                w.line(format!("let h00 = hf{i}_at(ci, ck);"));
                w.line(format!("let h10 = hf{i}_at(ci + 1, ck);"));
                w.line(format!("let h01 = hf{i}_at(ci, ck + 1);"));
                w.line(format!("let h11 = hf{i}_at(ci + 1, ck + 1);"));
                w.line("return vec4<f32>(h00, h10 - h00, h01 - h00, h00 - h10 - h01 + h11);");
            },
        );
        w.block(
            format!("fn hf{i}_cell_of(x: f32, z: f32) -> vec2<i32>"),
            |w| {
                w.line(format!(
                    "let ci = clamp(floor((x - {x0}) / {cw_l}), 0.0, {});",
                    f32_lit(f64::from(nx - 2))
                ));
                w.line(format!(
                    "let ck = clamp(floor((z - {z0}) / {cd_l}), 0.0, {});",
                    f32_lit(f64::from(nz - 2))
                ));
                w.line("return vec2<i32>(i32(ci), i32(ck));");
            },
        );
        w.block(
            format!(
                "fn hf{i}_cell_hit(ci: i32, ck: i32, a: vec3<f32>, d: vec3<f32>, sa: f32, sb: f32) -> vec4<f32>"
            ),
            |w| {
                w.line("let none = vec4<f32>(2.0, 0.0, 1.0, 0.0);");
                w.line("let p = a + d * sa;");
                w.line(format!("let u0 = (p.x - ({x0} + f32(ci) * {cw_l})) / {cw_l};"));
                w.line(format!("let w0 = (p.z - ({z0} + f32(ck) * {cd_l})) / {cd_l};"));
                w.line(format!("let du = d.x / {cw_l};"));
                w.line(format!("let dw = d.z / {cd_l};"));
                w.line(format!("let k = hf{i}_coefficients(ci, ck);"));
                w.line("let cc = p.y - (k.x + k.y * u0 + k.z * w0 + k.w * u0 * w0);");
                w.line("let bb = d.y - (k.y * du + k.z * dw + k.w * (u0 * dw + w0 * du));");
                w.line("let aa = -k.w * du * dw;");
                w.line("let len = max(sb - sa, 0.0);");
                w.line("var sigma = 0.0;");
                w.block("if (cc >= 0.0)", |w| {
                    w.line("let disc = bb * bb - 4.0 * aa * cc;");
                    w.block("if (!(disc >= 0.0))", |w| w.line("return none;"));
                    w.line("let q = -0.5 * (bb + select(-1.0, 1.0, bb >= 0.0) * sqrt(disc));");
                    w.line("let r1 = select(3.0e38, q / aa, aa != 0.0);");
                    w.line("let r2 = select(3.0e38, cc / q, q != 0.0);");
                    w.line("let p1 = select(3.0e38, r1, r1 >= 0.0 && r1 <= len);");
                    w.line("let p2 = select(3.0e38, r2, r2 >= 0.0 && r2 <= len);");
                    w.line("sigma = min(p1, p2);");
                    w.block("if (sigma >= 3.0e38)", |w| w.line("return none;"));
                });
                w.line("let u = clamp(u0 + sigma * du, 0.0, 1.0);");
                w.line("let wz = clamp(w0 + sigma * dw, 0.0, 1.0);");
                w.line(format!(
                    "let n = vec3<f32>(-(k.y + k.w * wz) / {cw_l}, 1.0, -(k.z + k.w * u) / {cd_l});"
                ));
                w.line("return vec4<f32>(sa + sigma, normalize(n));");
            },
        );
        w.block(
            format!("fn collider_hit_{i}(a: vec3<f32>, b: vec3<f32>) -> vec4<f32>"),
            |w| {
                w.line("let none = vec4<f32>(2.0, 0.0, 1.0, 0.0);");
                w.line("let d = b - a;");
                w.line("var s0 = 0.0;");
                w.line("var s1 = 1.0;");
                for (c, lo, hi) in [("x", &x0, &x1), ("z", &z0, &z1)] {
                    w.block(format!("if (abs(d.{c}) <= {tiny})"), |w| {
                        w.block(format!("if (a.{c} < {lo} || a.{c} > {hi})"), |w| {
                            w.line("return none;")
                        });
                    });
                    w.block("else", |w| {
                        w.line(format!("let t1 = ({lo} - a.{c}) / d.{c};"));
                        w.line(format!("let t2 = ({hi} - a.{c}) / d.{c};"));
                        w.line("s0 = max(s0, min(t1, t2));");
                        w.line("s1 = min(s1, max(t1, t2));");
                    });
                }
                w.block("if (s0 > s1)", |w| w.line("return none;"));
                w.line("let start = a + d * s0;");
                w.line(format!("var c = hf{i}_cell_of(start.x, start.z);"));
                w.line(format!(
                    "let si = select(select(0, -1, d.x < -{tiny}), 1, d.x > {tiny});"
                ));
                w.line(format!(
                    "let sk = select(select(0, -1, d.z < -{tiny}), 1, d.z > {tiny});"
                ));
                w.line("var s = s0;");
                w.block(format!("for (var it = 0u; it < {}u; it++)", nx + nz), |w| {
                    w.line(format!(
                        "let bx = {x0} + f32(select(c.x, c.x + 1, si > 0)) * {cw_l};"
                    ));
                    w.line(format!(
                        "let bz = {z0} + f32(select(c.y, c.y + 1, sk > 0)) * {cd_l};"
                    ));
                    w.line("let nx = select(3.0e38, (bx - a.x) / d.x, si != 0);");
                    w.line("let nz = select(3.0e38, (bz - a.z) / d.z, sk != 0);");
                    w.line("let end = max(min(s1, min(nx, nz)), s);");
                    w.line(format!("let hit = hf{i}_cell_hit(c.x, c.y, a, d, s, end);"));
                    w.block("if (hit.x <= 1.0)", |w| w.line("return hit;"));
                    w.block("if (end >= s1)", |w| w.line("break;"));
                    w.block("if (nx <= nz)", |w| w.line("c.x += si;"));
                    w.block("else", |w| w.line("c.y += sk;"));
                    w.block(
                        format!(
                            "if (c.x < 0 || c.x > {} || c.y < 0 || c.y > {})",
                            nx as i32 - 2,
                            nz as i32 - 2
                        ),
                        |w| w.line("break;"),
                    );
                    w.line("s = end;");
                });
                w.line("return none;");
            },
        );
        w.block(
            format!("fn collider_push_{i}(x: vec3<f32>, margin: f32) -> vec3<f32>"),
            |w| {
                w.block(
                    format!("if (x.x < {x0} || x.x > {x1} || x.z < {z0} || x.z > {z1})"),
                    |w| w.line("return x;"),
                );
                w.line(format!("let c = hf{i}_cell_of(x.x, x.z);"));
                w.line(format!(
                    "let u = (x.x - ({x0} + f32(c.x) * {cw_l})) / {cw_l};"
                ));
                w.line(format!(
                    "let wz = (x.z - ({z0} + f32(c.y) * {cd_l})) / {cd_l};"
                ));
                w.line(format!("let k = hf{i}_coefficients(c.x, c.y);"));
                w.line("let h = k.x + k.y * u + k.z * wz + k.w * u * wz;");
                w.line("return select(x, vec3<f32>(x.x, h + margin, x.z), x.y < h);");
            },
        );
    }
}
