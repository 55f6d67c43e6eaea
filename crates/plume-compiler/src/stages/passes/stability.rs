//! Stability analysis: warnings with numbers, from the linear stability limits of each
//! integrator (see docs/effect-format.md, "Stability"). Limits, for h = dt / substeps:
//!
//! | integrator        | drag k*h      | oscillation ω*h (attractor, vortex)           |
//! |-------------------|---------------|-----------------------------------------------|
//! | Euler             | < 2 (≤ 1 no overshoot) | always grows: × sqrt(1 + (ωh)²) per step |
//! | SemiImplicitEuler | < 2           | < 2                                           |
//! | Verlet            | < 2           | < 2                                           |
//! | Midpoint          | < 2           | always grows: × sqrt(1 + (ωh)⁴/4) per step    |
//! | Rk4               | < 2.785       | < 2√2                                         |
//! | Exact             | none          | (not allowed with oscillating forces)         |
//!
//! For the always-growing cases the warning fires when the amplitude would more than double
//! over the particles' lifetime (60 s for immortal particles). ω is that of the force's soft
//! core (sqrt(strength / core)), the steepest the field gets. A second check covers particles
//! that fall through the core faster than one core radius per step (the transit warning).
//! Every warning has a just-past/just-below test in tests/accuracy.rs.

use crate::base::diagnostics::Diagnostic;
use crate::base::path::ValuePath;
use crate::features::forces::Stiffness;
use crate::ir::EffectIr;
use crate::stages::schema::Integrator;

/// Horizon (s) for growth warnings when some particles never die.
pub(crate) const IMMORTAL_HORIZON: f64 = 60.0;
/// Growth factor over the horizon that triggers a warning.
pub(crate) const GROWTH_LIMIT: f64 = 2.0;
/// The largest fall speed x h / core before passes through a soft core lose energy accuracy
/// (measured: docs/accuracy.md, "Passing through a core").
pub(crate) const TRANSIT_LIMIT: f64 = 1.0;
/// Coordinates beyond this (m) lose visible precision in f32.
pub(crate) const PRECISION_LIMIT: f64 = 1.0e5;

/// The largest stable k*h for linear drag, or None when unconditionally stable.
pub fn drag_limit(i: Integrator) -> Option<f64> {
    match i {
        Integrator::Rk4 => Some(2.785),
        Integrator::Exact | Integrator::Auto => None,
        _ => Some(2.0),
    }
}

/// The largest stable ω*h for an undamped oscillation, or None when no hard limit exists.
pub fn oscillation_limit(i: Integrator) -> Option<f64> {
    match i {
        Integrator::SemiImplicitEuler | Integrator::Verlet => Some(2.0),
        Integrator::Rk4 => Some(2.0 * std::f64::consts::SQRT_2),
        _ => None,
    }
}

/// Amplitude growth per step for integrators that always gain energy, at ω*h = `wh`.
pub fn growth_per_step(i: Integrator, wh: f64) -> Option<f64> {
    match i {
        Integrator::Euler => Some((1.0 + wh * wh).sqrt()),
        Integrator::Midpoint => Some((1.0 + wh.powi(4) / 4.0).sqrt()),
        _ => None,
    }
}

/// The longest a particle lives (s), or `IMMORTAL_HORIZON` when some never die.
pub fn horizon(ir: &EffectIr) -> f64 {
    let mut longest: f64 = 0.0;
    for e in &ir.emitters {
        match e.lifetime {
            Some((_, max)) => longest = longest.max(max),
            None => return IMMORTAL_HORIZON,
        }
    }
    if longest > 0.0 {
        longest
    } else {
        IMMORTAL_HORIZON
    }
}

/// An upper bound on particle speed used for tunnelling checks, and where it comes from.
fn speed_bound(ir: &EffectIr) -> (f64, &'static str) {
    match ir.max_speed {
        Some(s) => (s, "max_speed"),
        None => (
            ir.emitters
                .iter()
                .map(|e| e.velocity.max_speed())
                .fold(0.0, f64::max),
            "the fastest spawn speed (set max_speed for a real bound)",
        ),
    }
}

fn force_value_path(force_names: &[&'static str], origin: usize, field: &str) -> ValuePath {
    let name = force_names.get(origin).copied().unwrap_or("force");
    ValuePath::root()
        .field("forces")
        .index(origin)
        .variant(name)
        .field(field)
}

/// Analyses the IR and returns warnings (with lookup paths).
pub(crate) fn analyse(ir: &EffectIr, force_names: &[&'static str]) -> Vec<(Diagnostic, String)> {
    let mut out: Vec<(Diagnostic, String)> = Vec::new();
    let mut warn = |path: ValuePath, msg: String| {
        out.push((Diagnostic::warning(path.display, msg), path.lookup));
    };
    let h = ir.h();
    let integ = ir.integrator;
    let name = integ.name();
    let steps = horizon(ir) / h;
    // (stiffness, first origin, field the warning points at, merged drags note)
    let mut stiff: Vec<(Stiffness, usize, &'static str, String)> = Vec::new();
    for term in &ir.terms {
        let t = term.as_dyn();
        let origin = t.origins()[0];
        let merged = if t.origins().len() > 1 {
            format!(" (drags {:?} merged)", t.origins())
        } else if t.stiffness_is_estimate() {
            " (estimated from the expression's Jacobian sampled over the emitters' region)".into()
        } else {
            String::new()
        };
        let field = match t.stiffness() {
            Stiffness::Damping(_) => "k",
            _ => t.stiffness_field(),
        };
        stiff.push((t.stiffness(), origin, field, merged));
        if let Some(well) = t.core_well() {
            let q = well.fall_speed * h / well.core;
            if q >= TRANSIT_LIMIT && integ != Integrator::Exact {
                warn(
                    force_value_path(force_names, origin, "core"),
                    format!(
                        "a particle falling in from the edge reaches about {:.3} m/s and crosses the {} m core in {:.2} of a step (v*h/core = {q:.2} >= {TRANSIT_LIMIT}): passes through the centre change its energy by tens of percent of the well's depth, so orbits drift and can escape; raise core or substeps to at least {}",
                        well.fall_speed,
                        well.core,
                        1.0 / q,
                        substeps_for(well.fall_speed * ir.dt / well.core / TRANSIT_LIMIT)
                    ),
                );
            }
        }
    }
    if let Some(flock) = &ir.flock {
        if flock.neighbors == crate::features::forces::flock::Neighbors::AllPairs
            && ir.capacity >= crate::features::forces::flock::GRID_FASTER_FROM
        {
            warn(
                force_value_path(force_names, flock.origin, "neighbors"),
                format!(
                    "all pairs at capacity {}: from {} boids the grid was measured faster (docs/performance.md); use neighbors: Grid(cell: {})",
                    ir.capacity,
                    crate::features::forces::flock::GRID_FASTER_FROM,
                    flock.radius
                ),
            );
        }
        // Cohesion is a spring toward the mean (ω² = cohesion); separation pushes a close pair
        // apart at up to separation / core per metre each, 2 separation / core for the pair's
        // relative motion (held for the step, like an explicit evaluation). Alignment damps
        // toward the mean velocity at rate `alignment`, like drag.
        let w2 = flock.cohesion + 2.0 * flock.separation / flock.core();
        if w2 > 0.0 {
            let field = if flock.cohesion >= 2.0 * flock.separation / flock.core() {
                "cohesion"
            } else {
                "separation"
            };
            stiff.push((
                Stiffness::Oscillation(w2.sqrt()),
                flock.origin,
                field,
                String::new(),
            ));
        }
        if flock.alignment > 0.0 {
            stiff.push((
                Stiffness::Damping(flock.alignment),
                flock.origin,
                "alignment",
                String::new(),
            ));
        }
    }
    for (stiffness, origin, field, merged) in stiff {
        match stiffness {
            Stiffness::None => {}
            Stiffness::Damping(k) => {
                let z = k * h;
                if let Some(limit) = drag_limit(integ) {
                    if z >= limit {
                        warn(
                            force_value_path(force_names, origin, field),
                            format!(
                                "k*h = {z:.3}{merged} is past {name}'s drag stability limit {limit} (h = {h:.4e} s): velocities oscillate and grow; raise substeps to at least {}, or use Exact where allowed",
                                substeps_for(k * ir.dt / limit)
                            ),
                        );
                    } else if integ == Integrator::Euler && z > 1.0 {
                        warn(
                            force_value_path(force_names, origin, field),
                            format!(
                                "k*h = {z:.3}{merged} > 1: Euler overshoots, flipping the relative velocity every step; raise substeps to at least {}",
                                substeps_for(k * ir.dt)
                            ),
                        );
                    }
                }
            }
            Stiffness::Oscillation(omega) => {
                let wh = omega * h;
                if let Some(limit) = oscillation_limit(integ) {
                    if wh >= limit {
                        warn(
                            force_value_path(force_names, origin, field),
                            format!(
                                "stiffness ω*h = {wh:.3} (ω = {omega:.3} rad/s, h = {h:.4e} s){merged} is past {name}'s limit {limit:.3}: orbits blow up; raise substeps to at least {}",
                                substeps_for(omega * ir.dt / limit)
                            ),
                        );
                    }
                } else if let Some(g) = growth_per_step(integ, wh) {
                    let total = g.powf(steps);
                    if total >= GROWTH_LIMIT {
                        warn(
                            force_value_path(force_names, origin, field),
                            format!(
                                "{name} gains energy on this force: ω*h = {wh:.3} (ω = {omega:.3} rad/s){merged} grows amplitudes {}x over {:.1} s; use SemiImplicitEuler, Verlet or Rk4, or more substeps",
                                fmt_factor(total),
                                horizon(ir)
                            ),
                        );
                    }
                }
            }
        }
    }

    let (speed, source) = speed_bound(ir);
    for (i, k) in ir.kills.iter().enumerate() {
        if let Some(thick) = k.thickness() {
            if speed * ir.dt > thick {
                warn(
                    ValuePath::root().field("kill").index(i),
                    format!(
                        "a particle at {speed} m/s ({source}) moves {:.3} m per step, more than this volume's thickness {thick:.3} m: it can pass through between checks",
                        speed * ir.dt
                    ),
                );
            }
        }
    }
    // Swept contacts never skip a collider, however fast the particle; what can still fail is
    // f32 itself: a feature thinner than the contact margin at its coordinates.
    let scale = crate::features::colliders::scale(&ir.colliders);
    for (i, c) in ir.colliders.iter().enumerate() {
        if let Some(thin) = c.surface.thinnest() {
            let margin = crate::features::colliders::MARGIN * scale;
            if thin < 8.0 * margin {
                warn(
                    ValuePath::root()
                        .field("collide")
                        .index(i)
                        .variant(c.surface.name()),
                    format!(
                        "this collider is {thin:.3e} m thin, within a few contact margins ({margin:.3e} m: 16 f32 ulps at {scale:.3e} m): contacts on it are only as precise as f32 there (move it nearer the origin or make it larger)"
                    ),
                );
            }
        }
    }

    let mut extent: f64 = 0.0;
    for e in &ir.emitters {
        extent = extent.max(e.shape.extent());
    }
    for c in &ir.colliders {
        extent = extent.max(c.surface.scale());
    }
    if extent >= PRECISION_LIMIT {
        let ulp = f64::from(f32::EPSILON) * extent;
        warn(
            ValuePath::root().field("emitters"),
            format!(
                "positions near {extent:.3e} m are kept in f32 to about {ulp:.3e} m; motion smaller than that per step is lost (move the effect nearer the origin)"
            ),
        );
    }

    if ir.emitters.is_empty() {
        warn(
            ValuePath::root().field("emitters"),
            "no emitters: the effect spawns nothing".into(),
        );
    }
    let burst: u64 = ir
        .emitters
        .iter()
        .filter(|e| e.timing.start_step == 0)
        .map(|e| u64::from(e.burst))
        .sum();
    if burst > u64::from(ir.capacity) {
        warn(
            ValuePath::root().field("capacity"),
            format!(
                "the bursts spawn {burst} particles at step 0 but capacity is {}: {} are dropped",
                ir.capacity,
                burst - u64::from(ir.capacity)
            ),
        );
    }
    let steady: f64 = ir
        .emitters
        .iter()
        .map(|e| {
            // A burst repeating for ever is a rate of burst / every.
            let repeats = match (e.timing.every, e.timing.cycles, e.timing.end_step) {
                (Some(every), None, None) => f64::from(e.burst) / every,
                _ => 0.0,
            };
            let rate = e.rate + repeats;
            match e.lifetime {
                Some((_, max)) => rate * max,
                None if rate > 0.0 && ir.kills.is_empty() => f64::INFINITY,
                None => 0.0,
            }
        })
        .sum();
    if steady > f64::from(ir.capacity) && burst <= u64::from(ir.capacity) {
        let msg = if steady.is_finite() {
            format!(
                "rate x lifetime keeps up to {steady:.0} particles alive but capacity is {}: spawns will be dropped",
                ir.capacity
            )
        } else {
            format!(
                "particles that never die are spawned at a steady rate with no kill volume: capacity {} fills and later spawns are dropped",
                ir.capacity
            )
        };
        warn(ValuePath::root().field("capacity"), msg);
    }
    out
}

/// The substeps that bring `ratio` (a stiffness times dt over its limit) under 1:
/// floor(ratio) + 1, saturating for absurd inputs (dt = 1e30) instead of overflowing.
fn substeps_for(ratio: f64) -> u64 {
    (ratio.floor() as u64).saturating_add(1)
}

fn fmt_factor(x: f64) -> String {
    if x.is_finite() && x < 1e6 {
        format!("{x:.1}")
    } else {
        String::from("more than 1e6")
    }
}
