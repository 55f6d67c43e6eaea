//! `SceneDepth`: particles collide with the depth image of the view they are drawn in, the
//! surfaces the camera sees. The host gives the image and its camera at run time (the
//! runtime's `Effect::set_scene_depth`; `plume render` and `plume preview` draw the effect's
//! scene meshes into one), so the compiled kernel reads them from two bindings:
//! `scene_depth`, the depth texture, and `scene_camera`, [`DepthCamera::words`]. Until an
//! image is given, nothing collides.
//!
//! **What a pixel is.** A pixel holding depth d in (0, 1) is the point its centre unprojects
//! to at d through the inverse projection: a surface at that point's view depth (−z in view
//! space). Depth exactly 0 or 1 (a clear value, standard or reversed-Z) is empty. A point is
//! *behind* the surface at the pixel it projects to when its view depth exceeds the surface's,
//! and *inside* it when it is behind by no more than `thickness`: past that it passes freely
//! (behind an object, not in it). Off screen, behind the camera or over an empty pixel, it
//! passes freely too: depth collision only knows what the camera sees.
//!
//! **Swept.** The substep's segment is sampled at one point per pixel it crosses on screen
//! (at most [`MAX_SAMPLES`]); a crossing is a sample in front of its pixel's surface followed by
//! one behind its own by at most `thickness` plus how much deeper the particle went between
//! the two, so a particle moving fast along the view ray does not pass through. The crossing is
//! bisected ([`BISECTIONS`] halvings) to the last point in front. The normal comes from the
//! neighbouring pixels' surface points (of the left and right neighbours, the one nearer in
//! depth, likewise up and down), turned to face the side the particle came from.
//!
//! **Inside.** A particle found inside the surface (a resting particle slid onto a nearer
//! pixel) is moved along its view ray to just in front of the surface.
//!
//! The f64 reference ([`SceneDepthIr::hit`]) runs the same steps on the same f32 image and
//! camera, given to `ReferenceSim::set_scene_depth`; f32 and f64 may round a point onto
//! neighbouring pixels where it projects onto a pixel's edge.

use std::sync::Arc;

use glam::{DMat3, DMat4, DVec3, DVec4, Mat4};

use super::Hit;
use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::writer::{f32_lit, Writer};

/// The thickness when the file gives none (m).
pub const DEFAULT_THICKNESS: f64 = 0.5;

/// The most points a substep's segment is sampled at.
pub const MAX_SAMPLES: u32 = 32;

/// Bisection halvings of a crossing.
const BISECTIONS: u32 = 16;

/// A homogeneous w this small (in magnitude) is a point at infinity.
const TINY_W: f64 = 1e-30;

/// The camera a depth image was drawn with (column-major f32, as the GPU reads it), with the
/// inverses both the kernel and the reference use.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthCamera {
    /// World to view (right-handed, looking down −z).
    pub view: [f32; 16],
    /// View to clip (wgpu's clip space, depth in [0, 1], standard or reversed).
    pub projection: [f32; 16],
    /// Clip to view.
    pub inverse_projection: [f32; 16],
    /// View to world.
    pub inverse_view: [f32; 16],
}

/// f32 words of [`DepthCamera::words`]: (width, height, 0, 0), then the four matrices.
pub const CAMERA_WORDS: usize = 4 + 4 * 16;

impl DepthCamera {
    /// The camera of `view` and `projection`; refused when either is not finite or not
    /// invertible.
    pub fn new(view: Mat4, projection: Mat4) -> Result<Self, String> {
        let finite = |m: &Mat4| m.to_cols_array().iter().all(|x| x.is_finite());
        if !finite(&view) || !finite(&projection) {
            return Err("the scene depth's camera has a matrix that is not finite".into());
        }
        let (v, p) = (view.as_dmat4(), projection.as_dmat4());
        let invertible = |m: &DMat4| {
            let d = m.determinant();
            d.is_finite() && d.abs() > 1e-30
        };
        if !invertible(&v) || !invertible(&p) {
            return Err("the scene depth's camera has a matrix that is not invertible".into());
        }
        let f32s = |m: DMat4| m.as_mat4().to_cols_array();
        Ok(Self {
            view: view.to_cols_array(),
            projection: projection.to_cols_array(),
            inverse_projection: f32s(p.inverse()),
            inverse_view: f32s(v.inverse()),
        })
    }

    /// The `scene_camera` binding's contents for an image of `width` x `height`.
    pub fn words(&self, width: u32, height: u32) -> [f32; CAMERA_WORDS] {
        let mut out = [0.0; CAMERA_WORDS];
        out[0] = width as f32;
        out[1] = height as f32;
        for (k, m) in [
            &self.view,
            &self.projection,
            &self.inverse_projection,
            &self.inverse_view,
        ]
        .into_iter()
        .enumerate()
        {
            out[4 + 16 * k..4 + 16 * (k + 1)].copy_from_slice(m);
        }
        out
    }
}

/// A depth image and its camera, as the reference reads it (the GPU reads the host's texture).
#[derive(Clone, Debug, PartialEq)]
pub struct DepthImage {
    /// Pixels across.
    pub width: u32,
    /// Pixels down.
    pub height: u32,
    /// Depth per pixel, row by row from the top.
    pub depth: Vec<f32>,
    /// The camera it was drawn with.
    pub camera: DepthCamera,
}

/// A scene depth collider in the IR; `image` is set only in a reference simulation that was
/// given one.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneDepthIr {
    /// How far behind a surface a particle still collides (m).
    pub thickness: f64,
    /// The image the reference collides with.
    pub image: Option<Arc<DepthImage>>,
}

/// Checks the thickness.
pub fn check(path: &ValuePath, c: &mut Checker, thickness: f64) {
    c.positive(&path.field("thickness"), thickness);
}

/// Where a world point is against the image.
#[derive(Clone, Copy, Debug)]
struct Place {
    /// The point in view space.
    view: DVec3,
    /// Its normalised device coordinates (x, y).
    ndc: (f64, f64),
    /// The pixel it projects to.
    pixel: (i64, i64),
    /// The surface point on the point's view ray, in view space.
    surface: DVec3,
    /// How far the surface may be off for the depth image's precision (see [`precision`]).
    tolerance: f64,
}

impl Place {
    /// How far behind the surface the point is (m; negative in front), the surface taken
    /// `tolerance` nearer so that a particle left just in front of it is not found behind it
    /// by the depth image's rounding.
    fn behind(&self) -> f64 {
        self.surface.z - self.view.z + self.tolerance
    }
}

/// Relative change of a depth value standing for its rounding: 8 f32 ulps.
const DEPTH_ULPS: f64 = 8.0 / 8_388_608.0;

/// Relative rounding of a view-space coordinate computed in f32 through two matrices.
const VIEW_ROUNDING: f64 = 1e-6;

/// The image's matrices in f64.
struct Frame<'a> {
    image: &'a DepthImage,
    view: DMat4,
    projection: DMat4,
    inverse_projection: DMat4,
    inverse_view: DMat4,
}

fn dmat(m: &[f32; 16]) -> DMat4 {
    DMat4::from_cols_array(&m.map(f64::from))
}

impl<'a> Frame<'a> {
    fn new(image: &'a DepthImage) -> Self {
        Self {
            image,
            view: dmat(&image.camera.view),
            projection: dmat(&image.camera.projection),
            inverse_projection: dmat(&image.camera.inverse_projection),
            inverse_view: dmat(&image.camera.inverse_view),
        }
    }

    /// The view-space point at normalised device coordinates (x, y, d), if finite.
    fn unproject(&self, x: f64, y: f64, d: f64) -> Option<DVec3> {
        let p = self.inverse_projection * DVec4::new(x, y, d, 1.0);
        (p.w.abs() > TINY_W).then(|| p.truncate() / p.w)
    }

    /// The surface point of pixel (ix, iy) in view space; None off the image or empty.
    fn surface(&self, ix: i64, iy: i64) -> Option<DVec3> {
        let (w, h) = (i64::from(self.image.width), i64::from(self.image.height));
        if ix < 0 || iy < 0 || ix >= w || iy >= h {
            return None;
        }
        let d = f64::from(self.image.depth[(iy * w + ix) as usize]);
        if !(d > 0.0 && d < 1.0) {
            return None;
        }
        let x = (ix as f64 + 0.5) / w as f64 * 2.0 - 1.0;
        let y = 1.0 - (iy as f64 + 0.5) / h as f64 * 2.0;
        self.unproject(x, y, d)
    }

    /// The view-space point, its pixel position (continuous) and its clip w.
    fn project(&self, x: DVec3) -> (DVec3, Option<(f64, f64)>) {
        let v = (self.view * x.extend(1.0)).truncate();
        let c = self.projection * v.extend(1.0);
        if !(c.w > TINY_W) {
            return (v, None);
        }
        (v, Some((c.x / c.w, c.y / c.w)))
    }

    /// The depth of pixel (ix, iy), clamped to the image; None where it is empty.
    fn depth(&self, ix: i64, iy: i64) -> Option<f64> {
        let (w, h) = (i64::from(self.image.width), i64::from(self.image.height));
        let d = f64::from(self.image.depth[(iy.clamp(0, h - 1) * w + ix.clamp(0, w - 1)) as usize]);
        (d > 0.0 && d < 1.0).then_some(d)
    }

    /// Where `x` is against the image, or None where it passes freely regardless of depth.
    fn place(&self, x: DVec3) -> Option<Place> {
        let (view, ndc) = self.project(x);
        let (nx, ny) = ndc?;
        if !(nx.abs() < 1.0 && ny.abs() < 1.0) {
            return None;
        }
        let (w, h) = (self.image.width as f64, self.image.height as f64);
        // Continuous pixel coordinates: pixel centres at integers.
        let fx = (nx * 0.5 + 0.5) * w - 0.5;
        let fy = (0.5 - ny * 0.5) * h - 0.5;
        let ix = (fx + 0.5).floor().clamp(0.0, w - 1.0) as i64;
        let iy = (fy + 0.5).floor().clamp(0.0, h - 1.0) as i64;
        let (x0, y0) = (fx.floor(), fy.floor());
        let (tx, ty) = (fx - x0, fy - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let corners = [
            self.depth(x0, y0),
            self.depth(x0 + 1, y0),
            self.depth(x0, y0 + 1),
            self.depth(x0 + 1, y0 + 1),
        ];
        let d = match corners {
            [Some(a), Some(b), Some(c), Some(e)] => {
                let top = a + (b - a) * tx;
                let bottom = c + (e - c) * tx;
                top + (bottom - top) * ty
            }
            _ => self.depth(ix, iy)?,
        };
        let surface = self.unproject(nx, ny, d)?;
        // How much 8 ulps of depth move the surface: far away a standard depth buffer's
        // steps grow with the square of the distance.
        let tolerance = self
            .unproject(nx, ny, d * (1.0 + DEPTH_ULPS))
            .map_or(0.0, |u| (u.z - surface.z).abs())
            + VIEW_ROUNDING * view.z.abs();
        Some(Place {
            view,
            ndc: (nx, ny),
            pixel: (ix, iy),
            surface,
            tolerance,
        })
    }

    /// The world normal of the surface at `p`'s pixel, facing `toward` (view space).
    fn normal(&self, p: &Place, toward: DVec3) -> DVec3 {
        let (ix, iy) = p.pixel;
        let s = self.surface(ix, iy).unwrap_or(p.surface);
        let tangent = |plus: Option<DVec3>, minus: Option<DVec3>| match (plus, minus) {
            (Some(a), Some(b)) => Some(if (a.z - s.z).abs() <= (s.z - b.z).abs() {
                a - s
            } else {
                s - b
            }),
            (Some(a), None) => Some(a - s),
            (None, Some(b)) => Some(s - b),
            (None, None) => None,
        };
        let tx = tangent(self.surface(ix + 1, iy), self.surface(ix - 1, iy));
        let ty = tangent(self.surface(ix, iy + 1), self.surface(ix, iy - 1));
        let to_eye = toward - s;
        let n = match (tx, ty) {
            (Some(a), Some(b)) => a.cross(b),
            _ => to_eye,
        };
        let n = if n.dot(to_eye) < 0.0 { -n } else { n };
        let world = DMat3::from_mat4(self.inverse_view) * n;
        let l = world.length();
        if l > 1e-30 && l.is_finite() {
            world / l
        } else {
            let back = DMat3::from_mat4(self.inverse_view) * DVec3::Z;
            back / back.length().max(1e-30)
        }
    }
}

impl SceneDepthIr {
    /// The first contact of segment `a` -> `b` (see the module doc).
    pub fn hit(&self, a: DVec3, b: DVec3) -> Option<Hit> {
        let frame = Frame::new(self.image.as_deref()?);
        let (w, h) = (frame.image.width as f64, frame.image.height as f64);
        let samples = match (frame.project(a).1, frame.project(b).1) {
            (Some(pa), Some(pb)) => {
                let px = ((pb.0 - pa.0) * 0.5 * w)
                    .abs()
                    .max(((pb.1 - pa.1) * 0.5 * h).abs());
                px.ceil().clamp(1.0, f64::from(MAX_SAMPLES)) as u32
            }
            _ => MAX_SAMPLES,
        };
        let mut prev = frame.place(a);
        let mut prev_t = 0.0;
        for k in 1..=samples {
            let t = f64::from(k) / f64::from(samples);
            let cur = frame.place(a + (b - a) * t);
            if let (Some(p), Some(c)) = (prev, cur) {
                let deeper = (p.view.z - c.view.z).max(0.0);
                if p.behind() < 0.0 && c.behind() >= 0.0 && c.behind() <= self.thickness + deeper {
                    let (mut lo, mut hi) = (prev_t, t);
                    let mut front = p;
                    for _ in 0..BISECTIONS {
                        let mid = 0.5 * (lo + hi);
                        match frame.place(a + (b - a) * mid) {
                            Some(m) if m.behind() >= 0.0 => hi = mid,
                            Some(m) => {
                                lo = mid;
                                front = m;
                            }
                            None => lo = mid,
                        }
                    }
                    let toward = frame.project(a).0;
                    return Some(Hit {
                        s: lo,
                        normal: frame.normal(&front, toward),
                    });
                }
            }
            prev = cur;
            prev_t = t;
        }
        None
    }

    /// `x` moved along its view ray to `margin` in front of the surface when it is inside it.
    pub fn push_out(&self, x: DVec3, margin: f64) -> DVec3 {
        let Some(image) = self.image.as_deref() else {
            return x;
        };
        let frame = Frame::new(image);
        let Some(p) = frame.place(x) else {
            return x;
        };
        let behind = p.behind();
        if !(behind >= 0.0 && behind <= self.thickness) {
            return x;
        }
        let (nx, ny) = p.ndc;
        let (Some(u0), Some(u1)) = (frame.unproject(nx, ny, 0.25), frame.unproject(nx, ny, 0.75))
        else {
            return x;
        };
        let ray = u1 - u0;
        if !(ray.z.abs() > TINY_W) {
            return x;
        }
        // Depth is −z: moving by λ·ray changes it by −λ·ray.z.
        let lambda = (behind + margin) / ray.z;
        let moved = p.view + ray * lambda;
        let world = frame.inverse_view * moved.extend(1.0);
        world.truncate()
    }

    /// Whether `x` is not inside a surface (the tests' check; no margin).
    pub fn allows(&self, x: DVec3) -> bool {
        let Some(image) = self.image.as_deref() else {
            return true;
        };
        Frame::new(image)
            .place(x)
            .is_none_or(|p| !(p.behind() >= 0.0 && p.behind() <= self.thickness))
    }

    /// One line for `--emit ir`.
    pub fn describe(&self) -> String {
        format!(
            "SceneDepth thickness {} (the host's depth image, at run time)",
            self.thickness
        )
    }

    /// The WGSL twins of [`SceneDepthIr::hit`] and [`SceneDepthIr::push_out`], reading the
    /// `scene_depth` texture and the `scene_camera` words.
    pub fn emit(&self, w: &mut Writer, i: usize) {
        let thickness = f32_lit(self.thickness);
        let mat = |first: usize| {
            format!(
                "mat4x4<f32>(scene_camera[{}], scene_camera[{}], scene_camera[{}], scene_camera[{}])",
                first,
                first + 1,
                first + 2,
                first + 3
            )
        };
        let (view, proj, inv_proj, inv_view) = (mat(1), mat(5), mat(9), mat(13));
        w.comment("The view-space surface point of pixel p, w = 1 when there is one.");
        w.block(format!("fn sd{i}_surface(p: vec2<i32>) -> vec4<f32>"), |w| {
            w.line("let size = vec2<i32>(scene_camera[0].xy);");
            w.block("if (any(p < vec2<i32>(0)) || any(p >= size))", |w| {
                w.line("return vec4<f32>(0.0);")
            });
            w.line("let d = textureLoad(scene_depth, p, 0).r;");
            w.block("if (!(d > 0.0 && d < 1.0))", |w| {
                w.line("return vec4<f32>(0.0);")
            });
            w.line("let sz = scene_camera[0].xy;");
            w.line("let ndc = vec2<f32>((f32(p.x) + 0.5) / sz.x * 2.0 - 1.0, 1.0 - (f32(p.y) + 0.5) / sz.y * 2.0);");
            w.line(format!("let u = {inv_proj} * vec4<f32>(ndc, d, 1.0);"));
            w.block(format!("if (!(abs(u.w) > {}))", f32_lit(TINY_W)), |w| {
                w.line("return vec4<f32>(0.0);")
            });
            w.line("return vec4<f32>(u.xyz / u.w, 1.0);");
        });
        w.comment("The view-space point of x and its NDC (x, y); w = 0 when behind the camera.");
        w.block(format!("fn sd{i}_project(x: vec3<f32>) -> array<vec4<f32>, 2>"), |w| {
            w.line(format!("let v = ({view} * vec4<f32>(x, 1.0)).xyz;"));
            w.line(format!("let c = {proj} * vec4<f32>(v, 1.0);"));
            w.block(format!("if (!(c.w > {}))", f32_lit(TINY_W)), |w| {
                w.line("return array<vec4<f32>, 2>(vec4<f32>(v, 0.0), vec4<f32>(0.0));")
            });
            w.line("return array<vec4<f32>, 2>(vec4<f32>(v, 1.0), vec4<f32>(c.xy / c.w, 0.0, 0.0));");
        });
        w.comment("The depth of pixel p clamped to the image; -1 where it is empty.");
        w.block(format!("fn sd{i}_depth(p: vec2<i32>) -> f32"), |w| {
            w.line("let size = vec2<i32>(scene_camera[0].xy);");
            w.line("let d = textureLoad(scene_depth, clamp(p, vec2<i32>(0), size - vec2<i32>(1)), 0).r;");
            w.line("return select(-1.0, d, d > 0.0 && d < 1.0);");
        });
        w.comment("Where x is: (view point, 1 when it meets a surface), (surface point on its ray, nearest pixel x), (ndc, nearest pixel y).");
        w.block(format!("fn sd{i}_place(x: vec3<f32>) -> array<vec4<f32>, 3>"), |w| {
            w.line(format!("let pr = sd{i}_project(x);"));
            w.line("let none = array<vec4<f32>, 3>(vec4<f32>(pr[0].xyz, 0.0), vec4<f32>(0.0), vec4<f32>(0.0));");
            w.block("if (pr[0].w == 0.0)", |w| w.line("return none;"));
            w.line("let n = pr[1].xy;");
            w.block("if (!(abs(n.x) < 1.0 && abs(n.y) < 1.0))", |w| {
                w.line("return none;")
            });
            w.line("let sz = scene_camera[0].xy;");
            w.line("let f = vec2<f32>((n.x * 0.5 + 0.5) * sz.x - 0.5, (0.5 - n.y * 0.5) * sz.y - 0.5);");
            w.line("let near = vec2<i32>(clamp(floor(f + vec2<f32>(0.5)), vec2<f32>(0.0), sz - vec2<f32>(1.0)));");
            w.line("let c0 = floor(f);");
            w.line("let t = f - c0;");
            w.line("let p0 = vec2<i32>(c0);");
            w.line(format!("let a = sd{i}_depth(p0);"));
            w.line(format!("let b = sd{i}_depth(p0 + vec2<i32>(1, 0));"));
            w.line(format!("let c = sd{i}_depth(p0 + vec2<i32>(0, 1));"));
            w.line(format!("let e = sd{i}_depth(p0 + vec2<i32>(1, 1));"));
            w.line("var d = 0.0;");
            w.block("if (min(min(a, b), min(c, e)) >= 0.0)", |w| {
                w.line("let top = a + (b - a) * t.x;");
                w.line("let bottom = c + (e - c) * t.x;");
                w.line("d = top + (bottom - top) * t.y;");
            });
            w.block("else", |w| {
                w.line(format!("d = sd{i}_depth(near);"));
                w.block("if (d < 0.0)", |w| w.line("return none;"));
            });
            w.line(format!("let u = {inv_proj} * vec4<f32>(n, d, 1.0);"));
            w.block(format!("if (!(abs(u.w) > {}))", f32_lit(TINY_W)), |w| {
                w.line("return none;")
            });
            w.line(format!("let u2 = {inv_proj} * vec4<f32>(n, d * {}, 1.0);", f32_lit(1.0 + DEPTH_ULPS)));
            w.line("let s = u.xyz / u.w;");
            w.comment("The surface taken nearer by its rounding (see the reference's Place::behind).");
            w.line(format!(
                "let tolerance = select(0.0, abs(u2.z / u2.w - s.z), abs(u2.w) > {}) + {} * abs(pr[0].z);",
                f32_lit(TINY_W),
                f32_lit(VIEW_ROUNDING)
            ));
            w.line("return array<vec4<f32>, 3>(vec4<f32>(pr[0].xyz, 1.0), vec4<f32>(s.xy, s.z + tolerance, f32(near.x)), vec4<f32>(n, f32(near.y), 0.0));");
        });
        w.comment("The tangent at s from its neighbours plus and minus: the one nearer in depth.");
        w.block(
            format!("fn sd{i}_tangent(s: vec3<f32>, plus: vec4<f32>, minus: vec4<f32>) -> vec4<f32>"),
            |w| {
                w.block("if (plus.w != 0.0 && minus.w != 0.0)", |w| {
                    w.line("return select(vec4<f32>(s - minus.xyz, 1.0), vec4<f32>(plus.xyz - s, 1.0), abs(plus.z - s.z) <= abs(s.z - minus.z));");
                });
                w.block("if (plus.w != 0.0)", |w| {
                    w.line("return vec4<f32>(plus.xyz - s, 1.0);")
                });
                w.block("if (minus.w != 0.0)", |w| {
                    w.line("return vec4<f32>(s - minus.xyz, 1.0);")
                });
                w.line("return vec4<f32>(0.0);");
            },
        );
        w.block(
            format!("fn sd{i}_normal(s_in: vec3<f32>, p: vec2<i32>, toward: vec3<f32>) -> vec3<f32>"),
            |w| {
                w.line(format!("let centre = sd{i}_surface(p);"));
                w.line("let s = select(s_in, centre.xyz, centre.w != 0.0);");
                w.line(format!(
                    "let tx = sd{i}_tangent(s, sd{i}_surface(p + vec2<i32>(1, 0)), sd{i}_surface(p - vec2<i32>(1, 0)));"
                ));
                w.line(format!(
                    "let ty = sd{i}_tangent(s, sd{i}_surface(p + vec2<i32>(0, 1)), sd{i}_surface(p - vec2<i32>(0, 1)));"
                ));
                w.line("let to_eye = toward - s;");
                w.line("var n = select(to_eye, cross(tx.xyz, ty.xyz), tx.w != 0.0 && ty.w != 0.0);");
                w.line("n = select(n, -n, dot(n, to_eye) < 0.0);");
                w.line(format!("let iv = {inv_view};"));
                w.line("let world = mat3x3<f32>(iv[0].xyz, iv[1].xyz, iv[2].xyz) * n;");
                w.line("let l = length(world);");
                w.line("let back = iv[2].xyz / max(length(iv[2].xyz), 1e-30);");
                w.line("return select(back, world / l, l > 1e-30 && l < 3.0e38);");
            },
        );
        w.block(
            format!("fn collider_hit_{i}(a: vec3<f32>, b: vec3<f32>) -> vec4<f32>"),
            |w| {
                w.line("let none = vec4<f32>(2.0, 0.0, 1.0, 0.0);");
                w.block("if (scene_camera[0].x < 1.0)", |w| w.line("return none;"));
                w.line("let sz = scene_camera[0].xy;");
                w.line(format!("let pa = sd{i}_project(a);"));
                w.line(format!("let pb = sd{i}_project(b);"));
                w.line(format!("var samples = {MAX_SAMPLES}u;"));
                w.block("if (pa[0].w != 0.0 && pb[0].w != 0.0)", |w| {
                    w.line("let px = max(abs((pb[1].x - pa[1].x) * 0.5 * sz.x), abs((pb[1].y - pa[1].y) * 0.5 * sz.y));");
                    w.line(format!(
                        "samples = u32(clamp(ceil(px), 1.0, {}));",
                        f32_lit(f64::from(MAX_SAMPLES))
                    ));
                });
                w.line(format!("var prev = sd{i}_place(a);"));
                w.line("var prev_t = 0.0;");
                w.block("for (var k = 1u; k <= samples; k++)", |w| {
                    w.line("let t = f32(k) / f32(samples);");
                    w.line(format!("let cur = sd{i}_place(a + (b - a) * t);"));
                    w.block("if (prev[0].w != 0.0 && cur[0].w != 0.0)", |w| {
                        w.line("let deeper = max(prev[0].z - cur[0].z, 0.0);");
                        w.line("let behind_prev = prev[1].z - prev[0].z;");
                        w.line("let behind_cur = cur[1].z - cur[0].z;");
                        w.block(
                            format!("if (behind_prev < 0.0 && behind_cur >= 0.0 && behind_cur <= {thickness} + deeper)"),
                            |w| {
                                w.line("var lo = prev_t;");
                                w.line("var hi = t;");
                                w.line("var front = prev;");
                                w.block(format!("for (var j = 0u; j < {BISECTIONS}u; j++)"), |w| {
                                    w.line("let mid = 0.5 * (lo + hi);");
                                    w.line(format!("let m = sd{i}_place(a + (b - a) * mid);"));
                                    w.block("if (m[0].w != 0.0 && m[1].z - m[0].z >= 0.0)", |w| {
                                        w.line("hi = mid;")
                                    });
                                    w.block("else", |w| {
                                        w.line("lo = mid;");
                                        w.block("if (m[0].w != 0.0)", |w| w.line("front = m;"));
                                    });
                                });
                                w.line(format!(
                                    "return vec4<f32>(lo, sd{i}_normal(front[1].xyz, vec2<i32>(i32(front[1].w), i32(front[2].z)), pa[0].xyz));"
                                ));
                            },
                        );
                    });
                    w.line("prev = cur;");
                    w.line("prev_t = t;");
                });
                w.line("return none;");
            },
        );
        w.block(
            format!("fn collider_push_{i}(x: vec3<f32>, margin: f32) -> vec3<f32>"),
            |w| {
                w.block("if (scene_camera[0].x < 1.0)", |w| w.line("return x;"));
                w.line(format!("let p = sd{i}_place(x);"));
                w.block("if (p[0].w == 0.0)", |w| w.line("return x;"));
                w.line("let behind = p[1].z - p[0].z;");
                w.block(
                    format!("if (!(behind >= 0.0 && behind <= {thickness}))"),
                    |w| w.line("return x;"),
                );
                w.line(format!("let ip = {inv_proj};"));
                w.line("let h0 = ip * vec4<f32>(p[2].xy, 0.25, 1.0);");
                w.line("let h1 = ip * vec4<f32>(p[2].xy, 0.75, 1.0);");
                let tiny = f32_lit(TINY_W);
                w.block(
                    format!("if (!(abs(h0.w) > {tiny} && abs(h1.w) > {tiny}))"),
                    |w| w.line("return x;"),
                );
                w.line("let ray = h1.xyz / h1.w - h0.xyz / h0.w;");
                w.block(format!("if (!(abs(ray.z) > {tiny}))"), |w| {
                    w.line("return x;")
                });
                w.line("let moved = p[0].xyz + ray * ((behind + margin) / ray.z);");
                w.line(format!("return ({inv_view} * vec4<f32>(moved, 1.0)).xyz;"));
            },
        );
    }
}
