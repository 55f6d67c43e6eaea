//! The preview's simulation clock: fixed steps of the effect's dt, as many as the wall clock
//! (times the time scale) has passed: several in a frame when needed, none when the frame is
//! early, never ahead of real time. When the GPU cannot keep up, the time it could not
//! simulate is dropped (slow motion) rather than owed, so a slow frame never snowballs.

use std::time::Duration;

/// Most steps one frame may take; past that, the remaining time is dropped.
pub const MAX_STEPS_PER_FRAME: u64 = 32;

/// Real time to simulation steps.
#[derive(Clone, Debug, PartialEq)]
pub struct StepClock {
    dt: f64,
    /// Simulated time owed (s): real time passed, times the scale, not yet stepped.
    owed: f64,
    /// Simulation seconds per real second (halved and doubled by `[` and `]`).
    pub scale: f64,
    /// Paused: real time passes without steps.
    pub paused: bool,
    /// Steps asked for by hand (`.`), taken on the next frame even when paused.
    pending: u64,
}

impl StepClock {
    /// A clock for steps of `dt` seconds, running at real time.
    pub fn new(dt: f64) -> Self {
        Self {
            dt,
            owed: 0.0,
            scale: 1.0,
            paused: false,
            pending: 0,
        }
    }

    /// The steps due after `elapsed` real time since the last call.
    pub fn steps_due(&mut self, elapsed: Duration) -> u64 {
        let mut steps = std::mem::take(&mut self.pending);
        if !self.paused {
            self.owed += elapsed.as_secs_f64() * self.scale;
            let whole = (self.owed / self.dt).floor();
            let take = (whole as u64).min(MAX_STEPS_PER_FRAME);
            self.owed -= take as f64 * self.dt;
            if whole as u64 > take {
                // Behind: drop what cannot be simulated this frame instead of owing it.
                self.owed = self.owed.min(self.dt);
            }
            steps += take;
        }
        steps
    }

    /// Asks for one step on the next frame (whether paused or not).
    pub fn step_once(&mut self) {
        self.pending += 1;
    }

    /// Halves the time scale (down to 1/64).
    pub fn slower(&mut self) {
        self.scale = (self.scale * 0.5).max(1.0 / 64.0);
    }

    /// Doubles the time scale (up to 64).
    pub fn faster(&mut self) {
        self.scale = (self.scale * 2.0).min(64.0);
    }

    /// Back to t = 0 with nothing owed (the scale and pause stay).
    pub fn restart(&mut self) {
        self.owed = 0.0;
        self.pending = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 1.0 / 60.0;

    fn ms(x: f64) -> Duration {
        Duration::from_secs_f64(x / 1000.0)
    }

    #[test]
    fn steps_follow_real_time_and_carry_the_remainder() {
        let mut c = StepClock::new(DT);
        // An early frame: nothing yet.
        assert_eq!(c.steps_due(ms(10.0)), 0);
        // 10 + 10 ms: one step of 16.7 ms, 3.3 ms carried.
        assert_eq!(c.steps_due(ms(10.0)), 1);
        // A long frame takes several.
        assert_eq!(c.steps_due(ms(50.0)), 3);
        // Over a second of 60 Hz frames, 60 steps in all: never ahead of real time.
        let mut c = StepClock::new(DT);
        let total: u64 = (0..60).map(|_| c.steps_due(ms(1000.0 / 60.0))).sum();
        assert!((59..=60).contains(&total), "{total}");
    }

    #[test]
    fn a_stalled_frame_drops_time_instead_of_owing_it() {
        let mut c = StepClock::new(DT);
        assert_eq!(c.steps_due(ms(5000.0)), MAX_STEPS_PER_FRAME);
        // The next normal frame is back to about one step, not hundreds.
        assert!(c.steps_due(ms(16.7)) <= 2);
    }

    #[test]
    fn pause_step_scale_and_restart() {
        let mut c = StepClock::new(DT);
        c.paused = true;
        assert_eq!(c.steps_due(ms(100.0)), 0);
        c.step_once();
        assert_eq!(c.steps_due(ms(100.0)), 1);
        assert_eq!(c.steps_due(ms(100.0)), 0);
        c.paused = false;
        c.slower();
        // Half speed: 110 ms of real time is 55 ms of simulation, 3 steps.
        assert_eq!(c.steps_due(ms(110.0)), 3);
        c.faster();
        c.faster();
        assert_eq!(c.scale, 2.0);
        c.restart();
        assert_eq!(c.steps_due(ms(1.0)), 0);
        for _ in 0..20 {
            c.slower();
        }
        assert_eq!(c.scale, 1.0 / 64.0);
    }
}
