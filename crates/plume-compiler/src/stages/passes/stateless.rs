//! The state pass: decides whether particles need state at all. With the Exact integrator a
//! particle's position and velocity are closed-form functions of its spawn draws and its age
//! (the stateless particle system; Latta's closed-form particles), so when nothing else needs
//! memory between steps the compiler emits one `evaluate` kernel that computes every live
//! particle from (id, spawn step, steps done) and keeps 0 bytes of state per particle.
//!
//! Spawning becomes bookkeeping: the CPU's schedule already knows which ids were requested at
//! which step, so it hands the kernel a table of *segments* (one per step and emitter that
//! spawned something and may still have live particles), and each thread finds its segment.
//!
//! What needs state, and so keeps the stateful kernels:
//! - any integrator but Exact (their result depends on every earlier step);
//! - kill volumes (whether a particle died depends on every earlier position);
//! - a capacity that could drop spawns (which ids got a slot depends on the past);
//! - a window of live spawning steps too long for the segment table.
//!
//! Planes, max_speed and Flock already rule out Exact. A depth sort works on the evaluated view.

use crate::base::check::Checker;
use crate::base::path::ValuePath;
pub(crate) use crate::ir::stateless::{StatelessIr, MAX_SEGMENTS};
pub use crate::ir::stateless::{FIRE_BATCH_STEPS, FRAME_HEADER_BYTES, SEGMENT_BYTES};
use crate::ir::EffectIr;
use crate::stages::schema::{Integrator, State};

/// The bounds of emitter `e`: (most alive at once, most live segments, its longest life in
/// steps), or why it has none.
fn emitter_bounds(ir: &EffectIr, e: usize) -> Result<(u64, u64, Option<u32>), String> {
    let em = &ir.emitters[e];
    let lives = em.lifetime_steps.map(|l| l.first + l.span - 1);
    // Bursts whose particles may be alive at once, each a segment of its own.
    let bursts = match em.burst {
        0 => 0,
        _ => em.timing.bursts_alive(lives).ok_or_else(|| {
            format!(
                "emitters[{e}] repeats its burst for ever and its particles never die, so they would outgrow any capacity and be dropped"
            )
        })?,
    };
    let burst = u64::from(em.burst).saturating_mul(bursts);
    if em.rate <= 0.0 {
        return Ok((burst, bursts, lives));
    }
    let Some(window) = lives else {
        return Err(format!(
            "emitters[{e}] spawns at a rate and its particles never die, so they would outgrow any capacity and be dropped"
        ));
    };
    // Spawns in any `window` consecutive steps: at most ceil(rate dt window), plus one for the
    // f64 rounding of the carried fraction.
    let per_window = (em.rate * ir.dt * f64::from(window)).floor();
    if !per_window.is_finite() || per_window >= 1e18 {
        return Err(format!(
            "emitters[{e}] spawns more particles over a lifetime than can be counted"
        ));
    }
    let spawns = per_window as u64 + 2;
    Ok((
        burst.saturating_add(spawns),
        // A step spawns one segment, bursts and rate alike: at most one a step.
        u64::from(window).min(match em.timing.is_plain() {
            // The burst at step 0 is within the rounding's margin of `spawns`.
            true => spawns,
            false => spawns.saturating_add(bursts),
        }),
        lives,
    ))
}

/// Why the effect needs state, naming the cause and its path, or the stateless plan.
pub(crate) fn plan(ir: &EffectIr) -> Result<StatelessIr, (String, ValuePath)> {
    if ir.integrator != Integrator::Exact {
        return Err((
            format!(
                "the {} integrator carries each particle's state from step to step (only Exact has a closed form)",
                ir.integrator.name()
            ),
            ValuePath::root().field("integrator"),
        ));
    }
    if let Some((_, a)) = ir.attributes.iter_kept(ir.kept_attributes()).next() {
        return Err((
            format!(
                "attributes.{} is carried by each particle from step to step",
                a.name
            ),
            ValuePath::root().field("attributes").field(&a.name),
        ));
    }
    if let Some(e) = ir.emitters.iter().position(|em| em.age_steps.is_some()) {
        return Err((
            format!("emitters[{e}].age starts each particle at an age of its own, which the closed form's segments do not track"),
            ValuePath::root().field("emitters").index(e).field("age"),
        ));
    }
    if ir.render.light.is_some() {
        return Err((
            "render.light picks its brightest particles from the particle buffers".into(),
            ValuePath::root().field("render").field("light"),
        ));
    }
    if ir.render.ribbon.is_some() {
        return Err((
            "render.ribbon joins particles through the slots they hold".into(),
            ValuePath::root().field("render").field("ribbon"),
        ));
    }
    if ir.render.trail.is_some() {
        return Err((
            "render.trail keeps each particle's past positions".into(),
            ValuePath::root().field("render").field("trail"),
        ));
    }
    if !ir.event_inputs.is_empty() {
        return Err((
            "the group is fed by events, whose spawns only the GPU counts".into(),
            ValuePath::root().field("state"),
        ));
    }
    if !ir.kills.is_empty() {
        return Err((
            "kill[0] decides deaths from every earlier position".into(),
            ValuePath::root().field("kill").index(0),
        ));
    }
    if ir.placed {
        return Err((
            "it is placed in a host's world at run time (world space): where particles start depends on where the emitter was".into(),
            ValuePath::root().field("state"),
        ));
    }
    if let Some(e) = ir
        .emitters
        .iter()
        .position(|em| matches!(em.shape, crate::ir::ShapeIr::Mesh(_)))
    {
        return Err((
            format!("emitters[{e}] spawns on a mesh, which stateless effects do not do yet"),
            ValuePath::root().field("emitters").index(e).field("shape"),
        ));
    }
    if ir.bursts {
        return Err((
            "it takes bursts fired from code at run time: when they spawn is not a function of (id, age)".into(),
            ValuePath::root().field("state"),
        ));
    }
    if let Some(e) = ir
        .emitters
        .iter()
        .position(|em| em.burst_range.is_some() || em.timing.every_steps.is_some())
    {
        let field = match ir.emitters[e].burst_range {
            Some(_) => "burst",
            None => "every",
        };
        return Err((
            format!("emitters[{e}].{field} is drawn anew for each burst, which the closed form's segments do not track"),
            ValuePath::root().field("emitters").index(e).field(field),
        ));
    }
    if let Some(e) = ir.emitters.iter().position(|em| em.params != (None, None)) {
        let field = match ir.emitters[e].params.0 {
            Some(_) => "burst",
            None => "rate",
        };
        return Err((
            format!("emitters[{e}].{field} follows a param changed at run time: how many spawn is not known when the effect compiles"),
            ValuePath::root().field("emitters").index(e).field(field),
        ));
    }
    let (mut peak, mut segments, mut lives) = (0u64, 0u64, Vec::new());
    for e in 0..ir.emitters.len() {
        let path = ValuePath::root().field("emitters").index(e);
        let (alive, segs, life) = emitter_bounds(ir, e).map_err(|why| (why, path.field("rate")))?;
        peak = peak.saturating_add(alive);
        segments = segments.saturating_add(segs);
        lives.push(life);
    }
    if peak > u64::from(ir.capacity) {
        return Err((
            format!(
                "capacity {} may drop spawns (up to {peak} alive at once), and which spawns get a slot depends on the past",
                ir.capacity
            ),
            ValuePath::root().field("capacity"),
        ));
    }
    if segments > MAX_SEGMENTS {
        return Err((
            format!(
                "particles stay alive over {segments} spawning steps, more than the {MAX_SEGMENTS} the segment table holds"
            ),
            ValuePath::root().field("emitters"),
        ));
    }
    Ok(StatelessIr {
        lives,
        max_segments: segments,
        peak,
    })
}

/// Decides `ir.stateless` from the file's `state` and records why.
pub(crate) fn decide(ir: &mut EffectIr) -> Result<(), Checker> {
    match (ir.state, plan(ir)) {
        (State::Stateful, _) => {
            ir.stateless = None;
            ir.state_reason = "state: Stateful in the file".into();
        }
        (State::Auto | State::Stateless, Ok(p)) => {
            ir.state_reason = format!(
                "{}: the closed form of (id, age); at most {} alive, spawned at up to {} (step, emitter) pairs still tracked",
                if ir.state == State::Auto {
                    "Auto"
                } else {
                    "chosen in the file"
                },
                p.peak,
                p.max_segments
            );
            ir.stateless = Some(p);
        }
        (State::Auto, Err((why, _))) => {
            ir.stateless = None;
            ir.state_reason = format!("Auto: {why}");
        }
        (State::Stateless, Err((why, _))) => {
            let mut c = Checker::default();
            c.error(
                &ValuePath::root().field("state"),
                format!(
                    "Stateless is not possible because {why}; it needs the Exact integrator, no kill volumes, no render.trail or render.ribbon, no events fed in, and a capacity no spawn can overflow (use Auto)"
                ),
            );
            return Err(c);
        }
    }
    Ok(())
}
