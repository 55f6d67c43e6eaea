//! Lowering: a checked [`EffectSpec`] becomes an [`EffectIr`] (f64 vectors, unit directions,
//! precomputed bases and grid steps, forces as terms). The integrator is still as written.

use crate::base::rng::seed_mix;
use crate::features::accuracy::BudgetCamera;
use crate::ir::{CameraIr, EffectIr, KillIr, RenderIr};
use crate::stages::schema::{Collider, EffectSpec, KillVolume};

/// What the effect's expressions may name: its params and dt, its named expressions
/// (`defines`, parsed from `effect.define`) and its attributes (`attrs`:
/// `features::attributes::names`).
pub(crate) fn names<'a>(
    effect: &'a EffectSpec,
    defines: &'a [crate::expr::define::Define],
    attrs: &'a [crate::expr::typed::AttrName],
) -> crate::expr::Names<'a> {
    crate::expr::Names {
        params: &effect.params,
        dt: effect.dt,
        live: effect.live_params,
        attrs,
        defines,
    }
}

/// Lowers a checked effect. Call only after [`crate::stages::validate::check_effect`] found no errors.
pub(crate) fn lower(effect: &EffectSpec) -> EffectIr {
    let (defines, _) = crate::expr::define::parse_all(&effect.define);
    let attrs =
        crate::features::attributes::names(&effect.attributes, names(effect, &defines, &[]));
    let scope = names(effect, &defines, &attrs);
    let mut ir = EffectIr {
        name: effect.name.clone(),
        capacity: effect.capacity,
        seed: effect.seed,
        seed_mix: seed_mix(effect.seed),
        dt: effect.dt,
        substeps: effect.substeps,
        emitters: effect
            .emitters
            .iter()
            .map(|e| e.lower(scope, seed_mix(effect.seed)))
            .collect(),
        terms: effect
            .forces
            .iter()
            .enumerate()
            .flat_map(|(i, f)| f.lower(i, effect.seed, scope))
            .collect(),
        field: effect.field.lower(),
        flock: effect
            .forces
            .iter()
            .enumerate()
            .find_map(|(i, f)| f.lower_flock(i)),
        attributes: crate::features::attributes::AttributesIr::lower(
            &effect.attributes,
            scope,
            seed_mix(effect.seed),
        ),
        max_speed: effect.max_speed,
        integrator: effect.integrator,
        integrator_reason: String::from("chosen in the file"),
        accuracy: effect.accuracy.as_ref().map(|a| {
            let mut lowered = a.lower();
            lowered.sample_burst = effect.sample_burst;
            lowered.host_camera = effect.accuracy_camera.map(|c| BudgetCamera {
                eye: c.eye.d(),
                target: c.target.d(),
                fov_y: c.fov_y,
            });
            lowered
        }),
        colliders: effect.collide.iter().map(Collider::lower).collect(),
        scene: effect.scene.iter().map(|m| m.lower()).collect(),
        lights: crate::features::lights::Lights::lower(&effect.lights),
        lights_named: !effect.lights.is_empty(),
        kills: effect
            .kill
            .iter()
            .map(|k| match k {
                KillVolume::InsideBox { min, max } => KillIr::InsideBox(min.d(), max.d()),
                KillVolume::OutsideBox { min, max } => KillIr::OutsideBox(min.d(), max.d()),
                KillVolume::InsideSphere { center, radius } => {
                    KillIr::InsideSphere(center.d(), *radius)
                }
                KillVolume::OutsideSphere { center, radius } => {
                    KillIr::OutsideSphere(center.d(), *radius)
                }
            })
            .collect(),
        sort: effect.sort,
        state: effect.state,
        stateless: None,
        state_reason: String::from("not decided yet"),
        placed: effect.placed,
        bursts: effect.bursts,
        live_params: if effect.live_params {
            effect
                .params
                .iter()
                .map(|(k, v)| (k.clone(), f64::from(*v as f32)))
                .collect()
        } else {
            Vec::new()
        },
        render: {
            let r = &effect.render;
            RenderIr {
                color: r
                    .color
                    .iter()
                    .map(|s| (s.0, [s.1 .0, s.1 .1, s.1 .2, s.1 .3]))
                    .collect(),
                size: r.size.iter().map(|s| (s.0, s.1)).collect(),
                size_y: r
                    .size_y
                    .as_ref()
                    .map(|stops| stops.iter().map(|s| (s.0, s.1)).collect()),
                alpha: r
                    .alpha
                    .as_ref()
                    .map(|stops| stops.iter().map(|s| (s.0, s.1)).collect()),
                blend: r.blend,
                background: r.background.d(),
                orient: crate::features::looks::orient::OrientIr::lower(&r.orient),
                size_in: r.size_in,
                // Loaded by `compile_effect`, which can report a file it cannot read.
                texture: None,
                rotation: r
                    .rotation
                    .as_ref()
                    .map(crate::features::looks::rotation::RotationIr::lower),
                soft: r.soft,
                glow: r.glow,
                trail: r
                    .trail
                    .as_ref()
                    .map(crate::features::looks::trail::TrailIr::lower),
                palette: r
                    .palette
                    .as_ref()
                    .map(|p| p.iter().map(|c| c.d()).collect()),
                by: crate::features::looks::by_expression::LookBy::lower(r.written_by(), scope),
                lit: r.lit.clone().map(|lit| crate::features::looks::lit::Lit {
                    shadows: effect.receive_shadows
                        || crate::features::lights::Lights::casts_shadow(&effect.lights),
                    ..lit
                }),
                // Loaded by `compile_effect`, as the texture.
                lit_maps: Vec::new(),
                light: r.light,
                ribbon: r.ribbon,
                mesh: None,
            }
        },
        bounds: effect.bounds.map(|b| (b.min.d(), b.max.d())),
        camera: CameraIr {
            eye: effect.camera.eye.d(),
            target: effect.camera.target.d(),
            fov_y: effect.camera.fov_y,
        },
        // Filled in by `crate::graph`, which knows the other groups.
        events: Vec::new(),
        event_inputs: Vec::new(),
    };
    // Each emitter draws its own gaps and burst counts (`SpawnTiming::draw`).
    for (i, e) in ir.emitters.iter_mut().enumerate() {
        e.timing.key = crate::base::rng::pcg(ir.seed_mix ^ (i as u32).wrapping_mul(0x9e37_79b9));
    }
    // Terms that need the emitters' region (a custom term's stiffness) learn it now.
    let h = ir.h();
    let emitters = ir.emitters.clone();
    for term in &mut ir.terms {
        term.fit_to_emitters(&emitters, h);
    }
    ir
}
