//! Lowering: a checked [`Effect`] becomes an [`EffectIr`] (f64 vectors, unit directions,
//! precomputed bases and grid steps, forces as terms). The integrator is still as written.

use glam::DVec3;

use crate::base::lifetime::LifetimeSteps;
use crate::base::rng::seed_mix;
use crate::features::accuracy::BudgetCamera;
use crate::features::forces::{safe_normalize, Force};
use crate::ir::{Basis, CameraIr, EffectIr, EmitterIr, KillIr, RenderIr, ShapeIr, VelocityIr};
use crate::stages::schema::{Collider, Effect, KillVolume, Shape, Velocity};

/// Lowers a checked effect. Call only after [`crate::stages::validate::check_effect`] found no errors.
pub fn lower(effect: &Effect) -> EffectIr {
    let scope = crate::features::forces::custom::Scope {
        params: &effect.params,
        dt: effect.dt,
        live: effect.live_params,
    };
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
            .map(|e| EmitterIr {
                burst: e.burst,
                rate: e.rate,
                shape: lower_shape(&e.shape),
                velocity: lower_velocity(&e.velocity),
                lifetime: e.lifetime.map(|r| (r.0, r.1)),
                lifetime_steps: e
                    .lifetime
                    .and_then(|r| LifetimeSteps::new(r.0, r.1, effect.dt)),
            })
            .collect(),
        terms: effect
            .forces
            .iter()
            .enumerate()
            .flat_map(|(i, f)| f.lower(i, effect.seed, scope))
            .collect(),
        field: effect.field.lower(),
        flock: effect.forces.iter().enumerate().find_map(|(i, f)| match f {
            Force::Flock(flock) => Some(flock.lower(i)),
            _ => None,
        }),
        max_speed: effect.max_speed,
        integrator: effect.integrator,
        integrator_reason: String::from("chosen in the file"),
        accuracy: effect.accuracy.as_ref().map(|a| {
            let mut lowered = a.lower();
            lowered.stand_in = effect.stand_in;
            lowered.host_camera = effect.accuracy_camera.map(|c| BudgetCamera {
                eye: c.eye.d(),
                target: c.target.d(),
                fov_y: c.fov_y,
            });
            lowered
        }),
        colliders: effect.collide.iter().map(Collider::lower).collect(),
        scene: effect.scene.iter().map(|m| m.lower()).collect(),
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
    // Custom terms estimate their stiffness over the emitters' region, now that it is known.
    let h = ir.h();
    let emitters = ir.emitters.clone();
    for term in &mut ir.terms {
        if let crate::features::forces::Term::Custom(c) = term {
            c.estimate_stiffness(&emitters, h);
        }
    }
    ir
}

fn lower_shape(s: &Shape) -> ShapeIr {
    match s {
        Shape::Point(p) => ShapeIr::Point(p.d()),
        Shape::Sphere { center, radius } => ShapeIr::Sphere {
            center: center.d(),
            radius: *radius,
        },
        Shape::Box { min, max } => ShapeIr::Box {
            min: min.d(),
            max: max.d(),
        },
        Shape::Disc {
            center,
            normal,
            radius,
        } => ShapeIr::Disc {
            center: center.d(),
            radius: *radius,
            basis: Basis::around(safe_normalize(normal.d())),
        },
        Shape::Grid { min, max, counts } => {
            let n = [counts.0, counts.1, counts.2];
            let (lo, hi) = (min.d().to_array(), max.d().to_array());
            let mut origin = [0.0; 3];
            let mut step = [0.0; 3];
            for a in 0..3 {
                if n[a] == 1 {
                    origin[a] = 0.5 * (lo[a] + hi[a]);
                } else {
                    origin[a] = lo[a];
                    step[a] = (hi[a] - lo[a]) / f64::from(n[a] - 1);
                }
            }
            ShapeIr::Grid {
                origin: DVec3::from_array(origin),
                step: DVec3::from_array(step),
                counts: n,
            }
        }
        Shape::Points(ps) => ShapeIr::Points(ps.iter().map(|p| p.d()).collect()),
        Shape::Mesh { surface, .. } => ShapeIr::Mesh(
            surface
                .clone()
                .expect("the checks refuse a Mesh shape whose file was not read"),
        ),
    }
}

fn lower_velocity(v: &Velocity) -> VelocityIr {
    match v {
        Velocity::Constant(v) => VelocityIr::Constant(v.d()),
        Velocity::Cone { axis, angle, speed } => {
            let axis = safe_normalize(axis.d());
            VelocityIr::Cone {
                axis,
                basis: Basis::around(axis),
                cos_angle: angle.to_radians().cos(),
                speed: (speed.0, speed.1),
            }
        }
        Velocity::Radial { speed } => VelocityIr::Radial {
            speed: (speed.0, speed.1),
        },
        Velocity::Normal { speed } => VelocityIr::Normal {
            speed: (speed.0, speed.1),
        },
    }
}
