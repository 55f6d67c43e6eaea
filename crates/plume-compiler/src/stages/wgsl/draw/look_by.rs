//! The look's expressions in `sprite_at` (`render.color_by`, `alpha_by`, `size_by`, `color_t`:
//! `features/looks/by_expression.rs`): their arguments for the particle, and the factors.

use crate::base::writer::{f32_lit, Writer};
use crate::ir::EffectIr;
use crate::stages::passes::layout::{Attribute, Layout};

/// The arguments of the look's expression functions for the particle `sprite_at` holds (its
/// position, velocity, age, life, id and attributes), their `let`s written first; None without
/// expressions.
pub(super) fn emit_by_args(
    w: &mut Writer,
    ir: &EffectIr,
    layout: &Layout,
    stateless: bool,
) -> Option<String> {
    let by = &ir.render.by;
    if by == &Default::default() {
        return None;
    }
    let dt = f32_lit(ir.dt);
    let (id, v) = match stateless {
        true => ("e.id", "e.now.v".to_string()),
        false if !by.reads_velocity() => ("p.id", "vec3<f32>(0.0)".to_string()),
        false if layout.has(Attribute::Velocity) => ("p.id", "vec3<f32>(p.vx, p.vy, p.vz)".into()),
        false => (
            "p.id",
            format!("vec3<f32>(p.dx, p.dy, p.dz) * {}", f32_lit(1.0 / ir.h())),
        ),
    };
    if by.reads_age_or_life() {
        match stateless {
            true => {
                w.line(
                    "let by_life = select(0u, e.now.die_at - e.born + 1u, e.now.die_at != DEAD);",
                );
                w.line(format!(
                    "let by_age = vec2<f32>(f32(e.age), f32(by_life)) * {dt};"
                ));
            }
            false => w.line(format!("let by_age = vec2<f32>(age_steps(p)) * {dt};")),
        }
    } else {
        w.line("let by_age = vec2<f32>(0.0);");
    }
    let attrs = ir.attributes.args_wgsl(ir.kept_attributes(), |i| {
        let fields = layout.user_fields(i).unwrap_or(&[]);
        fields.iter().map(|f| format!("p.{f}")).collect()
    });
    // The frame's time: the steps done in f32 (exact below 2^24 steps) times dt.
    let t = match by.reads_time() {
        true => format!(", f32(draw.steps) * {dt}"),
        false => String::new(),
    };
    Some(format!("x, {v}, by_age.x, by_age.y, {id}{attrs}{t}"))
}

/// Multiplies `s.color`'s RGB and alpha and `s.size` (and `s.size_y`) inside `sprite_at` by the
/// look's expressions (`render.color_by`, `alpha_by`, `size_by`), given the particle as the
/// draw sees it; `args`: the expressions' arguments when [`emit_by_args`] already wrote them.
pub(super) fn emit_look_by(
    w: &mut Writer,
    ir: &EffectIr,
    layout: &Layout,
    stateless: bool,
    args: Option<String>,
) {
    let by = &ir.render.by;
    let Some(args) = args.or_else(|| emit_by_args(w, ir, layout, stateless)) else {
        return;
    };
    if by.color.is_some() {
        w.line(format!(
            "s.color = vec4<f32>(s.color.rgb * color_by({args}), s.color.a);"
        ));
    }
    if by.alpha.is_some() {
        w.line(format!("s.color.a = s.color.a * alpha_by({args});"));
    }
    if by.size.is_some() {
        w.line(format!("let by_size = size_by({args});"));
        w.line("s.size = s.size * by_size;");
        if ir.render.size_y.is_some() {
            w.line("s.size_y = s.size_y * by_size;");
        }
    }
    if let (Some(_), Some(t)) = (&by.frame, &ir.render.texture) {
        // frame_by's whole part (floored and clamped in the function), wrapped around.
        w.line(format!(
            "s.frame = u32(frame_by({args})) % {}u;",
            t.frames().max(1)
        ));
    }
}
