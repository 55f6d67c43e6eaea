//! The reference simulation loop: the step contract (spawn, one fused update by dt with its
//! substeps, deaths) in f64, particle by particle.

use glam::DVec3;

use super::spawn::spawn;
use super::step::{accel, substep};
use super::{ParticleRecord, Totals};
use crate::features::colliders::resolve;
use crate::features::events::TriggerIr;
use crate::features::forces::flock::Frozen;
use crate::features::forces::ParticleCtx;
use crate::features::looks::ribbon::Ribbon;
use crate::features::looks::trail::History;
use crate::features::placement::Placement;
use crate::ir::EffectIr;
use crate::stages::integrators::ExactStep;
use crate::stages::schedule::Schedule;
use crate::stages::schema::Integrator;

#[derive(Clone, Debug)]
struct Particle {
    id: u32,
    x: DVec3,
    /// Velocity, or Verlet's displacement over one substep.
    v: DVec3,
    die_at: u32,
    /// The step that spawned it.
    born: u64,
    /// Its starting age in whole steps (`Emitter::age`): its age counts from `born - start`.
    start: u32,
    /// Past positions for `render.trail` (empty without one).
    history: History,
    /// Its tint (`tint.rs`), as its group stores or derives it.
    tint: DVec3,
    /// Its kept attributes' values (`features::attributes`), by index.
    attrs: crate::expr::eval::Attrs,
}

/// An event fired by a particle in the last step: its id, and its position and velocity at
/// the end of the step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fired {
    /// The firing particle's id.
    pub id: u32,
    /// Its position (m).
    pub x: DVec3,
    /// Its velocity (m/s).
    pub v: DVec3,
    /// Its tint, as its children may inherit it.
    pub tint: DVec3,
    /// Its attributes' values as the step began, as its children may inherit them.
    pub attrs: crate::expr::eval::Attrs,
}

/// The lifetime (s) of a particle born at step `born` that dies at the update of `die_at`
/// (0 for one that never dies), as the kernels compute it: (die_at − born + 1) dt in u32 steps.
fn lifetime_of(born: u64, die_at: u32, dt: f64) -> f64 {
    if die_at == crate::base::lifetime::NEVER {
        0.0
    } else {
        f64::from(die_at.wrapping_sub(born as u32).wrapping_add(1)) * dt
    }
}

/// The step a particle's age counts from, spawned at `born` with a starting age of `start`
/// steps, as the kernels store it: a u32 step index, wrapping below step 0.
fn clock(born: u64, start: u32) -> u64 {
    u64::from((born as u32).wrapping_sub(start))
}

/// `v` rounded to the nearest 16-bit floats, each clamped to f16's largest finite value first,
/// as a half-motion layout's store does (`pack2x16float` of the clamped value).
pub(crate) fn to_halves(v: DVec3) -> DVec3 {
    let half = |x: f64| half::f16::from_f64(x.clamp(-65504.0, 65504.0)).to_f64();
    DVec3::new(half(v.x), half(v.y), half(v.z))
}

/// Runs an effect's IR on the CPU in f64.
#[derive(Clone, Debug)]
pub struct ReferenceSim {
    ir: EffectIr,
    exact: Option<ExactStep>,
    schedule: Schedule,
    /// Live particles in id order.
    particles: Vec<Particle>,
    /// The baked field's nodes (baked at time 0, or at each step's start), when there is one.
    baked: Option<Vec<DVec3>>,
    totals: Totals,
    /// Per event the group fires, the firings of the last step.
    fired: Vec<Vec<Fired>>,
    /// The next id an event spawn hands out (a group fed by events counts its own ids).
    next_event_id: u32,
    /// Where emitters spawn in the world, for a placed effect (identity otherwise).
    placement: Placement,
    /// Whether each particle's motion is rounded to 16-bit floats wherever the GPU would store
    /// it (spawn and the end of each step): the accuracy pass's model of a half-motion layout.
    motion_in_halves: bool,
    /// The attributes its particles carry (`EffectIr::kept_attributes`, a bit set): fixed by
    /// the IR's expressions, so found once.
    kept: u64,
    /// The ribbon table the spawns write (`render.ribbon`; empty without one).
    ribbon_table: crate::features::looks::ribbon::Table,
}

impl ReferenceSim {
    /// A simulation at step 0 with no particles.
    pub fn new(ir: &EffectIr) -> Self {
        Self {
            exact: (ir.integrator == Integrator::Exact).then(|| ExactStep::new(ir, ir.h())),
            schedule: Schedule::new(ir),
            ir: ir.clone(),
            particles: Vec::new(),
            baked: ir.field.as_ref().map(|f| f.bake(&ir.terms, 0.0)),
            totals: Totals::default(),
            fired: vec![Vec::new(); ir.events.len()],
            next_event_id: 0,
            placement: Placement::IDENTITY,
            // The f64 twin stores what the GPU stores: motion in halves where the accuracy
            // pass chose them (`AccuracyIr::half_motion`; never in a stateless effect).
            motion_in_halves: ir.stateless.is_none()
                && ir.accuracy.as_ref().is_some_and(|a| a.half_motion),
            kept: ir.kept_attributes(),
            ribbon_table: ir.render.ribbon.map(|r| r.table()).unwrap_or_default(),
        }
    }

    /// Whether each particle's stored motion (velocity, or Verlet's displacement) is rounded
    /// to 16-bit floats where the GPU would store it, from now on: by default, as the
    /// effect's layout stores it. The accuracy pass sets it either way to compare the two, and
    /// the truth a budget is measured against never rounds.
    pub(crate) fn set_motion_in_halves(&mut self, on: bool) {
        self.motion_in_halves = on;
    }

    /// Places the emitters' next spawns in the world by `placement` (a placed effect's f64
    /// twin of `Effect::set_placement`; it moves nothing already spawned).
    pub fn set_placement(&mut self, placement: Placement) {
        self.placement = placement;
    }

    /// Gives the `SceneDepth` collider the depth image and camera it collides with from the next
    /// step on (the f64 twin of `Effect::set_scene_depth`, with the same f32 depths and
    /// matrices the GPU reads).
    pub fn set_scene_depth(
        &mut self,
        image: &std::sync::Arc<crate::features::colliders::scene_depth::DepthImage>,
    ) {
        self.ir.set_scene_depth(image);
    }

    /// Sets live param `name` to `value` for the next steps (the f64 twin of
    /// `Effect::set_param`: custom forces then read the f32 `value`, as the GPU does); refused
    /// for a name the effect does not read at run time.
    pub fn set_param(&mut self, name: &str, value: f32) -> Result<(), String> {
        let index = self
            .ir
            .live_params
            .iter()
            .position(|p| p.0 == name)
            .ok_or_else(|| format!("the effect reads no live param `{name}`"))?;
        self.ir.set_live_param(index, value);
        self.schedule.set_param(index, value);
        Ok(())
    }

    /// Keeps `scale` of every spawn from the next step on (the f64 twin of
    /// `Effect::set_spawn_scale`; see [`Schedule::set_spawn_scale`]).
    pub fn set_spawn_scale(&mut self, scale: f32) {
        self.schedule.set_spawn_scale(scale);
    }

    /// Queues a burst fired from code for the next steps (the f64 twin of `Effect::burst`; an
    /// effect compiled with `CompileOptions::bursts`); refused, with why, for a missing
    /// emitter or a coordinate that is not finite.
    pub fn burst(&mut self, burst: crate::features::bursts::Burst) -> Result<(), String> {
        self.schedule.queue_burst(burst)
    }

    /// Spawns the children of the `input`-th event this group is fed by, from the parent's
    /// firings of the last step, at the start of the next step (before [`Self::step`]): in
    /// parent id order, `count` each, ids consecutive, the last ones dropped when there is no
    /// room (their ids consumed all the same), as the GPU's event spawn does.
    pub(crate) fn spawn_events(&mut self, input: usize, fired: &[Fired]) {
        let inp = self.ir.event_inputs[input].clone();
        let mut order: Vec<&Fired> = fired.iter().collect();
        order.sort_by_key(|f| f.id);
        let requested = order.len() as u64 * u64::from(inp.count);
        let free = u64::from(self.ir.capacity) - self.particles.len() as u64;
        let n = requested.min(free);
        self.totals.spawned += n;
        self.totals.dropped += requested - n;
        let first = self.next_event_id;
        self.next_event_id = first.wrapping_add(requested as u32);
        let step = self.schedule.steps_done();
        let time = step as f64 * self.ir.dt;
        for i in 0..n {
            let parent = order[(i / u64::from(inp.count)) as usize];
            let c = (i % u64::from(inp.count)) as u32;
            let id = first.wrapping_add(i as u32);
            if let Some(ribbon) = &self.ir.render.ribbon {
                let link = Ribbon::child(parent.id, step, inp.period, inp.count, c);
                ribbon.write(&mut self.ribbon_table, id, link);
            }
            let mut s =
                crate::reference::spawn::spawn_at(&self.ir, inp.emitter, (id, c), step, parent.x);
            s.x += parent.x;
            s.v += inp.inherit_velocity * parent.v;
            let inherited = if inp.inherit_color {
                parent.tint
            } else {
                DVec3::ONE
            };
            let tint = crate::features::looks::tint::spawned(self.ir.tint(), id, inherited);
            let mut attrs = self.spawn_attrs(s.x, s.v, time, id);
            // What it inherits, as the GPU passes it: f32 words (`features::inherit`).
            for &(pa, ca) in &inp.inherits {
                attrs[ca] = parent.attrs[pa].as_vec3().as_dvec3();
            }
            let v =
                self.stored(self.initial_v(id, (step, s.start), time, (s.x, s.v), s.die_at, attrs));
            self.particles.push(Particle {
                id,
                x: s.x,
                v,
                die_at: s.die_at,
                born: step,
                start: s.start,
                history: History::default(),
                tint,
                attrs,
            });
        }
    }

    /// The firings of the last step of the `j`-th event this group fires.
    pub fn fired(&self, j: usize) -> &[Fired] {
        &self.fired[j]
    }

    /// What the state stores as velocity for a particle spawned at `step` with velocity `v`:
    /// `v` itself, or Verlet's first displacement.
    /// Motion as the GPU stores it: rounded to halves in a half-motion model.
    fn stored(&self, v: DVec3) -> DVec3 {
        if self.motion_in_halves {
            to_halves(v)
        } else {
            v
        }
    }

    /// The kept attributes' values of particle `id`, spawned at `time` at `x` with velocity `v`.
    fn spawn_attrs(&self, x: DVec3, v: DVec3, time: f64, id: u32) -> crate::expr::eval::Attrs {
        self.ir.attributes.spawn_values(self.kept, x, v, time, id)
    }

    fn initial_v(
        &self,
        id: u32,
        (step, start): (u64, u32),
        time: f64,
        (x, v): (DVec3, DVec3),
        die_at: u32,
        attrs: crate::expr::eval::Attrs,
    ) -> DVec3 {
        if self.ir.integrator != Integrator::Verlet {
            return v;
        }
        let h = self.ir.h();
        let ctx = ParticleCtx {
            id,
            age0: f64::from(start) * self.ir.dt,
            t0: time,
            life: lifetime_of(clock(step, start), die_at, self.ir.dt),
            attrs,
        };
        v * h - accel(&self.ir, self.baked.as_deref(), &ctx, x, v, time) * (0.5 * h * h)
    }

    /// Runs `n` steps.
    pub fn run(&mut self, n: u64) {
        for _ in 0..n {
            self.step();
        }
    }

    /// One step: spawn, update every live particle by dt, deaths.
    pub fn step(&mut self) {
        let plan = self.schedule.next_plan();
        if let Some(field) = &self.ir.field {
            if field.refresh == crate::features::field::Refresh::EveryStep {
                self.baked = Some(field.bake(&self.ir.terms, plan.time));
            }
        }
        let verlet = self.ir.integrator == Integrator::Verlet;
        let h = self.ir.h();
        for f in &mut self.fired {
            f.clear();
        }
        // Spawn: the first `free` requested ids get slots, the rest are dropped.
        let free = u64::from(self.ir.capacity) - self.particles.len() as u64;
        let mut budget = free.min(u64::from(plan.requested()));
        self.totals.spawned += budget;
        self.totals.dropped += u64::from(plan.requested()) - budget;
        let mut id = plan.first_id;
        // The emitters' spawns, then the bursts fired from code (`features::bursts`).
        let sources = plan
            .emitters
            .iter()
            .enumerate()
            .map(|(e, &(count, k0))| (e, count, k0, None))
            .chain(
                plan.bursts
                    .iter()
                    .map(|b| (b.burst.emitter as usize, b.burst.count, b.k0, Some(b.burst))),
            );
        for (e, count, k0, burst) in sources {
            for local in 0..count {
                if budget == 0 {
                    break;
                }
                budget -= 1;
                let k = k0.wrapping_add(local);
                if let Some(ribbon) = &self.ir.render.ribbon {
                    let link = ribbon.emitted(e as u32, self.ir.emitters.len() as u32, k);
                    ribbon.write(&mut self.ribbon_table, id + local, link);
                }
                let mut s = spawn(&self.ir, e, id + local, k, plan.step);
                if let Some(burst) = burst {
                    (s.x, s.v) = burst.apply(s.x, s.v);
                }
                if self.ir.placed {
                    s.x = self.placement.point(s.x);
                    s.v = self.placement.vector(s.v);
                }
                let attrs = self.spawn_attrs(s.x, s.v, plan.time, id + local);
                let v = self.stored(self.initial_v(
                    id + local,
                    (plan.step, s.start),
                    plan.time,
                    (s.x, s.v),
                    s.die_at,
                    attrs,
                ));
                self.particles.push(Particle {
                    id: id + local,
                    x: s.x,
                    v,
                    die_at: s.die_at,
                    born: plan.step,
                    start: s.start,
                    history: History::default(),
                    tint: crate::features::looks::tint::spawned(
                        self.ir.tint(),
                        id + local,
                        DVec3::ONE,
                    ),
                    attrs,
                });
            }
            id += count;
        }
        // Update.
        let step_index = plan.step as u32;
        let has_lifetimes = self.ir.has_lifetimes();
        let ir = &self.ir;
        let exact = self.exact.as_ref();
        let baked = self.baked.as_deref();
        let before = self.particles.len();
        // Flocking reads every boid as it is after the spawns, before anyone moves.
        let frozen: Vec<Frozen> = match &ir.flock {
            Some(flock) => {
                let boids: Vec<(DVec3, DVec3)> = self
                    .particles
                    .iter()
                    .map(|p| (p.x, if verlet { p.v / h } else { p.v }))
                    .collect();
                flock.frozen(&boids)
            }
            None => Vec::new(),
        };
        let mut index = 0;
        let rest_speed = ir.rest_speed();
        let fired = &mut self.fired;
        let halves = self.motion_in_halves;
        let kept = self.kept;
        let changes = ir.attributes.iter_kept(kept).any(|(_, a)| a.changes());
        self.particles.retain_mut(|p| {
            let flock = frozen.get(index);
            index += 1;
            let born = clock(p.born, p.start);
            let ctx = ParticleCtx {
                id: p.id,
                age0: (plan.step.saturating_sub(p.born) + u64::from(p.start)) as f64 * ir.dt,
                t0: plan.time,
                life: lifetime_of(born, p.die_at, ir.dt),
                attrs: p.attrs,
            };
            if let Some(trail) = &ir.render.trail {
                p.history.record(trail, plan.step, p.x);
            }
            let mut collided = false;
            for s in 0..ir.substeps {
                let t = plan.time + f64::from(s) * h;
                let x0 = p.x;
                substep(ir, exact, baked, flock, &ctx, &mut p.x, &mut p.v, t);
                collided |= resolve(&ir.colliders, rest_speed, x0, &mut p.x, &mut p.v, verlet, h);
            }
            if changes {
                p.attrs = ir.attributes.step_values(
                    kept,
                    &crate::expr::eval::Inputs {
                        x: p.x,
                        v: if verlet { p.v / h } else { p.v },
                        t: plan.time,
                        age: ctx.age0,
                        life: ctx.life,
                        seed_mix: ir.seed_mix,
                        id: p.id,
                        attrs: p.attrs,
                        ..Default::default()
                    },
                );
            }
            if halves {
                p.v = to_halves(p.v);
            }
            let dies =
                (has_lifetimes && step_index >= p.die_at) || ir.kills.iter().any(|k| k.kills(p.x));
            let firing = Fired {
                id: p.id,
                x: p.x,
                v: if verlet { p.v / h } else { p.v },
                tint: p.tint,
                attrs: ctx.attrs,
            };
            for (j, e) in ir.events.iter().enumerate() {
                let fires = match e.trigger {
                    TriggerIr::Death => dies,
                    TriggerIr::Collide => collided,
                    TriggerIr::Every(period) => TriggerIr::every_fires(period, born, plan.step),
                };
                if fires {
                    fired[j].push(firing);
                }
            }
            !dies
        });
        self.totals.died += (before - self.particles.len()) as u64;
        self.totals.steps += 1;
        self.totals.alive = self.particles.len() as u64;
    }

    /// Totals so far.
    pub fn totals(&self) -> Totals {
        self.totals
    }

    /// The live particles in id order, with velocity (Verlet's derived) and age.
    pub fn records(&self) -> Vec<ParticleRecord> {
        let h = self.ir.h();
        let kept = self.kept;
        let verlet = self.ir.integrator == Integrator::Verlet;
        self.particles
            .iter()
            .map(|p| ParticleRecord {
                id: p.id,
                position: p.x,
                velocity: if verlet { p.v / h } else { p.v },
                age: (self.schedule.steps_done() - p.born + u64::from(p.start)) as f64 * self.ir.dt,
                lifetime: (p.die_at != crate::base::lifetime::NEVER)
                    .then(|| lifetime_of(clock(p.born, p.start), p.die_at, self.ir.dt)),
                tint: p.tint,
                attributes: self.ir.attributes.words(kept, &p.attrs),
            })
            .collect()
    }

    /// Each live particle's trail (`render.trail`) in id order: its id and the ribbon's
    /// points, its position now and then its recorded samples newest first. Empty without a
    /// trail.
    pub fn trails(&self) -> Vec<(u32, Vec<DVec3>)> {
        if self.ir.render.trail.is_none() {
            return Vec::new();
        }
        self.particles
            .iter()
            .map(|p| (p.id, p.history.ribbon(p.x)))
            .collect()
    }

    /// The ribbon table the spawns wrote (`render.ribbon`; empty without one): what
    /// [`Ribbon::chains`] joins.
    pub fn ribbon_table(&self) -> &crate::features::looks::ribbon::Table {
        &self.ribbon_table
    }

    /// The spawn schedule (for ages).
    pub fn schedule(&self) -> &Schedule {
        &self.schedule
    }
}
