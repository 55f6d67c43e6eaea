//! The draw module: a vertex and a fragment shader per effect that draw its particles straight
//! from the GPU buffers, with no readback. It is a separate WGSL module from the compute one:
//! the compute module never contains render code, and the draw module only reads.
//!
//! The vertex shader pulls particle `slot` (the instance index, or the instance's entry of a
//! slot list: the depth order when `sort: true`) from the particle buffers, or, for a
//! stateless effect, computes it from the closed form with the same `evaluate_at` the compute
//! module uses, so a stateless effect is drawn with no state and no compute pass. It evaluates
//! the render section's colour and size over life, and expands a quad (a 4-vertex triangle
//! strip): camera-facing, or oriented as `render.orient` says ([`crate::features::looks::orient`]). Free slots, dead stateless slots, non-finite positions and fully
//! transparent or zero-size sprites become a degenerate quad outside the clip volume, which
//! rasterises nothing. The fragment shader draws the soft round sprite, or the texture's
//! flipbook frame when the effect has one ([`crate::features::looks::texture`]; the vertex shader picks the
//! frame from the particle's age).

use crate::base::lifetime::LifetimeSteps;
use crate::base::rng;
use crate::base::writer::{f32_lit, u32_lit, Writer};
use crate::ir::EffectIr;
use crate::stages::integrators::emit_advance;
use crate::stages::passes::layout::{self, Attribute, Layout};
use crate::stages::wgsl::{emit_particle_struct, particle_from_words, spawn, stateless};

/// How the runtime binds the particles for drawing. The compiled effect's own draw module is
/// [`DrawShape::single`]; the runtime asks for another shape when its device splits the state
/// across several buffers or when it draws through a compacted list of live slots.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DrawShape {
    /// Particle buffers the state is split into (stateful effects), all bound at once so that
    /// a depth order can reach any slot: bindings 2, 3, ... of the draw module.
    pub chunks: u32,
    /// Slots in each buffer but the last.
    pub chunk_slots: u32,
    /// Whether instance i draws slot `order[i]` (the depth order of a sorted effect, or a
    /// compacted list of live slots) instead of slot i.
    pub through_list: bool,
    /// The sprite's primitive: a quad (a 4-vertex strip) or one triangle around the disc.
    pub primitive: Primitive,
    /// Whether the module also holds `project`, the compute splat's first kernel (the
    /// runtime's `splat.rs` draws `plume render`'s images with it).
    pub splat: bool,
    /// Whether the fragment shader fades sprites near the host's depth buffer, bound at
    /// [`SCENE_DEPTH_BINDING`] (an effect with `render.soft`, drawn into a pass with depth).
    pub soft: bool,
}

/// Binding of the host's depth texture in a soft draw module.
pub const SCENE_DEPTH_BINDING: u32 = 32;

/// The geometry a sprite is drawn with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Primitive {
    /// A quad, two triangles as a 4-vertex strip: 4 vertices, 2 triangles, area 4 r².
    #[default]
    Quad,
    /// One equilateral triangle circumscribing the disc: 3 vertices, 1 triangle, area 5.2 r²
    /// (30% more fragments, all outside the disc discarded).
    Triangle,
}

impl Primitive {
    /// Vertices per sprite.
    pub fn vertices(self) -> u32 {
        match self {
            Primitive::Quad => 4,
            Primitive::Triangle => 3,
        }
    }
}

/// Bindings of the splat's `project` kernel: its view (image size, tiles, instance count), the
/// projected sprites (16 bytes each), each sprite's tile count, the same count again (the
/// runtime scans that copy in place into offsets), and the sprite's tile rectangle (computed
/// once here, so every later kernel agrees on it).
pub const SPLAT_BINDINGS: [u32; 5] = [20, 21, 22, 23, 24];

/// Side of the splat's square screen tiles (pixels).
pub const SPLAT_TILE: u32 = 16;

impl DrawShape {
    /// One particle buffer; through the depth order when the effect sorts.
    pub fn single(ir: &EffectIr) -> Self {
        Self {
            chunks: 1,
            chunk_slots: ir.capacity,
            through_list: ir.sort,
            primitive: Primitive::Quad,
            splat: false,
            soft: false,
        }
    }
}

/// Bytes of the `DrawView` uniform (binding 0): view and projection matrices (128), steps
/// done, the size scale and two words of padding.
pub const DRAW_VIEW_BYTES: u64 = 144;

/// Binding of the first particle buffer (stateful) or of the frame table (stateless).
pub const FIRST_DATA_BINDING: u32 = 2;

/// Emits the draw module of `ir` for particles bound as `shape` says.
pub fn emit(ir: &EffectIr, layout: &Layout, shape: &DrawShape) -> String {
    let mut w = Writer::new();
    let stateless = ir.stateless.is_some();
    w.comment(format!(
        "Plume effect {:?}: draw shaders, generated by plume-compiler {}; do not edit.",
        ir.name,
        env!("CARGO_PKG_VERSION")
    ));
    w.comment(if stateless {
        "Stateless: each vertex computes its particle from the closed form (no state, no compute pass)."
    } else {
        "Reads the particle state the compute module writes; writes nothing."
    });
    w.blank();
    w.line("const DEAD: u32 = 0xffffffffu;");
    let life = ir.render.varies_over_life() && ir.has_lifetimes();
    let shared = layout::shared_lifetime(ir);
    let texture = ir.render.texture.as_ref();
    let flipbook = texture.filter(|t| t.animated());
    let rotation = ir.render.rotation;
    let spins = rotation.is_some_and(|r| r.spins());
    // Random draws: a stateless effect redraws its spawns; a stateful one its lifetimes.
    let draws = stateless
        || ir.render.palette.is_some()
        || rotation.is_some()
        || flipbook.is_some_and(|t| t.draws_random())
        || ((life || flipbook.is_some() || spins)
            && ir.has_lifetimes()
            && !layout.has(Attribute::SpawnStep)
            && shared.is_some());
    if draws {
        w.line(format!("const SEED_MIX: u32 = {};", u32_lit(ir.seed_mix)));
    }
    if !stateless {
        w.line(format!("const VEC4S: u32 = {}u;", layout.vec4s()));
        if shape.chunks > 1 {
            w.line(format!(
                "const CHUNK_SLOTS: u32 = {};",
                u32_lit(shape.chunk_slots)
            ));
        }
    }
    w.comment("Where a hidden sprite goes: all four corners at one point outside the clip volume.");
    w.line("const HIDDEN: vec4<f32> = vec4<f32>(2.0, 2.0, 2.0, 1.0);");
    w.blank();
    emit_draw_view(&mut w);
    w.blank();
    if stateless {
        w.block("struct Spawned", |w| {
            w.line("x: vec3<f32>,");
            w.line("v: vec3<f32>,");
            w.line("die_at: u32,");
        });
        w.blank();
        stateless::emit_declarations(&mut w);
    } else {
        emit_particle_struct(&mut w, layout);
    }
    w.blank();
    w.line("@group(0) @binding(0) var<uniform> draw: DrawView;");
    if shape.through_list {
        w.line("@group(0) @binding(1) var<storage, read> order: array<u32>;");
    }
    if stateless {
        w.line(format!(
            "@group(0) @binding({FIRST_DATA_BINDING}) var<storage, read> frame: Frame;"
        ));
    } else {
        for c in 0..shape.chunks.max(1) {
            w.line(format!(
                "@group(0) @binding({}) var<storage, read> particles_{c}: array<vec4<u32>>;",
                FIRST_DATA_BINDING + c
            ));
        }
    }
    if let Some(t) = texture {
        w.blank();
        t.emit_declarations(&mut w);
    }
    if shape.splat {
        w.blank();
        emit_splat_declarations(&mut w);
    }
    let soft = ir.render.soft.filter(|_| shape.soft);
    if let Some(distance) = soft {
        w.blank();
        emit_soft(&mut w, distance);
    }
    w.blank();
    if draws {
        rng::emit_wgsl(&mut w);
        w.blank();
    }
    if ir.render.palette.is_some() {
        crate::features::looks::tint::emit_palette_fn(&mut w, ir.tint());
        w.blank();
    }
    if stateless {
        spawn::emit_emitter_fns(&mut w, ir);
        emit_advance(&mut w, ir);
        w.blank();
        stateless::emit_evaluate_at(&mut w, ir);
    } else {
        emit_load(&mut w, layout, shape);
        if life {
            w.blank();
            emit_life_fraction(&mut w, layout, shared);
        }
        if flipbook.is_some() || spins {
            w.blank();
            emit_age_steps(&mut w, layout, shared);
        }
    }
    if let Some(t) = flipbook {
        w.blank();
        t.emit_frame_fn(&mut w, ir.dt);
    }
    if let Some(r) = rotation {
        w.blank();
        r.emit_angle_fn(&mut w, ir.dt);
    }
    w.blank();
    emit_gradients(&mut w, ir);
    w.blank();
    emit_sprite_at(&mut w, ir, layout, shape, life);
    w.blank();
    emit_vertex(&mut w, shape, ir.render.turns_quad(), texture.is_some());
    w.blank();
    emit_fragment(&mut w, texture, soft.is_some());
    if shape.splat {
        w.blank();
        emit_project(&mut w);
    }
    w.finish()
}

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
    w.block("fn load_particle(slot: u32) -> Particle", |w| {
        if shape.chunks <= 1 {
            if n > 1 {
                w.line("let slots = arrayLength(&particles_0) / VEC4S;");
            }
            for k in 0..n {
                w.line(format!(
                    "let w{k} = particles_0[{}];",
                    crate::base::kernel::word_index(k, "slot", "slots")
                ));
            }
        } else {
            w.line("let c = slot / CHUNK_SLOTS;");
            w.line("let i = slot - c * CHUNK_SLOTS;");
            for k in 0..n {
                w.line(format!("var w{k}: vec4<u32>;"));
            }
            w.block("switch c", |w| {
                for c in 0..shape.chunks {
                    let label = if c + 1 == shape.chunks {
                        format!("case {c}u, default")
                    } else {
                        format!("case {c}u")
                    };
                    w.block(label, |w| {
                        if n > 1 {
                            w.line(format!("let slots = arrayLength(&particles_{c}) / VEC4S;"));
                        }
                        for k in 0..n {
                            w.line(format!(
                                "w{k} = particles_{c}[{}];",
                                crate::base::kernel::word_index(k, "i", "slots")
                            ));
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
fn emit_age_steps(w: &mut Writer, layout: &Layout, shared: Option<LifetimeSteps>) {
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

/// `sprite_at(instance)`: instance → slot (through `order` when there is one) → particle →
/// whether it shows, its centre in view space, its colour and size. Shared by the vertex shader
/// and the splat's `project`, so both draw the same sprites.
fn emit_sprite_at(w: &mut Writer, ir: &EffectIr, layout: &Layout, shape: &DrawShape, life: bool) {
    let stateless = ir.stateless.is_some();
    w.comment(
        "A particle as a sprite: whether it shows, its centre in view space, colour and size.",
    );
    let oriented = ir.render.turns_quad();
    w.block("struct SpriteAt", |w| {
        w.line("visible: bool,");
        w.line("center: vec4<f32>,");
        w.line("color: vec4<f32>,");
        w.line("size: f32,");
        if ir.render.size_y.is_some() {
            w.comment("The height, when it has a curve of its own (render.size_y).");
            w.line("size_y: f32,");
        }
        if ir.render.texture.is_some() {
            w.comment("The flipbook frame shown.");
            w.line("frame: u32,");
        }
        if oriented {
            w.comment("The quad's half axes in view space (render.orient, render.rotation).");
            w.line("half_x: vec3<f32>,");
            w.line("half_y: vec3<f32>,");
        }
    });
    w.blank();
    emit_finite3(w);
    w.blank();
    w.block("fn sprite_at(instance: u32) -> SpriteAt", |w| {
        w.line("var s: SpriteAt;");
        w.line("s.visible = false;");
        if shape.through_list {
            w.line("let slot = order[instance];");
        } else {
            w.line("let slot = instance;");
        }
        if stateless {
            w.line("let e = evaluate_at(slot);");
            w.block("if (!e.alive)", |w| w.line("return s;"));
            w.line("let x = e.now.x;");
        } else {
            w.line("let p = load_particle(slot);");
            w.block("if (p.id == DEAD)", |w| w.line("return s;"));
            w.line("let x = vec3<f32>(p.px, p.py, p.pz);");
        }
        w.block("if (!finite3(x))", |w| w.line("return s;"));
        match (life, stateless) {
            (false, _) => w.line("let f = 0.0;"),
            (true, false) => w.line("let f = life_fraction(p);"),
            (true, true) => {
                w.comment("Whole steps lived over whole steps of life.");
                w.line("var f = 0.0;");
                w.block("if (e.now.die_at != DEAD)", |w| {
                    w.line("let life = e.now.die_at - e.born + 1u;");
                    w.line("f = clamp(f32(e.age) / f32(life), 0.0, 1.0);");
                });
            }
        }
        match ir.render.texture.as_ref().map(|t| t.animated()) {
            None => {}
            Some(false) => w.line("s.frame = 0u;"),
            Some(true) if stateless => {
                w.line("let life = select(0u, e.now.die_at - e.born + 1u, e.now.die_at != DEAD);");
                w.line("s.frame = sprite_frame(e.id, e.age, life);");
            }
            Some(true) => {
                w.line("let age = age_steps(p);");
                w.line("s.frame = sprite_frame(p.id, age.x, age.y);");
            }
        }
        let tint = if stateless {
            crate::features::looks::tint::particle_wgsl(ir.tint(), "e", "e.id")
        } else {
            crate::features::looks::tint::particle_wgsl(ir.tint(), "p", "p.id")
        };
        match tint {
            Some(tint) => w.line(format!("s.color = color_at(f) * vec4<f32>({tint}, 1.0);")),
            None => w.line("s.color = color_at(f);"),
        }
        w.line("s.size = size_at(f) * draw.size_scale;");
        let height = if ir.render.size_y.is_some() {
            w.line("s.size_y = height_at(f) * draw.size_scale;");
            "s.size_y"
        } else {
            "s.size"
        };
        w.comment("Nothing to see: blending a zero alpha or a zero-size quad changes no pixel.");
        let height_hidden = if ir.render.size_y.is_some() {
            " || s.size_y <= 0.0"
        } else {
            ""
        };
        w.block(
            format!("if (s.color.a <= 0.0 || s.size <= 0.0{height_hidden})"),
            |w| w.line("return s;"),
        );
        w.line("s.center = draw.view * vec4<f32>(x, 1.0);");
        if oriented {
            if ir.render.orient.needs_velocity() {
                if stateless {
                    w.line("let vel = e.now.v;");
                } else if layout.has(Attribute::Velocity) {
                    w.line("let vel = vec3<f32>(p.vx, p.vy, p.vz);");
                } else {
                    w.comment("Verlet stores the displacement over one substep h: v = d / h.");
                    w.line(format!(
                        "let vel = vec3<f32>(p.dx, p.dy, p.dz) * {};",
                        f32_lit(1.0 / ir.h())
                    ));
                }
            }
            ir.render.orient.emit_half_axes(w, height);
            if ir.render.rotation.is_some() {
                match (stateless, ir.render.rotation.is_some_and(|r| r.spins())) {
                    (_, false) => w.line("let lived = 0u;"),
                    (true, true) => w.line("let lived = e.age;"),
                    (false, true) => w.line("let lived = age_steps(p).x;"),
                }
                w.line(format!(
                    "let angle = sprite_angle({}, lived);",
                    if stateless { "e.id" } else { "p.id" }
                ));
                crate::features::looks::rotation::RotationIr::emit_turn(w);
            }
        }
        w.line("s.visible = true;");
        w.line("return s;");
    });
}

/// The vertex shader `vs`: one instance per slot (or list entry), a quad (4-vertex strip) or a
/// triangle around the disc per sprite.
fn emit_vertex(w: &mut Writer, shape: &DrawShape, oriented: bool, textured: bool) {
    w.block("struct Sprite", |w| {
        w.line("@builtin(position) clip: vec4<f32>,");
        w.line("@location(0) uv: vec2<f32>,");
        w.line("@location(1) color: vec4<f32>,");
        if textured {
            w.line("@location(2) @interpolate(flat) frame: u32,");
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
            w.line("return out;");
        },
    );
}

/// The splat's declarations: its view and output buffers (bindings [`SPLAT_BINDINGS`]).
fn emit_splat_declarations(w: &mut Writer) {
    w.comment("The compute splat's image: size in pixels, tiles, and the instances to project.");
    w.block("struct SplatView", |w| {
        w.line("width: u32,");
        w.line("height: u32,");
        w.line("tiles_x: u32,");
        w.line("count: u32,");
    });
    let [view, splats, counts, offsets, boxes] = SPLAT_BINDINGS;
    w.line(format!(
        "@group(0) @binding({view}) var<uniform> splat_view: SplatView;"
    ));
    w.line(format!(
        "@group(0) @binding({splats}) var<storage, read_write> splats: array<vec4<u32>>;"
    ));
    w.line(format!(
        "@group(0) @binding({counts}) var<storage, read_write> tile_counts: array<u32>;"
    ));
    w.line(format!(
        "@group(0) @binding({offsets}) var<storage, read_write> tile_offsets: array<u32>;"
    ));
    w.line(format!(
        "@group(0) @binding({boxes}) var<storage, read_write> tile_boxes: array<vec2<u32>>;"
    ));
}

/// `project`: the splat's first kernel. Instance k's sprite as the rasteriser would place it,
/// in 16 bytes: its centre in pixels (two f32), its half extent in pixels and its alpha (two
/// f16), its RGB (three 10-bit unorms); and how many screen tiles its pixels touch (0 when
/// hidden, clipped, or covering no pixel centre). Pixels are square (the projection's aspect is
/// the image's), so one extent serves both axes.
fn emit_project(w: &mut Writer) {
    w.line("@compute @workgroup_size(256)");
    w.block(
        "fn project(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            w.line("let k = gid.x + gid.y * groups.x * 256u;");
            w.block("if (k >= splat_view.count)", |w| w.line("return;"));
            w.line("var tiles = 0u;");
            w.line("let s = sprite_at(k);");
            w.block("if (s.visible)", |w| {
                w.line("let clip = draw.proj * s.center;");
                w.comment("All corners share z and w: the rasteriser clips the whole sprite or none of it.");
                w.block("if (clip.w > 0.0 && clip.z >= 0.0 && clip.z <= clip.w)", |w| {
                    w.line("let h = 0.5 * s.size;");
                    w.line("let size = vec2<f32>(f32(splat_view.width), f32(splat_view.height));");
                    w.line("let extent = abs((draw.proj * vec4<f32>(h, 0.0, 0.0, 0.0)).x / clip.w) * 0.5 * size.x;");
                    w.comment("The extent as stored (f16), as the tile kernels see it.");
                    w.line("let packed = pack2x16float(vec2<f32>(extent, s.color.a));");
                    w.line("let e = unpack2x16float(packed).x;");
                    w.line("let c = vec2<f32>(clip.x / clip.w * 0.5 + 0.5, 0.5 - clip.y / clip.w * 0.5) * size;");
                    w.comment("Pixels whose centres (i + 0.5) lie strictly inside the sprite.");
                    w.line("let lo = max(ceil(c - e - 0.5), vec2<f32>(0.0));");
                    w.line("let hi = min(floor(c + e - 0.5), size - 1.0);");
                    w.block("if (all(lo <= hi))", |w| {
                        w.line(format!(
                            "let t0 = vec2<u32>(lo) / {SPLAT_TILE}u;"
                        ));
                        w.line(format!(
                            "let t1 = vec2<u32>(hi) / {SPLAT_TILE}u;"
                        ));
                        w.line("tiles = (t1.x - t0.x + 1u) * (t1.y - t0.y + 1u);");
                        w.line("tile_boxes[k] = vec2<u32>(t0.x | (t0.y << 16u), t1.x | (t1.y << 16u));");
                        w.line("let rgb = vec3<u32>(round(clamp(s.color.rgb, vec3<f32>(0.0), vec3<f32>(1.0)) * 1023.0));");
                        w.line("splats[k] = vec4<u32>(bitcast<vec2<u32>>(c), packed, rgb.x | (rgb.y << 10u) | (rgb.z << 20u));");
                    });
                });
            });
            w.line("tile_counts[k] = tiles;");
            w.line("tile_offsets[k] = tiles;");
        },
    );
}

/// The fragment shader `fs`: the texture's frame times the colour ([`crate::features::looks::texture`]), or a
/// soft round sprite, alpha a (1 − r²)², nothing at r >= 1.
/// With `soft`, that colour comes from `shade` and `fs` fades its alpha by `soft_fade`.
fn emit_fragment(
    w: &mut Writer,
    texture: Option<&crate::features::looks::texture::TextureIr>,
    soft: bool,
) {
    if soft {
        w.block("fn shade(in: Sprite) -> vec4<f32>", |w| {
            emit_shade(w, texture)
        });
        w.blank();
        w.line("@fragment");
        w.block("fn fs(in: Sprite) -> @location(0) vec4<f32>", |w| {
            w.line("let c = shade(in);");
            w.line("return vec4<f32>(c.rgb, c.a * soft_fade(in.clip));");
        });
    } else {
        w.line("@fragment");
        w.block("fn fs(in: Sprite) -> @location(0) vec4<f32>", |w| {
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
    w.blank();
    w.block("fn soft_fade(frag: vec4<f32>) -> f32", |w| {
        w.comment("Clamped to the texture: a smaller one (the placeholder before the host binds its own) stays in bounds.");
        w.line("let pixel = min(vec2<u32>(frag.xy), textureDimensions(scene_depth) - vec2<u32>(1u));");
        w.line("let scene = textureLoad(scene_depth, pixel, 0).r;");
        w.line("let gap = view_distance(scene) - view_distance(frag.z);");
        w.line("return clamp(gap / SOFT_DISTANCE, 0.0, 1.0);");
    });
}
