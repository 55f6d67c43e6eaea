//! What the sprite and trail draw modules share: the view uniform, loading a particle from
//! the buffers, its life fraction and age, the colour and size gradients, the tint, and the
//! soft-particle fade against the scene's depth.

use super::{DrawShape, SCENE_DEPTH_BINDING};
use crate::base::lifetime::LifetimeSteps;
use crate::base::rng;
use crate::base::writer::{f32_lit, Writer};
use crate::ir::EffectIr;
use crate::stages::passes::layout::{Attribute, Layout};
use crate::stages::wgsl::{particle_from_words, word_loads};

/// `finite3(x)`: whether no component is Inf or NaN, tested on the bits.
pub(crate) fn emit_finite3(w: &mut Writer) {
    w.comment("Integer test for Inf/NaN: WGSL may assume floats are finite.");
    w.block("fn finite3(x: vec3<f32>) -> bool", |w| {
        w.line("let e = bitcast<vec3<u32>>(x) & vec3<u32>(0x7f800000u);");
        w.line("return all(e != vec3<u32>(0x7f800000u));");
    });
}

/// The `DrawView` uniform's struct (binding 0, [`DRAW_VIEW_BYTES`]).
pub(crate) fn emit_draw_view(w: &mut Writer) {
    w.comment("The camera and the frame, written by the runtime before each draw.");
    w.block("struct DrawView", |w| {
        w.line("view: mat4x4<f32>,");
        w.line("proj: mat4x4<f32>,");
        w.line("steps: u32,");
        w.line("size_scale: f32,");
        w.line("pad0: u32,");
        w.line("pad1: u32,");
    });
}

/// `load_particle(slot)`: the particle in global slot `slot`, from whichever buffer holds it
/// (each buffer word-major over its own slots: [`crate::base::kernel::word_index`]).
pub(crate) fn emit_load(w: &mut Writer, layout: &Layout, shape: &DrawShape) {
    let n = layout.vec4s();
    // A padded layout's slots follow from a buffer's length; a half-motion layout's planes
    // are not all vec4s a slot, so its slots come from the chunking.
    let padded = !layout.half_motion;
    if layout.half_motion {
        crate::stages::wgsl::emit_half_unpack(w);
    }
    w.block("fn load_particle(slot: u32) -> Particle", |w| {
        if shape.chunks <= 1 {
            if padded && n > 1 {
                w.line("let slots = arrayLength(&particles_0) / VEC4S;");
            } else if !padded {
                w.line("let slots = CAPACITY;");
            }
            for (name, _, expr) in word_loads(layout, "particles_0", "slot", "slots") {
                w.line(format!("let {name} = {expr};"));
            }
        } else {
            w.line("let c = slot / CHUNK_SLOTS;");
            w.line("let i = slot - c * CHUNK_SLOTS;");
            let loads = word_loads(layout, "particles_0", "i", "slots");
            for (name, ty, _) in &loads {
                w.line(format!("var {name}: {ty};"));
            }
            w.block("switch c", |w| {
                for c in 0..shape.chunks {
                    let label = if c + 1 == shape.chunks {
                        format!("case {c}u, default")
                    } else {
                        format!("case {c}u")
                    };
                    w.block(label, |w| {
                        let buffer = format!("particles_{c}");
                        if padded && n > 1 {
                            w.line(format!("let slots = arrayLength(&{buffer}) / VEC4S;"));
                        } else if !padded {
                            w.line(format!(
                                "let slots = min(CHUNK_SLOTS, CAPACITY - {c}u * CHUNK_SLOTS);"
                            ));
                        }
                        for (name, _, expr) in word_loads(layout, &buffer, "i", "slots") {
                            w.line(format!("{name} = {expr};"));
                        }
                    });
                }
            });
        }
        w.line(format!("return {};", particle_from_words(layout)));
    });
}

/// `life_fraction(p)`: steps lived over whole steps of life, as the CPU's
/// `age / lifetime` (0 for a particle that never dies). With a stored spawn step it is
/// (steps − born) / (die_at − born + 1); otherwise the lifetime n comes from the shared
/// lifetime draw of the id, and n − (die_at + 1 − steps) steps have been lived.
pub(crate) fn emit_life_fraction(w: &mut Writer, layout: &Layout, shared: Option<LifetimeSteps>) {
    w.comment("Life fraction: whole steps lived over whole steps of life (lifetime.rs).");
    w.block("fn life_fraction(p: Particle) -> f32", |w| {
        w.block("if (p.die_at == DEAD)", |w| w.line("return 0.0;"));
        if layout.has(Attribute::SpawnStep) {
            w.line("let lived = draw.steps - p.born;");
            w.line("let life = p.die_at - p.born + 1u;");
        } else if let Some(draw) = shared {
            w.line(format!(
                "let lu = rand_u32(p.id, {}u);",
                rng::stream::LIFETIME
            ));
            w.line(format!("let life = {};", draw.wgsl()));
            w.comment("Steps still to live, this one's update included; wraps like die_at.");
            w.line("let left = p.die_at + 1u - draw.steps;");
            w.line("let lived = life - min(left, life);");
        } else {
            // needs_spawn_step() stores `born` whenever the draws differ.
            w.line("return 0.0;");
            return;
        }
        w.line("return clamp(f32(lived) / f32(life), 0.0, 1.0);");
    });
}

/// `age_steps(p)`: (whole steps lived, whole steps of life; 0 for a particle that never dies),
/// for choosing a flipbook frame or a spin's angle. From the stored spawn step when there is
/// one; otherwise from `die_at` and the shared lifetime draw (`needs_spawn_step` stores `born`
/// whenever a particle that never dies needs its age); (0, 0) when no particle ever dies and
/// none needs its age.
pub(crate) fn emit_age_steps(w: &mut Writer, layout: &Layout, shared: Option<LifetimeSteps>) {
    let dies = layout.has(Attribute::DeathStep);
    w.comment(
        "Whole steps lived and whole steps of life (0: never dies), for the flipbook or the spin.",
    );
    w.block("fn age_steps(p: Particle) -> vec2<u32>", |w| {
        if layout.has(Attribute::SpawnStep) {
            w.line("let lived = draw.steps - p.born;");
            if dies {
                w.block("if (p.die_at != DEAD)", |w| {
                    w.line("return vec2<u32>(lived, p.die_at - p.born + 1u);");
                });
            }
            w.line("return vec2<u32>(lived, 0u);");
        } else if let (true, Some(draw)) = (dies, shared) {
            w.block("if (p.die_at == DEAD)", |w| w.line("return vec2<u32>(0u);"));
            w.line(format!(
                "let lu = rand_u32(p.id, {}u);",
                rng::stream::LIFETIME
            ));
            w.line(format!("let life = {};", draw.wgsl()));
            w.line("let left = p.die_at + 1u - draw.steps;");
            w.line("return vec2<u32>(life - min(left, life), life);");
        } else {
            w.line("return vec2<u32>(0u);");
        }
    });
}

/// `color_at(f)` and `size_at(f)`: the render section's piecewise-linear gradients with their
/// stops baked in, as `RenderIr::color_at` and `size_at` (constant beyond the end stops; a
/// jump where two stops share a time).
pub(crate) fn emit_gradients(w: &mut Writer, ir: &EffectIr) {
    emit_particle_color(w, ir);
    emit_scalar_gradient(w, "size_at", &ir.render.size);
    if let Some(heights) = &ir.render.size_y {
        emit_scalar_gradient(w, "height_at", heights);
    }
}

/// `color_at(f)`: the particle's colour at life fraction `f`, its alpha from `render.alpha`'s
/// own stops when there are some (as `RenderIr::color_at`).
pub(crate) fn emit_particle_color(w: &mut Writer, ir: &EffectIr) {
    match &ir.render.alpha {
        None => emit_color_gradient(w, "color_at", &ir.render.color),
        Some(alpha) => {
            emit_color_gradient(w, "color_stops_at", &ir.render.color);
            emit_scalar_gradient(w, "alpha_at", alpha);
            w.block("fn color_at(f: f32) -> vec4<f32>", |w| {
                w.line("return vec4<f32>(color_stops_at(f).rgb, alpha_at(f));");
            });
        }
    }
}

/// `name(f)`: a scalar gradient through `stops` (0 where there are none).
pub(crate) fn emit_scalar_gradient(w: &mut Writer, name: &str, stops: &[(f64, f64)]) {
    let values: Vec<(f64, String)> = stops.iter().map(|(t, s)| (*t, f32_lit(*s))).collect();
    emit_gradient(w, name, "f32", &values, f32_lit(0.0));
}

/// `name(f)`: a colour gradient through `stops` (white where there are none).
pub(crate) fn emit_color_gradient(w: &mut Writer, name: &str, stops: &[(f64, [f64; 4])]) {
    let rgba = |c: [f64; 4]| {
        format!(
            "vec4<f32>({}, {}, {}, {})",
            f32_lit(c[0]),
            f32_lit(c[1]),
            f32_lit(c[2]),
            f32_lit(c[3])
        )
    };
    let colour: Vec<(f64, String)> = stops.iter().map(|(t, c)| (*t, rgba(*c))).collect();
    emit_gradient(w, name, "vec4<f32>", &colour, rgba([1.0, 1.0, 1.0, 1.0]));
}

pub(crate) fn emit_gradient(
    w: &mut Writer,
    name: &str,
    ty: &str,
    stops: &[(f64, String)],
    empty: String,
) {
    w.block(format!("fn {name}(f: f32) -> {ty}"), |w| {
        let Some((t0, first)) = stops.first() else {
            w.line(format!("return {empty};"));
            return;
        };
        if stops.iter().all(|(_, v)| v == first) {
            w.line(format!("return {first};"));
            return;
        }
        w.block(format!("if (f <= {})", f32_lit(*t0)), |w| {
            w.line(format!("return {first};"));
        });
        for pair in stops.windows(2) {
            let ((a_t, a), (b_t, b)) = (&pair[0], &pair[1]);
            w.block(format!("if (f <= {})", f32_lit(*b_t)), |w| {
                if b_t > a_t {
                    w.line(format!(
                        "return {a} + ({b} - {a}) * ((f - {}) / {});",
                        f32_lit(*a_t),
                        f32_lit(b_t - a_t)
                    ));
                } else {
                    w.line(format!("return {b};"));
                }
            });
        }
        w.line(format!("return {};", stops[stops.len() - 1].1));
    });
}

/// `view_distance(z)`: the distance in front of the camera of NDC depth z, from the draw
/// view's projection (see [`emit_soft`]).
pub(crate) fn emit_view_distance(w: &mut Writer) {
    w.comment(
        "Distance in front of the camera of NDC depth z (a far plane at infinity: a huge one).",
    );
    w.block("fn view_distance(z: f32) -> f32", |w| {
        w.block("if (draw.proj[3][3] > 0.5)", |w| {
            w.comment("Orthographic: depth is linear in distance.");
            w.block("if (abs(draw.proj[2][2]) < 1e-30)", |w| {
                w.line("return 0.0;")
            });
            w.line("return (draw.proj[3][2] - z) / draw.proj[2][2];");
        });
        w.line("let den = z + draw.proj[2][2];");
        w.block("if (abs(den) < 1e-30)", |w| w.line("return 3.0e38;"));
        w.line("return min(draw.proj[3][2] / den, 3.0e38);");
    });
}

/// The host's depth texture and `soft_fade(frag)`: how far (in metres along the view axis) the
/// scene's surface lies behind the fragment, over the fade distance, clamped to [0, 1]. Depths
/// are linearised with the projection's own terms, A = proj[2][2], B = proj[3][2]: for a
/// perspective projection (standard or reversed Z, finite or infinite far plane; proj[3][3] = 0)
/// NDC depth z and view distance d satisfy d = B / (z + A); for an orthographic one
/// (proj[3][3] = 1, w = 1) z = −A d + B, so d = (B − z) / A.
pub(crate) fn emit_soft(w: &mut Writer, distance: f64) {
    w.comment("Soft particles: the host's depth buffer (render.soft).");
    w.line(format!(
        "@group(0) @binding({SCENE_DEPTH_BINDING}) var scene_depth: texture_2d<f32>;"
    ));
    w.line(format!("const SOFT_DISTANCE: f32 = {};", f32_lit(distance)));
    w.blank();
    emit_view_distance(w);
    w.blank();
    w.block("fn soft_fade(frag: vec4<f32>) -> f32", |w| {
        w.comment("Clamped to the texture: a smaller one (the placeholder before the host binds its own) stays in bounds.");
        w.line("let pixel = min(vec2<u32>(frag.xy), textureDimensions(scene_depth) - vec2<u32>(1u));");
        w.line("let scene = textureLoad(scene_depth, pixel, 0).r;");
        w.line("let gap = view_distance(scene) - view_distance(frag.z);");
        w.line("return clamp(gap / SOFT_DISTANCE, 0.0, 1.0);");
    });
}

/// The draw modules' randomness: the PCG hash where the draw draws a value of its own (`draws`:
/// a shared lifetime, a palette), and `palette_tint` where the effect has a palette; each
/// followed by a blank line.
pub(crate) fn emit_draw_randomness(w: &mut Writer, ir: &EffectIr, draws: bool) {
    if draws {
        rng::emit_wgsl(w);
        w.blank();
    }
    if ir.render.palette.is_some() {
        crate::features::looks::tint::emit_palette_fn(w, ir.tint());
        w.blank();
    }
}
