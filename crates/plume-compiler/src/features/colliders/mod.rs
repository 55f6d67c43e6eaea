//! Colliders: each module owns one surface's schema checks, lowering, swept test in f64 (the
//! reference) and its WGSL twin. This module owns what they share: the schema enum, the IR,
//! the response and the swept resolution loop that both the update kernel and the reference
//! run.
//!
//! **Swept, not sampled.** Each substep tests the segment from the particle's old to its new
//! position against every collider, takes the first contact, puts the particle there (a few
//! f32 ulps outside), applies Latta's response (normal speed reflected by restitution,
//! tangential speed reduced by friction) and moves it the rest of the substep with its new
//! velocity, testing that segment again. At most `MAX_CONTACTS` contacts are resolved per
//! substep; a particle that would need more stays at its last contact for the rest of the
//! substep (it keeps its new velocity), so nothing passes through. A particle that starts a
//! substep inside a solid (spawned there, or rounding) is first pushed out to the nearest
//! surface, and every particle is pushed out once more after the loop.

pub mod aabb;
pub(crate) mod height_field;
pub(crate) mod height_image;
pub mod mesh;
pub mod plane;
pub mod scene_depth;
mod schema;
pub mod sphere;

pub(crate) use schema::collider_path;
pub use schema::Collider;

use glam::DVec3;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::writer::{f32_lit, Writer};

/// Contacts resolved per substep; past that the particle stops at its last contact.
pub(crate) const MAX_CONTACTS: u32 = 4;

/// The contact margin, relative to the larger of |x| and the colliders' own coordinates:
/// 16 f32 ulps, so that rounding cannot leave a particle on the wrong side of a surface.
pub const MARGIN: f64 = 1.9e-6;

/// The first contact along a segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Where along the segment, in [0, 1].
    pub s: f64,
    /// Unit normal at the contact, pointing to the allowed side.
    pub normal: DVec3,
}

/// A surface in the IR.
#[derive(Clone, Debug, PartialEq)]
pub enum Surface {
    /// A half-space.
    Plane(plane::PlaneIr),
    /// A ball, solid or a container.
    Sphere(sphere::SphereIr),
    /// An axis-aligned box, solid or a container.
    Box(aabb::BoxIr),
    /// A height field.
    HeightField(height_field::HeightFieldIr),
    /// A mesh's baked signed distance field.
    Mesh(mesh::MeshIr),
    /// The surfaces a depth image shows.
    SceneDepth(scene_depth::SceneDepthIr),
}

/// Checks the bounce every collider has: `restitution` and `friction`, each in [0, 1].
fn check_bounce(path: &ValuePath, c: &mut Checker, restitution: f64, friction: f64) {
    c.within(&path.field("restitution"), restitution, 0.0, 1.0);
    c.within(&path.field("friction"), friction, 0.0, 1.0);
}

/// A collider in the IR: a surface and how particles bounce off it.
#[derive(Clone, Debug, PartialEq)]
pub struct ColliderIr {
    /// The surface.
    pub surface: Surface,
    /// Restitution in [0, 1].
    pub restitution: f64,
    /// Friction in [0, 1].
    pub friction: f64,
}

impl Surface {
    /// The variant's name as written in effect files.
    pub fn name(&self) -> &'static str {
        match self {
            Surface::Plane(_) => "Plane",
            Surface::Sphere(_) => "Sphere",
            Surface::Box(_) => "Box",
            Surface::HeightField(_) => "HeightField",
            Surface::Mesh(_) => "Mesh",
            Surface::SceneDepth(_) => "SceneDepth",
        }
    }

    /// The first contact of the segment `a` -> `b` with the surface, entering the forbidden
    /// side from the allowed one.
    pub fn hit(&self, a: DVec3, b: DVec3) -> Option<Hit> {
        match self {
            Surface::Plane(p) => p.hit(a, b),
            Surface::Sphere(s) => s.hit(a, b),
            Surface::Box(s) => s.hit(a, b),
            Surface::HeightField(s) => s.hit(a, b),
            Surface::Mesh(s) => s.hit(a, b),
            Surface::SceneDepth(s) => s.hit(a, b),
        }
    }

    /// `x` moved to the allowed side (plus `margin`) when it is on the forbidden one.
    pub(crate) fn push_out(&self, x: DVec3, margin: f64) -> DVec3 {
        match self {
            Surface::Plane(p) => p.push_out(x, margin),
            Surface::Sphere(s) => s.push_out(x, margin),
            Surface::Box(s) => s.push_out(x, margin),
            Surface::HeightField(s) => s.push_out(x, margin),
            Surface::Mesh(s) => s.push_out(x, margin),
            Surface::SceneDepth(s) => s.push_out(x, margin),
        }
    }

    /// Whether a particle is pushed out at the start of a substep as well as at its end. The
    /// scene depth is not: its image only changes between frames, and the end's push-out
    /// (every substep) already leaves each particle outside; skipping the start's saves a
    /// lookup of the image per particle and substep.
    pub(crate) fn pushes_at_start(&self) -> bool {
        !matches!(self, Surface::SceneDepth(_))
    }

    /// Whether `x` is on the allowed side (the tests' check; no margin).
    pub fn allows(&self, x: DVec3) -> bool {
        match self {
            Surface::Plane(p) => (x - p.point).dot(p.normal) >= 0.0,
            Surface::Sphere(s) => s.allows(x),
            Surface::Box(s) => s.allows(x),
            Surface::HeightField(s) => s.allows(x),
            Surface::Mesh(s) => s.allows(x),
            Surface::SceneDepth(s) => s.allows(x),
        }
    }

    /// The largest coordinate magnitude the surface is built from (for the margin).
    pub fn scale(&self) -> f64 {
        match self {
            Surface::Plane(p) => p.point.abs().max_element(),
            Surface::Sphere(s) => s.center.abs().max_element() + s.radius,
            Surface::Box(s) => s.min.abs().max(s.max.abs()).max_element(),
            Surface::HeightField(s) => s.scale(),
            Surface::Mesh(s) => s.scale(),
            // A view's surfaces are as far out as the particles that meet them.
            Surface::SceneDepth(_) => 0.0,
        }
    }

    /// The thinnest feature the surface has, for the f32 resolution warning (None: unbounded).
    pub(crate) fn thinnest(&self) -> Option<f64> {
        match self {
            Surface::Plane(_) | Surface::HeightField(_) | Surface::SceneDepth(_) => None,
            Surface::Sphere(s) => Some(s.radius),
            Surface::Box(s) => Some((s.max - s.min).min_element()),
            Surface::Mesh(s) => Some(s.cell()),
        }
    }

    /// One line for `--emit ir`.
    pub fn describe(&self) -> String {
        let v = |v: DVec3| format!("({}, {}, {})", v.x, v.y, v.z);
        match self {
            Surface::Plane(p) => format!("Plane point {} normal {}", v(p.point), v(p.normal)),
            Surface::Sphere(s) => format!(
                "Sphere center {} radius {}{}",
                v(s.center),
                s.radius,
                if s.inside { " inside" } else { "" }
            ),
            Surface::Box(s) => format!(
                "Box min {} max {}{}",
                v(s.min),
                v(s.max),
                if s.inside { " inside" } else { "" }
            ),
            Surface::HeightField(s) => s.describe(),
            Surface::Mesh(s) => s.describe(),
            Surface::SceneDepth(s) => s.describe(),
        }
    }

    /// Emits `fn collider_hit_{i}(a, b) -> vec4<f32>` ((s, normal), s = 2 for no contact) and
    /// `fn collider_push_{i}(x, margin) -> vec3<f32>`.
    fn emit_fns(&self, w: &mut Writer, i: usize, data_offset: u32) {
        match self {
            Surface::Plane(p) => p.emit(w, i),
            Surface::Sphere(s) => s.emit(w, i),
            Surface::Box(s) => s.emit(w, i),
            Surface::HeightField(s) => s.emit(w, i, data_offset),
            Surface::Mesh(s) => s.emit(w, i, data_offset),
            Surface::SceneDepth(s) => s.emit(w, i),
        }
    }

    /// How many f32 values the surface keeps in the `collider_data` binding.
    pub(crate) fn data_len(&self) -> u32 {
        match self {
            Surface::HeightField(f) => f.heights.len() as u32,
            Surface::Mesh(m) => m.baked.sdf.values.len() as u32,
            _ => 0,
        }
    }
}

impl ColliderIr {
    /// Latta's response to a contact with normal `n`: v' = (1 - mu) v_t - e v_n when moving
    /// into the surface; a contact slower than `rest_speed` does not bounce (e = 0) so that
    /// resting particles stay put instead of hopping by e·g·h² every step.
    pub(crate) fn respond(&self, v: DVec3, n: DVec3, rest_speed: f64) -> DVec3 {
        let vn = v.dot(n);
        if vn >= 0.0 {
            return v;
        }
        let v_n = vn * n;
        let e = if -vn < rest_speed {
            0.0
        } else {
            self.restitution
        };
        (1.0 - self.friction) * (v - v_n) - e * v_n
    }
}

/// The largest coordinate any collider is built from, at least 1 (for the margin).
pub(crate) fn scale(colliders: &[ColliderIr]) -> f64 {
    colliders
        .iter()
        .map(|c| c.surface.scale())
        .fold(1.0, f64::max)
}

/// The contact margin at `x`.
pub fn margin(x: DVec3, scale: f64) -> f64 {
    MARGIN * x.abs().max_element().max(scale)
}

/// `x` pushed out of every collider (at the start of a substep, only of those that push there).
fn push_out_all(colliders: &[ColliderIr], mut x: DVec3, scale: f64, start: bool) -> DVec3 {
    for c in colliders {
        if !start || c.surface.pushes_at_start() {
            x = c.surface.push_out(x, margin(x, scale));
        }
    }
    x
}

/// The f64 reference of the swept resolution (see the module doc): the particle moved from
/// `x0` to `x` this substep of length `h`; `v` is its velocity (Verlet: its displacement).
/// Returns whether it touched a collider.
pub(crate) fn resolve(
    colliders: &[ColliderIr],
    rest_speed: f64,
    x0: DVec3,
    x: &mut DVec3,
    v: &mut DVec3,
    verlet: bool,
    h: f64,
) -> bool {
    if colliders.is_empty() {
        return false;
    }
    let scale = scale(colliders);
    let mut x_from = push_out_all(colliders, x0, scale, true);
    let mut vel = if verlet { *v / h } else { *v };
    let mut rest = 1.0;
    let mut touched = false;
    for k in 0..MAX_CONTACTS {
        let mut best: Option<(Hit, &ColliderIr)> = None;
        for c in colliders {
            if let Some(hit) = c.surface.hit(x_from, *x) {
                if best.is_none_or(|(b, _)| hit.s < b.s) {
                    best = Some((hit, c));
                }
            }
        }
        let Some((hit, c)) = best else { break };
        let on = x_from + (*x - x_from) * hit.s;
        let contact = on + hit.normal * margin(on, scale);
        vel = c.respond(vel, hit.normal, rest_speed);
        rest *= 1.0 - hit.s;
        x_from = contact;
        *x = if k + 1 == MAX_CONTACTS {
            contact
        } else {
            contact + vel * (rest * h)
        };
        touched = true;
    }
    *x = push_out_all(colliders, *x, scale, false);
    if touched {
        *v = if verlet { vel * h } else { vel };
    }
    touched
}

/// Emits each collider's functions; a height field's heights and a mesh's field live in the
/// `collider_data` binding, one after the other in collider order.
pub(crate) fn emit_helpers(w: &mut Writer, colliders: &[ColliderIr]) {
    let mut offset = 0;
    for (i, c) in colliders.iter().enumerate() {
        w.comment(format!("collide[{i}]: {}", c.surface.name()));
        c.surface.emit_fns(w, i, offset);
        offset += c.surface.data_len();
        w.blank();
    }
}

/// The height fields' heights and the meshes' fields, in collider order (the `collider_data`
/// binding).
pub fn data(colliders: &[ColliderIr]) -> Vec<f32> {
    let mut out = Vec::new();
    for c in colliders {
        match &c.surface {
            Surface::HeightField(f) => out.extend(f.heights.iter().map(|&h| h as f32)),
            Surface::Mesh(m) => out.extend_from_slice(&m.baked.sdf.values),
            _ => {}
        }
    }
    out
}

/// Emits the swept resolution in the update kernel's substep, with `x_start` (where the
/// substep began), `x` and `v` (or Verlet's `d`) in scope. Mirrors [`resolve`]; sets the
/// variable `touched_flag` names to true after a contact, when one is given.
pub(crate) fn emit_resolve(
    w: &mut Writer,
    colliders: &[ColliderIr],
    rest_speed: f64,
    h: f64,
    verlet: bool,
    touched_flag: Option<&str>,
) {
    let scale = f32_lit(scale(colliders));
    let push_all = |w: &mut Writer, var: &str, start: bool| {
        for (i, c) in colliders.iter().enumerate() {
            if start && !c.surface.pushes_at_start() {
                continue;
            }
            w.line(format!(
                "{var} = collider_push_{i}({var}, {} * max(max(abs({var}.x), abs({var}.y)), max(abs({var}.z), {scale})));",
                f32_lit(MARGIN)
            ));
        }
    };
    w.block("", |w| {
        w.line("var x_from = x_start;");
        push_all(w, "x_from", true);
        if verlet {
            w.line(format!("var vel = d * {};", f32_lit(1.0 / h)));
        } else {
            w.line("var vel = v;");
        }
        w.line("var rest = 1.0;");
        w.line("var touched = false;");
        w.block(format!("for (var k = 0u; k < {MAX_CONTACTS}u; k++)"), |w| {
            w.line("var hit = vec4<f32>(2.0, 0.0, 0.0, 0.0);");
            w.line("var bounce = vec2<f32>(0.0, 1.0);");
            for (i, c) in colliders.iter().enumerate() {
                w.line(format!("let h{i} = collider_hit_{i}(x_from, x);"));
                w.block(format!("if (h{i}.x < hit.x)"), |w| {
                    w.line(format!("hit = h{i};"));
                    w.line(format!(
                        "bounce = vec2<f32>({}, {});",
                        f32_lit(c.restitution),
                        f32_lit(1.0 - c.friction)
                    ));
                });
            }
            w.block("if (hit.x > 1.0)", |w| w.line("break;"));
            w.line("let n = hit.yzw;");
            w.line("let x_on = x_from + (x - x_from) * hit.x;");
            w.line(format!(
                "let contact = x_on + n * ({} * max(max(abs(x_on.x), abs(x_on.y)), max(abs(x_on.z), {scale})));",
                f32_lit(MARGIN)
            ));
            w.line("let vn = dot(vel, n);");
            w.block("if (vn < 0.0)", |w| {
                w.line("let v_n = vn * n;");
                w.line(format!(
                    "let e = select(bounce.x, 0.0, -vn < {});",
                    f32_lit(rest_speed)
                ));
                w.line("vel = bounce.y * (vel - v_n) - e * v_n;");
            });
            w.line("rest = rest * (1.0 - hit.x);");
            w.line("x_from = contact;");
            w.line(format!(
                "x = select(contact + vel * (rest * {}), contact, k + 1u == {MAX_CONTACTS}u);",
                f32_lit(h)
            ));
            w.line("touched = true;");
        });
        push_all(w, "x", false);
        w.block("if (touched)", |w| {
            if let Some(flag) = touched_flag {
                w.line(format!("{flag} = true;"));
            }
            if verlet {
                w.line(format!("d = vel * {};", f32_lit(h)));
            } else {
                w.line("v = vel;");
            }
        });
    });
}
