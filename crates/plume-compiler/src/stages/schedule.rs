//! The step contract's bookkeeping, shared by the GPU runtime and the CPU reference so both
//! spawn exactly the same ids at the same steps.
//!
//! At step k (time t = k dt): each emitter spawns its bursts due at k (its timing's, see
//! `features/emitter/timing.rs`: the first at its start step) plus, while its rate runs, the
//! whole part of its accumulated `rate * dt`, the fractional remainder carried to the next step. Ids are handed
//! out across emitters in the order they are listed, step by step; spawns dropped for lack of
//! capacity still consume their ids, so ids never depend on what the GPU had free. Bursts
//! fired from code (`features::bursts`) take the ids after the emitters', up to
//! `bursts::SLOTS` per step in the order they were fired.

use std::collections::VecDeque;

use crate::features::bursts::{Burst, PlannedBurst, SLOTS};
use crate::features::emitter::SpawnTiming;
use crate::features::forces::noise::TIME_PERIOD;
use crate::ir::EffectIr;

/// What one step spawns.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepPlan {
    /// Step index k.
    pub step: u64,
    /// Simulation time at the start of the step, k dt (f64, never accumulated).
    pub time: f64,
    /// Id of the first particle requested this step.
    pub first_id: u32,
    /// Per emitter: (spawns this step, the emitter's own spawn counter before them).
    pub emitters: Vec<(u32, u32)>,
    /// Bursts fired from code that spawn this step, after every emitter's spawns.
    pub bursts: Vec<PlannedBurst>,
}

impl StepPlan {
    /// Total spawns requested this step.
    pub fn requested(&self) -> u32 {
        self.emitters.iter().map(|e| e.0).sum::<u32>()
            + self.bursts.iter().map(|b| b.burst.count).sum::<u32>()
    }

    /// Time passed to kernels, as f32: t mod the noise period when `wrap`
    /// ([`crate::ir::EffectIr::wraps_kernel_time`]), else t itself.
    pub fn kernel_time(&self, wrap: bool) -> f32 {
        if wrap {
            self.time.rem_euclid(TIME_PERIOD) as f32
        } else {
            self.time as f32
        }
    }
}

/// Produces the [`StepPlan`] of each step in turn and remembers which step each id was
/// requested at (for ages).
#[derive(Clone, Debug)]
pub struct Schedule {
    dt: f64,
    bursts: Vec<u32>,
    rates: Vec<f64>,
    timings: Vec<SpawnTiming>,
    /// Per emitter, the live params its burst and rate follow ([`Schedule::set_param`]).
    params: Vec<(Option<usize>, Option<usize>)>,
    /// Per emitter, the range its burst counts are drawn from, when they are drawn.
    burst_ranges: Vec<Option<(u32, u32)>>,
    /// Per emitter, the number of its next burst (how many have fired).
    next_burst: Vec<u32>,
    carried: Vec<f64>,
    emitted: Vec<u32>,
    next_step: u64,
    next_id: u32,
    /// (first id, step) for every step that requested at least one spawn, in order; entries
    /// whose particles have all died are dropped (see `keeps`).
    first_ids: VecDeque<(u32, u64)>,
    /// The most steps a particle lives (every emitter's lifetime bounded), so that a step's
    /// entry can go once its particles are all dead: a game's effect that spawns every frame
    /// would otherwise hold one more entry a frame for as long as it runs. None: kept.
    keeps: Option<u64>,
    /// Bursts fired from code that no step has spawned yet, oldest first.
    pending: VecDeque<Burst>,
    /// The fraction of every spawn kept ([`Schedule::set_spawn_scale`]), 1 for all.
    spawn_scale: f64,
    /// Per emitter, the fraction of a particle its scaled bursts owe the next one.
    burst_carried: Vec<f64>,
}

impl Schedule {
    /// A schedule at step 0 for `ir`.
    pub fn new(ir: &EffectIr) -> Self {
        Self {
            dt: ir.dt,
            bursts: ir.emitters.iter().map(|e| e.burst).collect(),
            burst_ranges: ir.emitters.iter().map(|e| e.burst_range).collect(),
            rates: ir.emitters.iter().map(|e| e.rate).collect(),
            timings: ir.emitters.iter().map(|e| e.timing).collect(),
            params: ir.emitters.iter().map(|e| e.params).collect(),
            next_burst: vec![0; ir.emitters.len()],
            carried: vec![0.0; ir.emitters.len()],
            emitted: vec![0; ir.emitters.len()],
            next_step: 0,
            next_id: 0,
            first_ids: VecDeque::new(),
            keeps: ir
                .emitters
                .iter()
                .map(|e| {
                    e.lifetime_steps
                        .map(|l| u64::from(l.first) + u64::from(l.span))
                })
                .try_fold(0, |most, life| life.map(|l| most.max(l)))
                .filter(|_| ir.event_inputs.is_empty()),
            pending: VecDeque::new(),
            spawn_scale: 1.0,
            burst_carried: vec![0.0; ir.emitters.len()],
        }
    }

    /// Keeps `scale` (clamped to 0..=1; 0 for NaN) of every spawn planned from now on: each
    /// rate runs at `scale` times its value and each burst, the emitters' and those fired
    /// from code, spawns `scale` times its count, a fraction carried to the emitter's next
    /// burst. So a thinned effect spawns fewer particles, each spawned as any other; those
    /// alive live on. At 1 (the start) the plan is exactly the unscaled one.
    pub fn set_spawn_scale(&mut self, scale: f32) {
        self.spawn_scale = if scale.is_nan() {
            0.0
        } else {
            f64::from(scale.clamp(0.0, 1.0))
        };
    }

    /// The fraction of every spawn kept ([`Schedule::set_spawn_scale`]).
    pub fn spawn_scale(&self) -> f32 {
        self.spawn_scale as f32
    }

    /// `count` particles of emitter `e`'s bursts, thinned by the spawn scale.
    fn scaled_burst(&mut self, e: usize, count: u64) -> u64 {
        if self.spawn_scale >= 1.0 || count == 0 {
            return count;
        }
        let kept = count as f64 * self.spawn_scale + self.burst_carried[e];
        let whole = kept.floor();
        self.burst_carried[e] = kept - whole;
        whole as u64
    }

    /// Queues `burst` for the next step that has a burst slot free (the next step, unless
    /// [`SLOTS`] bursts are already waiting); refused, with why, when its emitter does not
    /// exist or a coordinate is not finite.
    pub fn queue_burst(&mut self, burst: Burst) -> Result<(), String> {
        if burst.emitter as usize >= self.rates.len() {
            return Err(format!(
                "a burst from emitter {}, but the effect has {} emitter(s)",
                burst.emitter,
                self.rates.len()
            ));
        }
        if !burst.is_finite() {
            return Err(format!(
                "a burst's offset {:?} and velocity {:?} must be finite",
                burst.offset, burst.velocity
            ));
        }
        self.pending.push_back(burst);
        Ok(())
    }

    /// Sets live param `index` to `value` for the steps planned after this: the bursts and
    /// rates that follow it take it (a burst rounded to whole particles, neither below 0).
    pub fn set_param(&mut self, index: usize, value: f32) {
        use crate::features::emitter::AmountKind;
        let value = f64::from(value);
        for (e, &(burst, rate)) in self.params.iter().enumerate() {
            if burst == Some(index) {
                self.bursts[e] = u32::from_param(value);
            }
            if rate == Some(index) {
                self.rates[e] = f64::from_param(value);
            }
        }
    }

    /// Steps whose spawns it still remembers (for ages): those that may have live particles.
    pub fn steps_remembered(&self) -> usize {
        self.first_ids.len()
    }

    /// Steps planned so far.
    pub fn steps_done(&self) -> u64 {
        self.next_step
    }

    /// Ids requested so far (the next id to hand out).
    pub fn ids_requested(&self) -> u32 {
        self.next_id
    }

    /// Plans the next step.
    pub fn next_plan(&mut self) -> StepPlan {
        let mut plan = StepPlan::default();
        self.next_plan_into(&mut plan);
        plan
    }

    /// [`Self::next_plan`] written into `plan`, whose lists are cleared and refilled: a
    /// caller planning many steps (a batch's instances, every frame) allocates nothing.
    pub fn next_plan_into(&mut self, plan: &mut StepPlan) {
        let step = self.next_step;
        let first_id = self.next_id;
        let emitters = &mut plan.emitters;
        let bursts = &mut plan.bursts;
        emitters.clear();
        bursts.clear();
        for e in 0..self.rates.len() {
            let timing = self.timings[e];
            let mut count = 0u64;
            while timing
                .burst_step(self.next_burst[e])
                .is_some_and(|due| due <= step)
            {
                let n = self.next_burst[e];
                let burst = match self.burst_ranges[e] {
                    Some(range) => timing.burst_count(n, range),
                    None => self.bursts[e],
                };
                count = count.saturating_add(u64::from(burst));
                self.next_burst[e] += 1;
            }
            let mut count = self.scaled_burst(e, count);
            if timing.rate_runs(step) {
                self.carried[e] += self.rates[e] * self.spawn_scale * self.dt;
                let whole = self.carried[e].floor();
                self.carried[e] -= whole;
                count = count.saturating_add(whole as u64);
            }
            let count = count.min(u64::from(u32::MAX - self.next_id)) as u32;
            emitters.push((count, self.emitted[e]));
            self.emitted[e] = self.emitted[e].wrapping_add(count);
            self.next_id += count;
        }
        while bursts.len() < SLOTS as usize {
            let Some(mut burst) = self.pending.pop_front() else {
                break;
            };
            let e = burst.emitter as usize;
            let kept = self.scaled_burst(e, u64::from(burst.count)) as u32;
            burst.count = kept.min(u32::MAX - self.next_id);
            bursts.push(PlannedBurst {
                burst,
                k0: self.emitted[e],
            });
            self.emitted[e] = self.emitted[e].wrapping_add(burst.count);
            self.next_id += burst.count;
        }
        if self.next_id > first_id {
            self.first_ids.push_back((first_id, step));
        }
        // An entry whose particles have all died (spawned `keeps` steps ago and more) goes,
        // once a later one covers the ids after it.
        if let Some(keeps) = self.keeps {
            while self.first_ids.len() > 1 && self.first_ids[0].1 + keeps + 1 < step {
                self.first_ids.pop_front();
            }
        }
        self.next_step += 1;
        plan.step = step;
        plan.time = step as f64 * self.dt;
        plan.first_id = first_id;
    }

    /// Skips `n` steps at once when no step from now on can spawn anything (every rate is 0 or
    /// has ended, every burst has fired), as stepping them would; returns false, skipping
    /// nothing, otherwise.
    pub(crate) fn skip_idle(&mut self, n: u64) -> bool {
        if self.next_step == 0 || !self.pending.is_empty() {
            return false;
        }
        let step = self.next_step;
        // A burst or rate that follows a live param may be set above 0 later.
        let spawns_later = |e: usize| {
            let timing = &self.timings[e];
            let (burst_param, rate_param) = self.params[e];
            ((self.rates[e] > 0.0 || rate_param.is_some()) && timing.rate_runs_after(step))
                || ((self.bursts[e] > 0
                    || burst_param.is_some()
                    || self.burst_ranges[e].is_some_and(|r| r.1 > 0))
                    && timing.burst_step(self.next_burst[e]).is_some())
        };
        if (0..self.rates.len()).any(spawns_later) {
            return false;
        }
        self.next_step = self.next_step.saturating_add(n);
        true
    }

    /// The step at which particle `id` was spawned.
    pub fn spawn_step(&self, id: u32) -> u64 {
        let i = self.first_ids.partition_point(|&(first, _)| first <= id);
        self.first_ids[i.saturating_sub(1)].1
    }

    /// Lifetime in seconds of particle `id` that dies at the update of step `die_at`
    /// (None for `NEVER`).
    pub fn lifetime(&self, id: u32, die_at: u32) -> Option<f64> {
        if die_at == crate::base::lifetime::NEVER {
            return None;
        }
        let lived = u64::from(die_at).wrapping_sub(self.spawn_step(id) & 0xffff_ffff) + 1;
        Some((lived & 0xffff_ffff) as f64 * self.dt)
    }

    /// Age in seconds of particle `id` after the steps done so far: (done - spawn step) dt.
    pub fn age(&self, id: u32) -> f64 {
        (self.next_step - self.spawn_step(id)) as f64 * self.dt
    }
}

/// A run of consecutive ids that one emitter spawned at one step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Segment {
    /// The step that spawned them.
    pub step: u64,
    /// The emitter.
    pub emitter: usize,
    /// The first id.
    pub first_id: u32,
    /// How many ids.
    pub count: u32,
    /// The emitter's own spawn counter at the first id.
    pub k_base: u32,
}

/// The spawn bookkeeping of a stateless effect: the segments that may still hold live
/// particles, per emitter in step order, each dropped once every particle in it has died.
#[derive(Clone, Debug)]
pub struct LiveSegments {
    /// Per emitter, the most steps one of its particles lives (None: forever).
    lives: Vec<Option<u32>>,
    per_emitter: Vec<std::collections::VecDeque<Segment>>,
    steps_done: u64,
}

impl LiveSegments {
    /// No segments yet, for emitters whose particles live at most `lives` steps.
    pub fn new(lives: Vec<Option<u32>>) -> Self {
        Self {
            per_emitter: vec![Default::default(); lives.len()],
            lives,
            steps_done: 0,
        }
    }

    /// Records one step's spawns (plans must come in order), then drops the segments whose
    /// particles have all died by its end: those `lives` or more steps old.
    pub fn record(&mut self, plan: &StepPlan) {
        self.record_noting(plan, &mut Vec::new());
    }

    /// [`Self::record`], also pushing the step's new segments onto `noted`.
    fn record_noting(&mut self, plan: &StepPlan, noted: &mut Vec<Segment>) {
        let mut id = plan.first_id;
        for (e, &(count, k_base)) in plan.emitters.iter().enumerate() {
            if count > 0 {
                let segment = Segment {
                    step: plan.step,
                    emitter: e,
                    first_id: id,
                    count,
                    k_base,
                };
                self.per_emitter[e].push_back(segment);
                noted.push(segment);
            }
            id += count;
        }
        self.advance_to(plan.step + 1);
    }

    /// Plans `steps` more steps of `schedule` and records them, skipping in O(1) steps that can
    /// spawn nothing (`skip_idle`).
    pub fn advance(&mut self, schedule: &mut Schedule, steps: u64) {
        self.advance_noting(schedule, steps, &mut Vec::new());
    }

    /// [`Self::advance`], also pushing every segment the steps spawn onto `noted` (those
    /// that die within them too).
    pub fn advance_noting(
        &mut self,
        schedule: &mut Schedule,
        steps: u64,
        noted: &mut Vec<Segment>,
    ) {
        for left in (1..=steps).rev() {
            if schedule.skip_idle(left) {
                self.advance_to(schedule.steps_done());
                return;
            }
            self.record_noting(&schedule.next_plan(), noted);
        }
    }

    /// Moves to `steps_done` steps with no spawns since the last recorded step (after
    /// [`Schedule::skip_idle`]), dropping the segments whose particles have all died.
    pub(crate) fn advance_to(&mut self, steps_done: u64) {
        self.steps_done = steps_done;
        for (segments, life) in self.per_emitter.iter_mut().zip(&self.lives) {
            if let Some(life) = life {
                while segments
                    .front()
                    .is_some_and(|s| self.steps_done - s.step >= u64::from(*life))
                {
                    segments.pop_front();
                }
            }
        }
    }

    /// Steps recorded so far.
    pub fn steps_done(&self) -> u64 {
        self.steps_done
    }

    /// The segments that may hold live particles, emitter by emitter, each in step order.
    pub fn iter(&self) -> impl Iterator<Item = &Segment> {
        self.per_emitter.iter().flatten()
    }

    /// Particles alive now: per segment, those whose drawn lifetime (the same integer draw as
    /// the kernels', see [`crate::base::lifetime`]) exceeds the segment's age in steps.
    pub fn alive(&self, ir: &EffectIr) -> u64 {
        let mut alive = 0;
        for seg in self.iter() {
            let age = self.steps_done - seg.step;
            let Some(l) = ir.emitters[seg.emitter].lifetime_steps else {
                alive += u64::from(seg.count);
                continue;
            };
            if age < u64::from(l.first) {
                alive += u64::from(seg.count);
            } else if age < u64::from(l.first) + u64::from(l.span) - 1 {
                // Within the lifetimes' spread: draw each one.
                alive += (0..seg.count)
                    .filter(|j| {
                        let u = crate::base::rng::rand_u32(
                            ir.seed_mix,
                            seg.first_id + j,
                            crate::base::rng::stream::LIFETIME,
                        );
                        u64::from(l.draw(u)) > age
                    })
                    .count() as u64;
            }
        }
        alive
    }

    /// Number of segments held.
    pub fn len(&self) -> usize {
        self.per_emitter.iter().map(|s| s.len()).sum()
    }

    /// Whether no segment is held.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}
