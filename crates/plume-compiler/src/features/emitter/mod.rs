//! Emitters: when, where and how fast particles spawn. The schema (`Emitter`, `Shape`,
//! `Velocity`), its checks and its lowered form (`EmitterIr`, `ShapeIr`, `VelocityIr`), which
//! events reuse for the particles they spawn and custom forces read for their stiffness
//! estimates. Each part owns its WGSL and its f64 twin: `shape_ir.rs` where particles start,
//! `velocity.rs` how they move off, `timing.rs` at which steps they spawn.

mod amount;
mod expression;
mod shape;
mod shape_ir;
mod timing;
mod torus;
mod velocity;

use std::path::Path;

use glam::DVec3;
use serde::Deserialize;

use crate::base::check::Checker;
use crate::base::lifetime::LifetimeSteps;
use crate::base::path::ValuePath;
use crate::base::rng::ParticleDraws;
use crate::base::values::Range;
use crate::base::writer::Writer;
use crate::expr::Names;

pub use amount::Amount;
pub(crate) use amount::AmountKind;
pub use shape::Shape;
pub(crate) use shape_ir::ShapeIr;
pub use timing::Every;
pub(crate) use timing::SpawnTiming;
pub use velocity::Velocity;
pub(crate) use velocity::VelocityIr;

/// One particle source.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Emitter {
    /// Particles spawned at once when the emitter starts (and again every `every` seconds):
    /// a number or a param's name.
    #[serde(default)]
    pub burst: Amount<u32>,
    /// Particles per second, a number or a param's name; the fractional remainder carries to
    /// the next step.
    #[serde(default)]
    pub rate: Amount<f64>,
    /// Seconds before the emitter starts spawning.
    #[serde(default)]
    pub start: f64,
    /// Seconds it spawns for, from `start`; `None`: for ever.
    #[serde(default)]
    pub duration: Option<f64>,
    /// Seconds between repeats of the burst, or a range of seconds from which each gap is
    /// drawn; `None`: it fires once.
    #[serde(default)]
    pub every: Option<timing::Every>,
    /// How many times a repeating burst fires; `None`: for as long as the emitter runs.
    #[serde(default)]
    pub cycles: Option<u32>,
    /// Where particles start.
    pub shape: Shape,
    /// How fast and where they start moving.
    pub velocity: Velocity,
    /// Lifetime range in seconds; `None` lives forever.
    #[serde(default)]
    pub lifetime: Option<Range>,
    /// A starting age range in seconds, drawn per particle in whole steps: a particle starts
    /// that far into its life (its lifetime counts from its starting age, its colour and size
    /// over life start that far along); `None` starts at 0.
    #[serde(default)]
    pub age: Option<Range>,
}

/// One emitter.
#[derive(Clone, Debug, PartialEq)]
pub struct EmitterIr {
    /// Spawned at each of the timing's bursts.
    pub burst: u32,
    /// A burst count drawn anew for each burst from this range (`burst: (lo, hi)`), when it
    /// is one; `burst` is then its low end.
    pub(crate) burst_range: Option<(u32, u32)>,
    /// Per second, while the timing lets it run.
    pub rate: f64,
    /// The live params the burst and the rate follow (indices in `EffectIr::live_params`).
    pub params: (Option<usize>, Option<usize>),
    /// At which steps it spawns.
    pub timing: SpawnTiming,
    /// Spawn position.
    pub(crate) shape: ShapeIr,
    /// Spawn velocity.
    pub(crate) velocity: VelocityIr,
    /// Lifetime range (s).
    pub lifetime: Option<(f64, f64)>,
    /// The lifetime as whole steps (see [`crate::base::lifetime`]).
    pub lifetime_steps: Option<LifetimeSteps>,
    /// The starting age's draw in whole steps (stream `START_AGE`), when it has one.
    pub age_steps: Option<LifetimeSteps>,
}

/// An orthonormal pair spanning the plane perpendicular to a unit vector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Basis {
    /// First tangent.
    pub t1: DVec3,
    /// Second tangent (`n × t1`).
    pub t2: DVec3,
}

impl Basis {
    /// A right-handed basis around unit `n`.
    pub(crate) fn around(n: DVec3) -> Self {
        let helper = if n.x.abs() > 0.9 { DVec3::Y } else { DVec3::X };
        let t1 = n.cross(helper).normalize();
        let t2 = n.cross(t1);
        Self { t1, t2 }
    }
}

impl Emitter {
    /// An emitter of `shape` and `velocity` that never spawns on its own (an event's spawn rule).
    pub fn idle(shape: Shape, velocity: Velocity, lifetime: Option<Range>) -> Self {
        Self {
            burst: Amount::Value(0),
            rate: Amount::Value(0.0),
            start: 0.0,
            duration: None,
            every: None,
            cycles: None,
            shape,
            velocity,
            lifetime,
            age: None,
        }
    }

    /// Records in `c` what is wrong with the emitter at `path`; `names` are what its
    /// expressions may name (and the step, `names.dt`).
    pub(crate) fn check(&self, c: &mut Checker, path: &ValuePath, names: Names) {
        let dt = names.dt;
        self.rate.check(c, &path.field("rate"), names);
        self.burst.check(c, &path.field("burst"), names);
        timing::check(
            c,
            path,
            (self.start, self.duration, self.every, self.cycles),
            self.burst.value(names.params),
            dt,
        );
        self.shape.check(c, &path.field("shape"), names);
        let on_mesh = matches!(self.shape, Shape::Mesh { .. });
        self.velocity
            .check(c, &path.field("velocity"), on_mesh, names);
        if matches!(self.shape, Shape::Mesh { volume: true, .. })
            && matches!(self.velocity, Velocity::Normal { .. })
        {
            c.error(
                &path.field("velocity").variant("Normal"),
                "a particle spawned in a mesh's volume has no surface normal: use Radial (away from the mesh's centre) or Cone",
            );
        }
        if let Some(life) = self.lifetime {
            let p = path.field("lifetime");
            if c.range(&p, life) {
                if life.0 <= 0.0 {
                    c.error(
                        &p.component(0, "min"),
                        format!("must be > 0 seconds, got {}", life.0),
                    );
                } else if dt > 0.0 && LifetimeSteps::new(life.0, life.1, dt).is_none() {
                    c.error(
                        &p.component(1, "max"),
                        format!("is more than 2^31 steps of dt = {dt} s, got {}", life.1),
                    );
                }
            }
        }
        if let Some(age) = self.age {
            let p = path.field("age");
            if c.range(&p, age) {
                if age.0 < 0.0 {
                    c.error(
                        &p.component(0, "min"),
                        format!("must be >= 0 seconds, got {}", age.0),
                    );
                } else if dt > 0.0 && LifetimeSteps::ages(age.0, age.1, dt).is_none() {
                    c.error(
                        &p.component(1, "max"),
                        format!("is more than 2^31 steps of dt = {dt} s, got {}", age.1),
                    );
                }
            }
        }
    }

    /// The emitter's lowered form (after [`Emitter::check`] passed) in an effect of
    /// `seed_mix`.
    pub(crate) fn lower(&self, names: Names, seed_mix: u32) -> EmitterIr {
        let dt = names.dt;
        let shape = self.shape.lower(names, seed_mix);
        let (burst, rate) = (self.burst.lower(names), self.rate.lower(names));
        EmitterIr {
            burst: burst.value,
            burst_range: match self.burst {
                Amount::Range(lo, hi) => Some((lo, hi)),
                _ => None,
            },
            rate: rate.value,
            params: (burst.param, rate.param),
            timing: SpawnTiming::new(self.start, self.duration, self.every, self.cycles, dt),
            velocity: self.velocity.lower(names, &shape, seed_mix),
            shape,
            lifetime: self.lifetime.map(|r| (r.0, r.1)),
            lifetime_steps: self.lifetime.and_then(|r| LifetimeSteps::new(r.0, r.1, dt)),
            // A range within half a step of 0 starts every particle at 0: no draw.
            age_steps: self
                .age
                .and_then(|r| LifetimeSteps::ages(r.0, r.1, dt))
                .filter(|a| (a.first, a.span) != (0, 1)),
        }
    }
}

impl EmitterIr {
    /// Whether its spawn expressions (a `Custom` shape or velocity) read the gradient noise
    /// through `op`.
    pub(crate) fn uses(&self, op: crate::expr::typed::Op1) -> bool {
        let shape = matches!(&self.shape, ShapeIr::Custom { expr, .. } if expr.uses(op));
        let velocity = matches!(&self.velocity, VelocityIr::Custom { expr, .. } if expr.uses(op));
        shape || velocity
    }

    /// Whether everything it spawns, it spawns at step 0: one burst, no rate, no start delay,
    /// no param that could open it later (so once its particles are gone, the effect is done).
    pub fn spawns_once_at_start(&self) -> bool {
        self.rate <= 0.0
            && self.params == (None, None)
            && self.timing.start_step == 0
            && self.timing.every.is_none()
    }

    /// The position and velocity of particle `id`, the emitter's `k`-th, spawned at `step` in
    /// a frame at `origin` (the f64 twin of `emit_wgsl`).
    pub fn sample(
        &self,
        seed_mix: u32,
        (id, k): (u32, u32),
        step: u64,
        origin: DVec3,
    ) -> (DVec3, DVec3) {
        let d = ParticleDraws { seed_mix, id };
        let t = step as f64 * self.timing.dt;
        let (x, normal) = self.shape.sample(&d, k, (t, origin));
        (
            x,
            self.velocity
                .sample(&d, &self.shape, (x, normal), (t, origin)),
        )
    }

    /// Whether its spawn position or velocity reads `origin` (an event's firing particle).
    pub(crate) fn reads_origin(&self) -> bool {
        let reads = |e: &crate::expr::Expr| e.reads(crate::expr::Var::Origin);
        matches!(&self.shape, ShapeIr::Custom { expr, .. } if reads(expr))
            || matches!(&self.velocity, VelocityIr::Custom { expr, .. } if reads(expr))
    }

    /// Sets live param `index` to `value` in the emitter's expressions.
    pub fn set_param(&mut self, index: u32, value: f64) {
        if let ShapeIr::Custom { expr, .. } = &mut self.shape {
            expr.set_param(index, value);
        }
        if let VelocityIr::Custom { expr, .. } = &mut self.velocity {
            expr.set_param(index, value);
        }
    }

    /// Emits what emitter `e` needs at the module's top level, before its `emit_e` function;
    /// `data_offset` is where its mesh's data starts in `spawn_data`.
    pub(crate) fn emit_items(&self, w: &mut Writer, e: usize, data_offset: u32) {
        self.shape.emit_items(w, e, data_offset);
    }

    /// Emits the statements of emitter `e`'s `emit_e(id, k, step)` that set its position and
    /// velocity (`s.x`, `s.v`): the WGSL twin of [`Self::sample`].
    pub(crate) fn emit_wgsl(&self, w: &mut Writer, e: usize) {
        self.shape.emit_wgsl(w, e, self.timing.dt);
        self.velocity.emit_wgsl(w, &self.shape, self.timing.dt);
    }
}

/// Reads every `Mesh` spawn shape's file into its placed surface (files relative to
/// `base_dir`), recording what is wrong in `c` at the shape's `file`.
pub(crate) fn read_mesh_shapes(emitters: &mut [Emitter], base_dir: Option<&Path>, c: &mut Checker) {
    for (i, emitter) in emitters.iter_mut().enumerate() {
        let path = ValuePath::root().field("emitters").index(i);
        emitter.read_mesh_shape(&path, base_dir, c);
    }
}

impl Emitter {
    /// Reads the shape's file when it is a `Mesh` ([`Shape::read_mesh`]); `path` is the
    /// emitter's.
    pub(crate) fn read_mesh_shape(
        &mut self,
        path: &ValuePath,
        base_dir: Option<&Path>,
        c: &mut Checker,
    ) {
        self.shape.read_mesh(&path.field("shape"), base_dir, c);
    }
}

/// Where emitter `e`'s mesh surface starts in the `spawn_data` binding (the surfaces of the
/// emitters before it come first).
pub(crate) fn spawn_data_offset(emitters: &[EmitterIr], e: usize) -> u32 {
    emitters[..e]
        .iter()
        .map(|em| match &em.shape {
            ShapeIr::Mesh(m) => m.data_len(),
            _ => 0,
        })
        .sum()
}

/// The `spawn_data` binding's contents: every mesh surface's thresholds and triangles, in
/// emitter order; None when no emitter spawns on a mesh.
pub fn spawn_data(emitters: &[EmitterIr]) -> Option<Vec<u32>> {
    let mut out = Vec::new();
    let mut any = false;
    for em in emitters {
        if let ShapeIr::Mesh(m) = &em.shape {
            out.extend(m.data());
            any = true;
        }
    }
    any.then_some(out)
}
