//! What a batched module adds to the kernels (`crate::batch`): the instance each kernel takes
//! from its dispatch's z, that instance's row of the step parameters, counters and free list
//! segment, and the per-instance initial state.

use crate::base::kernel::emit_thread_index;
use crate::base::writer::Writer;
use crate::stages::passes::layout::Layout;

/// A batched module's step parameters: every instance's row of this step, and the private
/// copy of this kernel's instance's row under the name every other kernel reads (`params`),
/// with the instance itself (`inst`, from the dispatch's z: [`emit_instance`]).
pub(crate) fn emit_declarations(w: &mut Writer, binding: u32) {
    w.line(format!(
        "@group(0) @binding({binding}) var<storage, read> step_params: array<StepParams>;"
    ));
    w.comment("This kernel's batched instance and its row of the step's parameters.");
    w.line("var<private> inst: u32;");
    w.line("var<private> params: StepParams;");
}

/// A batched module's entry point starts by taking its instance (`inst_expr`) and that
/// instance's step parameters; other modules' entry points need neither.
pub(crate) fn emit_instance(w: &mut Writer, layout: &Layout, inst_expr: &str) {
    if layout.batched {
        w.line(format!("inst = {inst_expr};"));
        w.line("params = step_params[inst];");
    }
}

/// The counters of the kernel's instance: the effect's, or a batched instance's entry.
pub fn counters(layout: &Layout) -> &'static str {
    match layout.batched {
        true => "counters[inst]",
        false => "counters",
    }
}

/// Where the kernel's instance's free list begins, as the start of an index expression: a
/// batched instance's segment is `CAPACITY` entries at `inst * CAPACITY`.
pub(crate) fn free_list_base(layout: &Layout) -> &'static str {
    match layout.batched {
        true => "inst * CAPACITY + ",
        false => "",
    }
}

/// A batched module's initial state, an instance at a time: `init` frees every slot of the
/// instance in z of its dispatch and fills its free list and counters (every instance of a
/// new batch at once); `init_last` the same for the last z of its dispatch only (an instance
/// that starts again or anew: a dispatch of k + 1 layers inits instance k, the others return
/// at once). Global slot of instance n's local slot l: n · CAPACITY + l.
pub(crate) fn emit_init(w: &mut Writer) {
    for (name, inst) in [("init", "gid.z"), ("init_last", "groups.z - 1u")] {
        w.line("@compute @workgroup_size(WORKGROUP)");
        w.block(
            format!("fn {name}(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)"),
            |w| {
                if name == "init_last" {
                    w.block(format!("if (gid.z != {inst})"), |w| w.line("return;"));
                }
                w.line("let n = gid.z;");
                emit_thread_index(w, "local", Some("CAPACITY"));
                w.line("let slot = n * CAPACITY + local;");
                w.line("mark_free(slot);");
                w.comment("Pops take from the top: the first spawns get the instance's lowest slots.");
                w.line("free_list[slot] = n * CAPACITY + CAPACITY - 1u - local;");
                w.block("if (local == 0u)", |w| {
                    w.line("atomicStore(&counters[n].free_count, CAPACITY);");
                    w.line("counters[n].spawn_base = 0u;");
                    w.line("counters[n].spawn_count = 0u;");
                    w.line("counters[n].spawned = 0u;");
                    w.line("counters[n].dropped = 0u;");
                    w.line("atomicStore(&counters[n].died, 0u);");
                });
            },
        );
    }
}

/// Where the draw module reads each batched instance's transform (its own space to the
/// world; identity for an instance in world space).
pub const INSTANCE_MODELS_BINDING: u32 = 35;

/// A batched draw module's camera: the uniform the runtime writes (`draw_uniform`), each
/// instance's transform, and the private copy every other line reads as `draw`, whose view
/// [`emit_instance_view`] turns by the sprite's instance (the fragment shader takes it as
/// written: it reads the projection, never the view).
pub(crate) fn emit_draw_declarations(w: &mut Writer) {
    w.line("@group(0) @binding(0) var<uniform> draw_uniform: DrawView;");
    w.line(format!(
        "@group(0) @binding({INSTANCE_MODELS_BINDING}) var<storage, read> instance_models: array<mat4x4<f32>>;"
    ));
    w.comment(
        "The camera as this sprite's instance sees it: the view times the instance's transform.",
    );
    w.line("var<private> draw: DrawView;");
}

/// In a batched draw's `sprite_at`, once `slot` is known: the camera through the transform of
/// the instance that owns the slot.
pub(crate) fn emit_instance_view(w: &mut Writer, layout: &Layout) {
    w.line("draw = draw_uniform;");
    w.line(format!(
        "draw.view = draw_uniform.view * instance_models[slot / {}u];",
        layout.instance_slots
    ));
}
