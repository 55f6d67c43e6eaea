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

pub(crate) mod common;
mod look_by;
pub(crate) mod splat;
mod sprite_shaders;

use crate::base::writer::{f32_lit, u32_lit, Writer};
use crate::ir::EffectIr;
use crate::stages::integrators::emit_advance;
use crate::stages::passes::layout::{self, Attribute, Layout};
use crate::stages::wgsl::{emit_particle_struct, spawn, stateless};
use common::{
    emit_age_steps, emit_draw_randomness, emit_draw_view, emit_finite3, emit_gradients,
    emit_life_fraction, emit_load, emit_soft,
};
use splat::{emit_project, emit_project_quads, emit_quad_raster, emit_splat_declarations};
pub use splat::{
    splat_additive_lists, splat_affine_quads, splat_discs, splat_hdr_pitch, splat_light_ceiling,
    splat_light_constants, splat_mesh_refusal, splat_quad_words, splat_slices, HostDepthTest,
    SplatHost, SPLAT_FLAT_VIEW, SPLAT_HOST_DEPTH_BINDING, SPLAT_PARTIAL_BINDING,
    SPLAT_RASTER_BINDINGS, SPLAT_SLICES,
};
use sprite_shaders::{emit_fragment, emit_vertex};

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
    /// Whether the module also holds `project`, the compute renderer's first kernel (the
    /// runtime's `splat.rs` draws `plume render`'s images with it).
    pub splat: bool,
    /// Whether the compute renderer composites into an HDR image (the effect glows, or the top-level
    /// group of its graph does: every group then draws into the one HDR image).
    pub hdr: bool,
    /// Whether the fragment shader fades sprites near the host's depth buffer, bound at
    /// [`SCENE_DEPTH_BINDING`] (an effect with `render.soft`, drawn into a pass with depth).
    pub soft: bool,
    /// Set when the compute renderer draws for a host's image (the embedding API's compute draw): it
    /// keeps each pixel's coverage for the composite over the host's colour, and tests (and
    /// fades) against the host's depth. Needs `splat` and `hdr`.
    pub host: Option<SplatHost>,
    /// Whether the compute renderer's HDR light stops at a ceiling below f16's largest value (the
    /// top-level group's glow clamp, `render.glow.clamp`): its composite then tests each
    /// pixel's light against `splat_tiles.light_ceiling` once a mask word. Without a clamp
    /// the test would never pass, and it costs time in every HDR composite (docs/performance.md,
    /// "What bounds sparks and orbit").
    pub clamped: bool,
    /// Whether the module also holds the light kernels of `render.light`
    /// (`light_keys_pass`, `light_pick_pass`; the runtime draws them with an identity view
    /// and no slot list).
    pub particle_light: bool,
    /// Whether the compute renderer's composite may use subgroup operations: the adapter's subgroups are
    /// exactly 32 invocations wide (the runtime checks), and its line masks are then built by
    /// bit-matrix transposes, a subgroup each, instead of a thread per mask word.
    pub subgroups: bool,
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

/// Bindings of the compute renderer's `project` kernel: its view (image size, tiles, instance count), the
/// projected sprites (16 bytes each), each sprite's tile count, the same count again (the
/// runtime scans that copy in place into offsets), and the sprite's tile rectangle (computed
/// once here, so every later kernel agrees on it).
pub const SPLAT_BINDINGS: [u32; 5] = [20, 21, 22, 23, 24];

/// Side of the compute renderer's square screen tiles (pixels).
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
            hdr: false,
            soft: false,
            host: None,
            clamped: false,
            subgroups: false,
            particle_light: false,
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
    // The look's expressions read the age (in whole steps) as a spin does.
    let ages = spins || ir.render.by.reads_age_or_life();
    // Random draws: a stateless effect redraws its spawns; a stateful one its lifetimes.
    // The gradient noise: for the look's expressions, and a stateless effect's spawn
    // expressions, which its vertex shader evaluates again.
    let uses = |op| ir.render.by.uses(op) || (stateless && ir.emitters.iter().any(|e| e.uses(op)));
    let (noise, curl) = (
        uses(crate::expr::typed::Op1::Noise),
        uses(crate::expr::typed::Op1::Curl),
    );
    let draws = stateless
        || noise
        || curl
        || ir.render.palette.is_some()
        || ir.render.by.draws_random()
        || rotation.is_some()
        || flipbook.is_some_and(|t| t.draws_random())
        || ((life || flipbook.is_some() || ages)
            && ir.has_lifetimes()
            && !layout.has(Attribute::SpawnStep)
            && shared.is_some());
    if draws {
        w.line(format!("const SEED_MIX: u32 = {};", u32_lit(ir.seed_mix)));
    }
    if !stateless {
        w.line(format!("const VEC4S: u32 = {}u;", layout.vec4s()));
        if layout.half_motion {
            w.line(format!("const CAPACITY: u32 = {};", u32_lit(ir.capacity)));
        }
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
    if layout.batched {
        crate::stages::wgsl::batch::emit_draw_declarations(&mut w);
    } else {
        w.line("@group(0) @binding(0) var<uniform> draw: DrawView;");
    }
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
    // A mesh look drawn by the compute renderer has kernels of its own (`mesh_splat`).
    let splat_mesh = ir.render.mesh.as_ref().filter(|_| shape.splat);
    if shape.splat && splat_mesh.is_none() {
        w.blank();
        emit_splat_declarations(&mut w, ir, splat_discs(ir, shape.hdr), shape);
    }
    let soft = ir.render.soft.filter(|_| shape.soft);
    if let Some(distance) = soft {
        w.blank();
        emit_soft(&mut w, distance);
    }
    w.blank();
    emit_draw_randomness(&mut w, ir, draws);
    if noise || curl {
        crate::base::gradient_noise::emit_curl_helpers(&mut w);
        if noise {
            crate::base::gradient_noise::emit_noise_helper(&mut w);
        }
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
        if flipbook.is_some() || ages {
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
    if ir.render.by != Default::default() {
        w.blank();
        let kept = ir.kept_attributes();
        ir.render
            .by
            .emit_fns(&mut w, &ir.attributes.params_wgsl(kept));
    }
    if let Some(lit) = &ir.render.lit {
        w.blank();
        lit.emit_lit_color(&mut w, ir.render.turns_quad());
    }
    w.blank();
    emit_sprite_at(&mut w, ir, layout, shape, life);
    if let Some(t) = texture {
        w.blank();
        t.emit_texel_fn(&mut w);
    }
    if let Some(lit) = &ir.render.lit {
        lit.emit_map_fns(&mut w, shape.splat);
    }
    w.blank();
    emit_vertex(
        &mut w,
        shape,
        ir.render.turns_quad(),
        texture.is_some(),
        ir.render.lit.as_ref(),
    );
    w.blank();
    let lit_turned = ir.render.lit.as_ref().map(|l| (l, ir.render.turns_quad()));
    emit_fragment(
        &mut w,
        texture,
        soft.is_some(),
        lit_turned,
        (layout.batched, ir.render.blend),
    );
    // Ribbons read slots straight from their table: never through a slot list.
    if let Some(ribbon) = ir
        .render
        .ribbon
        .filter(|_| !shape.through_list && !shape.splat)
    {
        w.blank();
        ribbon.emit_draw(&mut w, ir.capacity, ir.render.lit.as_ref(), ir.render.blend);
    }
    if let Some(mesh) = ir.render.mesh.as_ref().filter(|_| !shape.splat) {
        w.blank();
        mesh.emit_draw(
            &mut w,
            ir.render.turns_quad(),
            ir.render.lit.as_ref(),
            ir.render.blend,
        );
    }
    if let Some(light) = ir.render.light.filter(|_| shape.particle_light) {
        w.blank();
        light.emit_kernels(&mut w, ir.capacity);
    }
    if let Some(mesh) = splat_mesh {
        w.blank();
        let look = (
            ir.render.turns_quad(),
            ir.render.lit.as_ref(),
            ir.render.blend,
        );
        let host = shape.host.map(splat::mesh_host);
        let image = (shape.hdr, host.as_ref());
        crate::features::looks::mesh_splat::emit_mesh_splat(&mut w, mesh, look, image);
    } else if shape.splat {
        w.blank();
        if splat_discs(ir, shape.hdr) {
            emit_project(&mut w, ir);
        } else {
            emit_project_quads(&mut w, ir, shape.host.is_some());
            w.blank();
            emit_quad_raster(&mut w, ir, shape);
        }
    }
    w.finish()
}

/// `sprite_at(instance)`: instance → slot (through `order` when there is one) → particle →
/// whether it shows, its centre in view space, its colour and size. Shared by the vertex shader
/// and the compute renderer's `project`, so both draw the same sprites.
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
        if layout.batched {
            crate::stages::wgsl::batch::emit_instance_view(w, layout);
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
        // The look's expressions' arguments, once, before the colour when `color_t` picks its t.
        let by_args = match ir.render.by.color_t.is_some() {
            true => look_by::emit_by_args(w, ir, layout, stateless),
            false => None,
        };
        let t = match by_args {
            Some(ref args) => {
                w.line(format!("let fc = color_t({args});"));
                "fc"
            }
            None => "f",
        };
        match tint {
            Some(tint) => w.line(format!("s.color = color_at({t}) * vec4<f32>({tint}, 1.0);")),
            None => w.line(format!("s.color = color_at({t});")),
        }
        w.line("s.size = size_at(f) * draw.size_scale;");
        if ir.render.size_y.is_some() {
            w.line("s.size_y = height_at(f) * draw.size_scale;");
        }
        look_by::emit_look_by(w, ir, layout, stateless, by_args);
        if ir.render.size_in == crate::features::looks::screen_size::SizeIn::Screen {
            crate::features::looks::screen_size::emit_scale(w, ir.render.size_y.is_some());
        }
        let height = match ir.render.size_y.is_some() {
            true => "s.size_y",
            false => "s.size",
        };
        w.comment("Nothing to see: blending a zero alpha or a zero-size quad changes no pixel.");
        let height_hidden = if ir.render.size_y.is_some() {
            " || s.size_y <= 0.0"
        } else {
            ""
        };
        w.block(
            format!(
                "if ({} || s.size <= 0.0{height_hidden})",
                ir.render.blend.hidden_wgsl()
            ),
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
