//! The draw module's entry points: the vertex shader `vs`, which places each sprite's quad (or
//! triangle) from `sprite_at`, and the fragment shader `fs`, which shades it (the soft disc or
//! the texture's frame, lit by the lights for a lit look, faded near the scene for a soft one).

use super::{DrawShape, Primitive};
use crate::base::writer::{f32_lit, Writer};

/// The vertex shader `vs`: one instance per slot (or list entry), a quad (4-vertex strip) or a
/// triangle around the disc per sprite.
pub(super) fn emit_vertex(
    w: &mut Writer,
    shape: &DrawShape,
    oriented: bool,
    textured: bool,
    look: Option<&crate::features::looks::lit::Lit>,
) {
    let lit = look.is_some();
    let particle_shadow = look.is_some_and(|l| l.shadow_per_particle());
    w.block("struct Sprite", |w| {
        w.line("@builtin(position) clip: vec4<f32>,");
        w.line("@location(0) uv: vec2<f32>,");
        w.line("@location(1) color: vec4<f32>,");
        if textured {
            w.line("@location(2) @interpolate(flat) frame: u32,");
        }
        if lit {
            w.comment("A lit sprite's point in view space (render.lit).");
            w.line("@location(3) view_pos: vec3<f32>,");
        }
        if lit && oriented {
            w.comment(
                "Its basis (unit axes, facing) in view space: an upright sprite's is the view's.",
            );
            w.line("@location(4) @interpolate(flat) basis_x: vec3<f32>,");
            w.line("@location(5) @interpolate(flat) basis_y: vec3<f32>,");
            w.line("@location(6) @interpolate(flat) basis_z: vec3<f32>,");
        }
        if particle_shadow {
            w.comment("The shadowed light's verdict at the sprite's centre (shadow_at: Particle).");
            w.line("@location(7) @interpolate(flat) shadow: f32,");
        }
    });
    w.blank();
    w.line("@vertex");
    w.block(
        "fn vs(@builtin(vertex_index) vertex: u32, @builtin(instance_index) instance: u32) -> Sprite",
        |w| {
            w.line("var out: Sprite;");
            w.line("out.clip = HIDDEN;");
            w.line("out.uv = vec2<f32>(0.0);");
            w.line("out.color = vec4<f32>(0.0);");
            if textured {
                w.line("out.frame = 0u;");
            }
            if lit {
                w.line("out.view_pos = vec3<f32>(0.0);");
            }
            if lit && oriented {
                w.line("out.basis_x = vec3<f32>(1.0, 0.0, 0.0);");
                w.line("out.basis_y = vec3<f32>(0.0, 1.0, 0.0);");
                w.line("out.basis_z = vec3<f32>(0.0, 0.0, 1.0);");
            }
            if particle_shadow {
                w.line("out.shadow = 1.0;");
            }
            w.line("let s = sprite_at(instance);");
            w.block("if (!s.visible)", |w| w.line("return out;"));
            match shape.primitive {
                Primitive::Quad => {
                    w.comment("Strip corners (-1,-1), (1,-1), (-1,1), (1,1), offset in view space so the quad faces the camera.");
                    w.line("let corner = vec2<f32>(f32(vertex & 1u), f32((vertex >> 1u) & 1u)) * 2.0 - 1.0;");
                }
                Primitive::Triangle => {
                    w.comment("Corners (0, 2), (-sqrt 3, -1), (sqrt 3, -1): the triangle whose incircle is the disc.");
                    w.line(format!(
                        "let corner = select(vec2<f32>((f32(vertex) - 1.5) * {}, -1.0), vec2<f32>(0.0, 2.0), vertex == 0u);",
                        f32_lit(2.0 * 3f64.sqrt())
                    ));
                }
            }
            if oriented {
                w.line("out.clip = draw.proj * (s.center + vec4<f32>(corner.x * s.half_x + corner.y * s.half_y, 0.0));");
            } else {
                w.line("out.clip = draw.proj * (s.center + vec4<f32>(corner * (0.5 * s.size), 0.0, 0.0));");
            }
            w.line("out.uv = corner;");
            w.line("out.color = s.color;");
            if textured {
                w.line("out.frame = s.frame;");
            }
            if lit {
                let (ax, ay) = match oriented {
                    true => ("s.half_x", "s.half_y"),
                    false => (
                        "vec3<f32>(0.5 * s.size, 0.0, 0.0)",
                        "vec3<f32>(0.0, 0.5 * s.size, 0.0)",
                    ),
                };
                w.line(format!("out.view_pos = s.center.xyz + corner.x * {ax} + corner.y * {ay};"));
                if oriented {
                    w.line(format!("let basis = sprite_basis({ax}, {ay}, s.center.xyz);"));
                    w.line("out.basis_x = basis[0];");
                    w.line("out.basis_y = basis[1];");
                    w.line("out.basis_z = basis[2];");
                }
            }
            if particle_shadow {
                w.line("out.shadow = shadow_visibility(s.center.xyz);");
            }
            w.line("return out;");
        },
    );
}

/// The fragment shader `fs`: the texture's frame times the colour ([`crate::features::looks::texture`]), or a
/// soft round sprite, alpha a (1 − r²)², nothing at r >= 1.
/// With `soft` or `lit`, that colour comes from `shade`, and `fs` shades it by the lights
/// (`lit_color` of the pixel's `lit_light`; `lit` says too whether the quad is turned,
/// its basis then a varying) and fades its alpha by `soft_fade`.
pub(super) fn emit_fragment(
    w: &mut Writer,
    texture: Option<&crate::features::looks::texture::TextureIr>,
    soft: bool,
    lit: Option<(&crate::features::looks::lit::Lit, bool)>,
    (batched, blend): (bool, crate::features::looks::Blend),
) {
    // A batch's draw reads the camera through its private copy (see `wgsl::batch`).
    let take_view = |w: &mut Writer| {
        if batched {
            w.line("draw = draw_uniform;");
        }
    };
    // The blend's last word on what a fragment writes (`Blend::emit_blend_out`). Premultiplied:
    // the coverage is shaded at opacity 1 (`pin`) and the colour written times it.
    let premultiplied = blend == crate::features::looks::Blend::Premultiplied;
    let shaded = if premultiplied { "pin" } else { "in" };
    let out = |c: &str| match blend {
        crate::features::looks::Blend::Premultiplied => format!("premultiplied({c}, in.color.a)"),
        _ if blend.changes_output() => format!("blend_out({c})"),
        _ => c.to_string(),
    };
    if soft || lit.is_some() || blend.changes_output() || premultiplied {
        blend.emit_blend_out(w);
        if premultiplied {
            w.comment("Premultiplied blending (Blend): the colour c shaded at opacity 1 (its alpha the coverage), written times the coverage, with the opacity alpha times it.");
            w.block(
                "fn premultiplied(c: vec4<f32>, alpha: f32) -> vec4<f32>",
                |w| {
                    w.line("return vec4<f32>(c.rgb * c.a, alpha * c.a);");
                },
            );
        }
        w.block("fn shade(in: Sprite) -> vec4<f32>", |w| {
            emit_shade(w, texture)
        });
        w.blank();
        w.line("@fragment");
        w.block("fn fs(in: Sprite) -> @location(0) vec4<f32>", |w| {
            take_view(w);
            if premultiplied {
                w.line("var pin = in;");
                w.line("pin.color.a = 1.0;");
            }
            if let Some((look, oriented)) = lit {
                if !look.map_files().is_empty() {
                    w.comment("The lit maps first: their derivatives before any discard.");
                }
                w.line(format!("let maps = {};", look.maps_wgsl()));
                if look.shadow_per_particle() {
                    w.line("particle_shadow = in.shadow;");
                }
                w.comment("The texel before the light: its fetch is under way while the light is worked out (docs/performance.md, \"Lit sprites\").");
                w.line(format!("let unlit = shade({shaded});"));
                match oriented {
                    true => w.line("let basis = mat3x3<f32>(in.basis_x, in.basis_y, in.basis_z);"),
                    false => w.line("let basis = VIEW_BASIS;"),
                }
                w.line("let c = lit_color(unlit, lit_light(in.uv, basis, maps, in.view_pos));");
            } else {
                w.line(format!("let c = shade({shaded});"));
            }
            match soft {
                true => w.line(format!(
                    "return {};",
                    out("vec4<f32>(c.rgb, c.a * soft_fade(in.clip))")
                )),
                false => w.line(format!("return {};", out("c"))),
            }
        });
    } else {
        w.line("@fragment");
        w.block("fn fs(in: Sprite) -> @location(0) vec4<f32>", |w| {
            take_view(w);
            emit_shade(w, texture)
        });
    }
}

/// The sprite's colour at a fragment: the texture's frame times the colour, or the soft disc.
fn emit_shade(w: &mut Writer, texture: Option<&crate::features::looks::texture::TextureIr>) {
    if let Some(t) = texture {
        t.emit_fragment_body(w);
        return;
    }
    w.line("let r2 = dot(in.uv, in.uv);");
    w.block("if (r2 >= 1.0)", |w| w.line("discard;"));
    w.comment("Soft round falloff: full at the centre, zero at the rim.");
    w.line("let falloff = (1.0 - r2) * (1.0 - r2);");
    w.line("return vec4<f32>(in.color.rgb, in.color.a * falloff);");
}
