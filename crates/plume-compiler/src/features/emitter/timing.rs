//! When an emitter spawns: its start, how long it runs, and its burst's repeats, turned into
//! whole steps once (in f64, never accumulated) so that the schedule the GPU runtime and the
//! f64 reference share (`stages/schedule.rs`) asks only integer questions of it.
//!
//! A time t becomes the first step whose start k·dt is not before it: k = ⌈t/dt − 1e-9⌉ (the
//! 1e-9, as for lifetimes, keeps a time written in decimal that is a whole number of steps
//! from rounding up a step). The emitter's rate runs in the steps [start, end), its burst
//! number n fires at the step of `start + n · every` for n < `cycles`, before the end.

use serde::de::{self, Deserialize, Deserializer, Unexpected, Visitor};

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::rng::pcg;

/// Seconds between a burst's repeats: a number, or a range `(lo, hi)` from which each gap is
/// drawn anew (in whole steps, uniform from round(lo / dt) to round(hi / dt), at least one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Every {
    /// The same gap each time.
    Fixed(f64),
    /// A gap drawn for each repeat.
    Range(f64, f64),
}

impl Every {
    /// The shortest gap (s).
    pub fn shortest(self) -> f64 {
        match self {
            Every::Fixed(s) | Every::Range(s, _) => s,
        }
    }

    /// The mean gap (s), for estimates.
    pub fn mean(self) -> f64 {
        match self {
            Every::Fixed(s) => s,
            Every::Range(lo, hi) => 0.5 * (lo + hi),
        }
    }
}

impl<'de> Deserialize<'de> for Every {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct EveryVisitor;
        impl<'de> Visitor<'de> for EveryVisitor {
            type Value = Every;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("seconds, or a range of seconds `(lo, hi)` drawn anew for each repeat")
            }
            fn visit_f64<E: de::Error>(self, x: f64) -> Result<Every, E> {
                Ok(Every::Fixed(x))
            }
            fn visit_u64<E: de::Error>(self, x: u64) -> Result<Every, E> {
                Ok(Every::Fixed(x as f64))
            }
            fn visit_i64<E: de::Error>(self, x: i64) -> Result<Every, E> {
                Ok(Every::Fixed(x as f64))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Every, E> {
                Err(E::invalid_type(Unexpected::Str(v), &self))
            }
            fn visit_seq<A: de::SeqAccess<'de>>(self, mut seq: A) -> Result<Every, A::Error> {
                let mut next = |i| -> Result<f64, A::Error> {
                    seq.next_element()?
                        .ok_or_else(|| de::Error::invalid_length(i, &self))
                };
                let (lo, hi) = (next(0)?, next(1)?);
                Ok(Every::Range(lo, hi))
            }
        }
        d.deserialize_any(EveryVisitor)
    }
}

/// The most steps a time may lie ahead (as for lifetimes): 2^31.
const MAX_STEPS: f64 = 2_147_483_648.0;

/// The step at which a time `seconds` (>= 0) after step 0 has come, for steps of `dt`.
fn step_of(seconds: f64, dt: f64) -> u64 {
    (seconds / dt - 1e-9).ceil().max(0.0) as u64
}

/// An emitter's timing in whole steps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpawnTiming {
    /// Seconds before the emitter starts.
    pub start: f64,
    /// The first step at which it spawns.
    pub(crate) start_step: u64,
    /// The first step at which it spawns no more (None: it runs for ever).
    pub(crate) end_step: Option<u64>,
    /// Seconds between its burst's repeats, the shortest when they are drawn (None: the burst
    /// fires once).
    pub every: Option<f64>,
    /// Drawn repeats' gaps in whole steps, (fewest, most), drawn with `key`.
    pub(crate) every_steps: Option<(u64, u64)>,
    /// The key of this emitter's draws of gaps and burst counts (set by the IR's lowering,
    /// distinct per emitter).
    pub key: u32,
    /// How many times the burst fires (None: for as long as the emitter runs).
    pub cycles: Option<u32>,
    /// Seconds per step.
    pub dt: f64,
}

impl SpawnTiming {
    /// The timing of the file's fields (after `check` passed), for steps of `dt`.
    pub fn new(
        start: f64,
        duration: Option<f64>,
        every: Option<Every>,
        cycles: Option<u32>,
        dt: f64,
    ) -> Self {
        let gap = |s: f64| ((s / dt).round() as u64).max(1);
        Self {
            start,
            start_step: step_of(start, dt),
            end_step: duration.map(|d| step_of(start + d, dt)),
            every: every.map(Every::shortest),
            every_steps: match every {
                Some(Every::Range(lo, hi)) => Some((gap(lo), gap(hi).max(gap(lo)))),
                _ => None,
            },
            key: 0,
            cycles: match every {
                Some(_) => cycles,
                None => Some(1),
            },
            dt,
        }
    }

    /// Spawns from step 0 for ever, the burst once: what an emitter without timing fields does.
    pub(crate) fn is_plain(&self) -> bool {
        self.start_step == 0
            && self.end_step.is_none()
            && self.every.is_none()
            && self.cycles == Some(1)
    }

    /// Whether the rate runs at `step`.
    pub(crate) fn rate_runs(&self, step: u64) -> bool {
        step >= self.start_step && self.end_step.is_none_or(|end| step < end)
    }

    /// Whether the rate runs at `step` or any later step.
    pub(crate) fn rate_runs_after(&self, step: u64) -> bool {
        self.end_step.is_none_or(|end| step < end)
    }

    /// The step at which burst number `n` fires, or None when it never does (past `cycles`
    /// or the end).
    pub fn burst_step(&self, n: u32) -> Option<u64> {
        if self.cycles.is_some_and(|c| n >= c) {
            return None;
        }
        let step = match (n, self.every, self.every_steps) {
            (0, _, _) => self.start_step,
            // Drawn gaps: whole steps, summed exactly.
            (_, _, Some((lo, hi))) => (0..n).fold(self.start_step, |step, i| {
                step.saturating_add(lo + u64::from(self.draw(i, 0)) % (hi - lo + 1))
            }),
            (_, Some(every), None) => step_of(self.start + f64::from(n) * every, self.dt),
            (_, None, _) => return None,
        };
        self.end_step.is_none_or(|end| step < end).then_some(step)
    }

    /// The emitter's `i`-th draw of purpose `purpose` (0: a gap, 1: a burst count): a PCG hash
    /// of its key, the number and the purpose, the same for the GPU runtime and the reference,
    /// which share the schedule.
    pub fn draw(&self, i: u32, purpose: u32) -> u32 {
        pcg(pcg(self.key ^ purpose.wrapping_mul(0x9e37_79b9)).wrapping_add(i))
    }

    /// The count of burst number `n` of an emitter whose burst is drawn from `[lo, hi]`.
    pub fn burst_count(&self, n: u32, (lo, hi): (u32, u32)) -> u32 {
        let span = u64::from(hi - lo) + 1;
        lo + (u64::from(self.draw(n, 1)) % span) as u32
    }

    /// The most bursts whose particles can be alive at once when they live at most `life`
    /// steps (None: for ever); None when that is unbounded (bursts for ever of immortal
    /// particles).
    pub(crate) fn bursts_alive(&self, life: Option<u32>) -> Option<u64> {
        let total = match (self.cycles, self.every, self.end_step) {
            (Some(c), _, _) => Some(u64::from(c)),
            (None, Some(every), Some(end)) => {
                let span = end.saturating_sub(self.start_step) as f64 * self.dt;
                Some((span / every).floor() as u64 + 1)
            }
            (None, _, None) => None,
            (None, None, Some(_)) => Some(1),
        };
        let window = match (life, self.every) {
            // Bursts at least `every` apart, within any `life` consecutive steps: one more
            // for the rounding of their times to steps.
            (Some(life), Some(every)) => {
                Some((f64::from(life) * self.dt / every).floor() as u64 + 2)
            }
            _ => None,
        };
        match (total, window) {
            (Some(t), Some(w)) => Some(t.min(w)),
            (t, w) => t.or(w),
        }
    }

    /// The IR's words for what is not plain (empty when `is_plain`).
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if self.start_step > 0 {
            parts.push(format!("from step {}", self.start_step));
        }
        if let Some(end) = self.end_step {
            parts.push(format!("until step {end}"));
        }
        if let Some(every) = self.every {
            let cycles = match self.cycles {
                Some(c) => format!("{c} times"),
                None => "for ever".into(),
            };
            match self.every_steps {
                Some((lo, hi)) => {
                    parts.push(format!("burst every {lo} to {hi} steps (drawn), {cycles}"))
                }
                None => parts.push(format!("burst every {every} s, {cycles}")),
            }
        }
        parts.join(", ")
    }
}

/// Records in `c` what is wrong with an emitter's timing fields at `path` (the emitter), for
/// steps of `dt`: `burst` is its burst, which `every` repeats.
pub(super) fn check(
    c: &mut Checker,
    path: &ValuePath,
    (start, duration, every, cycles): (f64, Option<f64>, Option<Every>, Option<u32>),
    burst: u32,
    dt: f64,
) {
    let ahead = |c: &mut Checker, at: &ValuePath, seconds: f64| {
        if dt > 0.0 && seconds / dt >= MAX_STEPS {
            c.error(
                at,
                format!("is more than 2^31 steps of dt = {dt} s, got {seconds}"),
            );
        }
    };
    if c.non_negative(&path.field("start"), start) {
        ahead(c, &path.field("start"), start);
    }
    if let Some(d) = duration {
        let at = path.field("duration");
        if c.positive(&at, d) {
            ahead(c, &at, start + d);
        }
    }
    if let Some(Every::Range(lo, hi)) = every {
        let at = path.field("every");
        let min = at.component(0, "min");
        if c.range(&at, crate::base::values::Range(lo, hi)) && c.positive(&min, lo) {
            ahead(c, &at.component(1, "max"), hi);
            if dt > 0.0 && lo < dt * (1.0 - 1e-9) {
                c.error(
                    &min,
                    format!(
                        "a burst repeats at most once a step: must be >= dt = {dt} s, got {lo}"
                    ),
                );
            }
        }
        if burst == 0 {
            c.error(&at, "repeats the burst, but `burst` is 0");
        }
    }
    if let Some(Every::Fixed(every)) = every {
        let at = path.field("every");
        if c.positive(&at, every) {
            ahead(c, &at, every);
            if dt > 0.0 && every < dt * (1.0 - 1e-9) {
                c.error(
                    &at,
                    format!("a burst repeats at most once a step: must be >= dt = {dt} s, got {every} (use a rate to spawn more often)"),
                );
            }
        }
        if burst == 0 {
            c.error(&at, "repeats the burst, but `burst` is 0");
        }
    }
    if let Some(n) = cycles {
        let at = path.field("cycles");
        if every.is_none() {
            c.error(&at, "counts a burst's repeats: it needs `every`");
        } else if n == 0 {
            c.error(&at, "must be >= 1, got 0");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_timing_fires_the_burst_at_step_0_and_runs_for_ever() {
        let t = SpawnTiming::new(0.0, None, None, None, 0.1);
        assert!(t.is_plain());
        assert_eq!(t.burst_step(0), Some(0));
        assert_eq!(t.burst_step(1), None);
        assert!(t.rate_runs(0) && t.rate_runs(1_000_000));
        assert_eq!(t.describe(), "");
    }

    #[test]
    fn repeats_start_and_end_land_on_whole_steps() {
        // dt 0.1: start 0.25 s is step 3 (0.3 s is the first step not before it), 1.0 s of
        // duration ends at 1.25 s: step 13. Bursts every 0.5 s: 0.25, 0.75, 1.25 (the end).
        let t = SpawnTiming::new(0.25, Some(1.0), Some(Every::Fixed(0.5)), None, 0.1);
        assert_eq!((t.start_step, t.end_step), (3, Some(13)));
        assert_eq!(t.burst_step(0), Some(3));
        assert_eq!(t.burst_step(1), Some(8));
        assert_eq!(t.burst_step(2), None, "1.25 s is the end");
        assert!(!t.rate_runs(2) && t.rate_runs(3) && t.rate_runs(12) && !t.rate_runs(13));
        assert!(t.rate_runs_after(12) && !t.rate_runs_after(13));
        // A time that is a whole number of steps, written in decimal, does not round up.
        let t = SpawnTiming::new(0.3, None, Some(Every::Fixed(0.7)), Some(2), 0.1);
        assert_eq!(
            (t.burst_step(0), t.burst_step(1), t.burst_step(2)),
            (Some(3), Some(10), None)
        );
    }

    #[test]
    fn bursts_alive_at_once_are_bounded_by_cycles_lives_and_the_end() {
        let t = SpawnTiming::new(0.0, None, Some(Every::Fixed(1.0)), Some(3), 0.1);
        assert_eq!(t.bursts_alive(None), Some(3));
        assert_eq!(t.bursts_alive(Some(15)), Some(3));
        let t = SpawnTiming::new(0.0, None, Some(Every::Fixed(1.0)), None, 0.1);
        assert_eq!(t.bursts_alive(None), None, "for ever, immortal");
        assert_eq!(t.bursts_alive(Some(25)), Some(4));
        let t = SpawnTiming::new(0.0, Some(3.0), Some(Every::Fixed(1.0)), None, 0.1);
        assert_eq!(t.bursts_alive(None), Some(4));
    }
}
