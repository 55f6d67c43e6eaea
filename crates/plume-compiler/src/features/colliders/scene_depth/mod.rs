//! `SceneDepth`: particles collide with the depth image of the view they are drawn in, the
//! surfaces the camera sees. The host gives the image and its camera at run time (the
//! runtime's `Effect::set_scene_depth`; `plume render` and `plume preview` draw the effect's
//! scene meshes into one), so the compiled kernel reads them from two bindings:
//! `scene_depth`, the runtime's copy of the host's depth (a buffer), and `scene_camera`, [`DepthCamera::words`]. Until an
//! image is given, nothing collides.
//!
//! **What the image holds.** A pixel holding depth d in (0, 1) is the point its centre
//! unprojects to at d through the inverse projection; depth exactly 0 or 1 (a clear value,
//! standard or reversed-Z) is empty. The surface on a point's own view ray is d interpolated
//! bilinearly between the four nearest pixel centres (d is affine across a triangle on screen,
//! so a plane comes out exact but for the depth's rounding; where one of the four is empty,
//! the nearest pixel's d), unprojected, and taken nearer by what 8 ulps of d are worth there
//! (`Place::behind`). A point is *behind* the surface when its view depth (−z in view space)
//! exceeds the surface's, and *inside* it when behind by no more than `thickness`: past that it
//! passes freely (behind an object, not in it). Off screen, behind the camera or over an empty
//! pixel, it passes freely too: depth collision only knows what the camera sees.
//!
//! **Swept.** The substep's segment is sampled at one point per pixel it crosses on screen
//! (at most `MAX_SAMPLES`); a crossing is a sample in front of its surface followed by one
//! inside it, or behind it by at most `thickness` plus how much deeper the particle went
//! between the two, so a particle moving fast along the view ray does not pass through. The
//! crossing is bisected to the last point in front, until known to `CONTACT_PRECISION` of
//! the view depth (at most `BISECTIONS` halvings). The normal comes from the nearest pixel's
//! neighbours' surface points (of the left and right neighbours, the one nearer in depth,
//! likewise up and down), turned to face the side the particle came from.
//!
//! **Inside.** A particle found inside the surface at the end of a substep (a resting particle
//! slid onto a pixel that shows the surface a little nearer) is moved along its view ray to
//! just in front of it. There is no push-out at the start of a substep
//! (`pushes_at_start`).
//!
//! The f64 reference ([`SceneDepthIr::hit`]) runs the same steps on the same f32 image and
//! camera, given to `ReferenceSim::set_scene_depth`; f32 and f64 may round a point onto
//! neighbouring pixels where it projects onto a pixel's edge.

mod image;
mod wgsl;

use std::sync::Arc;

use glam::{DMat3, DMat4, DVec3, DVec4};

use super::Hit;
use crate::base::check::Checker;
use crate::base::path::ValuePath;

pub use image::{at, DepthCamera, DepthImage};
pub(crate) use image::{CAMERA_VEC4S, CAMERA_WORDS};

/// The thickness when the file gives none (m).
pub(crate) const DEFAULT_THICKNESS: f64 = 0.5;

/// The most points a substep's segment is sampled at.
pub(crate) const MAX_SAMPLES: u32 = 32;

/// The most bisection halvings of a crossing.
pub(super) const BISECTIONS: u32 = 16;

/// A crossing is bisected until it is known to this fraction of the view depth (where the
/// segment starts): 1e-5, 0.08 mm at 8 m, finer than the depth image's own rounding there
/// (about 0.6 mm for a standard Depth32Float range; see [`Place::behind`]). A resting particle's
/// short segment needs few halvings, a fast one's up to [`BISECTIONS`].
pub(super) const CONTACT_PRECISION: f64 = 1e-5;

/// A homogeneous w this small (in magnitude) is a point at infinity.
pub(super) const TINY_W: f64 = 1e-30;

/// A scene depth collider in the IR; `image` is set only in a reference simulation that was
/// given one.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneDepthIr {
    /// How far behind a surface a particle still collides (m).
    pub thickness: f64,
    /// The image the reference collides with.
    pub image: Option<Arc<DepthImage>>,
}

/// `SceneDepth(...)` as effect files write it: the surfaces the view's depth image shows,
/// given at run time by the host (or by the scene `plume render` and `plume preview` draw).
#[derive(Clone, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneDepth {
    /// How far behind a surface a particle still collides (m, > 0); farther behind, it is
    /// behind the object, not in it, and passes.
    #[serde(default = "default_thickness")]
    pub thickness: f64,
    /// Fraction of normal speed kept on a bounce, in [0, 1].
    pub restitution: f64,
    /// Fraction of tangential speed lost on a bounce, in [0, 1].
    pub friction: f64,
}

/// The fields of [`SceneDepth`].
pub(crate) const FIELDS: &[&str] = &["thickness", "restitution", "friction"];

fn default_thickness() -> f64 {
    DEFAULT_THICKNESS
}

impl SceneDepth {
    /// Checks the thickness (> 0) and the bounce; `path` names the variant.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        c.positive(&path.field("thickness"), self.thickness);
        super::check_bounce(path, c, self.restitution, self.friction);
    }

    /// Lowers the checked collider (its image comes at run time).
    pub(crate) fn lower(&self) -> super::ColliderIr {
        super::ColliderIr {
            surface: super::Surface::SceneDepth(SceneDepthIr {
                thickness: self.thickness,
                image: None,
            }),
            restitution: self.restitution,
            friction: self.friction,
        }
    }
}

/// Where a world point is against the image.
#[derive(Clone, Copy, Debug)]
struct Place {
    /// Its normalised device coordinates (x, y); None behind the camera.
    ndc: Option<(f64, f64)>,
    /// Its view depth (−z in view space).
    depth: f64,
    /// Where there is a surface on its view ray: the surface's view depth, taken nearer by
    /// its rounding, and the nearest pixel.
    surface: Option<(f64, (i64, i64))>,
}

impl Place {
    /// How far behind the surface the point is (m; negative in front), where there is one.
    /// The surface is taken nearer by what 8 ulps of its depth are worth there, plus 1e-6 of
    /// the point's depth, so that a particle left just in front of it is not found in it by
    /// the depth image's rounding.
    fn behind(&self) -> Option<f64> {
        self.surface.map(|(s, _)| self.depth - s)
    }
}

/// Relative change of a depth value standing for its rounding: 8 f32 ulps.
pub(super) const DEPTH_ULPS: f64 = 8.0 / 8_388_608.0;

/// Relative rounding of a view depth computed in f32 through a matrix.
pub(super) const VIEW_ROUNDING: f64 = 1e-6;

/// The image's matrices in f64 (from the very f32 words the GPU reads).
struct Frame<'a> {
    image: &'a DepthImage,
    view_projection: DMat4,
    view: DMat4,
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
            view_projection: dmat(&image.camera.view_projection),
            view: dmat(&image.camera.view),
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

    /// The depth of pixel (ix, iy), clamped to the image; None where it is empty.
    fn depth(&self, ix: i64, iy: i64) -> Option<f64> {
        let (w, h) = (i64::from(self.image.width), i64::from(self.image.height));
        let d = f64::from(self.image.depth[(iy.clamp(0, h - 1) * w + ix.clamp(0, w - 1)) as usize]);
        (d > 0.0 && d < 1.0).then_some(d)
    }

    /// Where `x` is against the image.
    fn place(&self, x: DVec3) -> Place {
        let p = x.extend(1.0);
        let c = self.view_projection * p;
        let depth = -self.view.row(2).dot(p);
        let ndc = (c.w > TINY_W).then(|| (c.x / c.w, c.y / c.w));
        let surface = ndc.and_then(|(nx, ny)| self.surface_on_ray(nx, ny, depth));
        Place {
            ndc,
            depth,
            surface,
        }
    }

    /// The surface on the view ray through (nx, ny): its view depth (taken nearer by its
    /// rounding; see [`Place::behind`]) and the nearest pixel, or None off screen or empty.
    fn surface_on_ray(&self, nx: f64, ny: f64, depth: f64) -> Option<(f64, (i64, i64))> {
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
        // Only the unprojection's z and w are needed: rows 2 and 3 of the inverse projection.
        let ip = &self.inverse_projection;
        let u = DVec4::new(nx, ny, d, 1.0);
        let (z, w) = (ip.row(2).dot(u), ip.row(3).dot(u));
        if w.is_nan() || w.abs() <= TINY_W {
            return None;
        }
        // What 8 ulps of depth are worth: far away a standard depth buffer's steps grow with
        // the square of the distance.
        let step = d * DEPTH_ULPS;
        let (z2, w2) = (z + step * ip.z_axis.z, w + step * ip.z_axis.w);
        let rounding = if w2.abs() > TINY_W {
            (z2 / w2 - z / w).abs()
        } else {
            0.0
        };
        Some((-z / w - rounding - VIEW_ROUNDING * depth.abs(), (ix, iy)))
    }

    /// The world normal of the surface at `pixel`, facing `toward` (a view-space point).
    fn normal(&self, (ix, iy): (i64, i64), toward: DVec3) -> DVec3 {
        let Some(s) = self.surface(ix, iy) else {
            return self.back();
        };
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
            self.back()
        }
    }

    /// The direction back towards the camera (view +z in the world).
    fn back(&self) -> DVec3 {
        let back = DMat3::from_mat4(self.inverse_view) * DVec3::Z;
        back / back.length().max(1e-30)
    }
}

impl SceneDepthIr {
    /// The first contact of segment `a` -> `b` (see the module doc).
    pub fn hit(&self, a: DVec3, b: DVec3) -> Option<Hit> {
        let frame = Frame::new(self.image.as_deref()?);
        let (w, h) = (frame.image.width as f64, frame.image.height as f64);
        let (pa, pb) = (frame.place(a), frame.place(b));
        let samples = match (pa.ndc, pb.ndc) {
            (Some(na), Some(nb)) => {
                let px = ((nb.0 - na.0) * 0.5 * w)
                    .abs()
                    .max(((nb.1 - na.1) * 0.5 * h).abs());
                px.ceil().clamp(1.0, f64::from(MAX_SAMPLES)) as u32
            }
            _ => MAX_SAMPLES,
        };
        let mut prev = pa;
        let mut prev_t = 0.0;
        for k in 1..=samples {
            let t = f64::from(k) / f64::from(samples);
            let cur = if k == samples {
                pb
            } else {
                frame.place(a + (b - a) * t)
            };
            if let (Some(bp), Some(bc)) = (prev.behind(), cur.behind()) {
                let deeper = (cur.depth - prev.depth).max(0.0);
                if bp < 0.0 && bc >= 0.0 && bc <= self.thickness + deeper {
                    let (mut lo, mut hi) = (prev_t, t);
                    let mut front = prev;
                    let enough =
                        CONTACT_PRECISION * pa.depth.max(0.0) / (b - a).length().max(1e-30);
                    for _ in 0..BISECTIONS {
                        if hi - lo <= enough {
                            break;
                        }
                        let mid = 0.5 * (lo + hi);
                        let m = frame.place(a + (b - a) * mid);
                        if m.behind().is_some_and(|b| b >= 0.0) {
                            hi = mid;
                        } else {
                            lo = mid;
                            if m.surface.is_some() {
                                front = m;
                            }
                        }
                    }
                    let (_, pixel) = front.surface.expect("a front sample has a surface");
                    let toward = (frame.view * a.extend(1.0)).truncate();
                    return Some(Hit {
                        s: lo,
                        normal: frame.normal(pixel, toward),
                    });
                }
            }
            prev = cur;
            prev_t = t;
        }
        None
    }

    /// `x` moved along its view ray to `margin` in front of the surface when it is inside it.
    pub(crate) fn push_out(&self, x: DVec3, margin: f64) -> DVec3 {
        let Some(image) = self.image.as_deref() else {
            return x;
        };
        let frame = Frame::new(image);
        let p = frame.place(x);
        let (Some(behind), Some((nx, ny))) = (p.behind(), p.ndc) else {
            return x;
        };
        if !(behind >= 0.0 && behind <= self.thickness) {
            return x;
        }
        let (Some(u0), Some(u1)) = (frame.unproject(nx, ny, 0.25), frame.unproject(nx, ny, 0.75))
        else {
            return x;
        };
        let ray = u1 - u0;
        if ray.z.is_nan() || ray.z.abs() <= TINY_W {
            return x;
        }
        // Depth is −z: moving by λ·ray changes it by −λ·ray.z.
        let view = (frame.view * x.extend(1.0)).truncate();
        let moved = view + ray * ((behind + margin) / ray.z);
        (frame.inverse_view * moved.extend(1.0)).truncate()
    }

    /// Whether `x` is not inside a surface (the tests' check; no margin).
    pub fn allows(&self, x: DVec3) -> bool {
        let Some(image) = self.image.as_deref() else {
            return true;
        };
        Frame::new(image)
            .place(x)
            .behind()
            .is_none_or(|b| !(b >= 0.0 && b <= self.thickness))
    }

    /// One line for `--emit ir`.
    pub fn describe(&self) -> String {
        format!(
            "SceneDepth thickness {} (the host's depth image, at run time)",
            self.thickness
        )
    }
}
