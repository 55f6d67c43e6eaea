//! Accuracy budgets (`accuracy`): the error an author accepts, stated in metres over the first
//! seconds of each particle's life. This module owns the budget's schema, its checks, its
//! lowered form and what the compiler chose to meet it; the choice itself is made by
//! `stages::passes::accuracy` from f64 runs of sample particles (`reference::calibrate`), and
//! `plume accuracy` checks the budget on the GPU.

use serde::{Deserialize, Deserializer};

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::Integrator;

/// An accuracy budget: each particle's position stays within `position` metres of its exact
/// (f64) trajectory over the first `over` seconds of its life (or its whole life, if shorter).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Accuracy {
    /// The largest distance (m) from the exact trajectory.
    pub position: f64,
    /// Seconds of each particle's life the budget covers.
    #[serde(default = "default_over")]
    pub over: f64,
}

fn default_over() -> f64 {
    4.0
}

/// Reads `accuracy: (position: .., over: ..)` (or `Accuracy(..)`) as a budget: the field is
/// optional, but written without `Some`.
pub fn deserialize_budget<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Accuracy>, D::Error> {
    Accuracy::deserialize(d).map(Some)
}

/// Checks a budget at `path`.
pub fn check(c: &mut Checker, path: &ValuePath, budget: &Accuracy) {
    c.positive(&path.field("position"), budget.position);
    c.positive(&path.field("over"), budget.over);
}

/// The budget, lowered, with what was chosen to meet it.
#[derive(Clone, Debug, PartialEq)]
pub struct AccuracyIr {
    /// The largest distance (m) from the exact trajectory.
    pub position: f64,
    /// Seconds of each particle's life it covers.
    pub over: f64,
    /// What the compiler chose and why; None until the accuracy pass has run.
    pub choice: Option<Choice>,
}

impl Accuracy {
    /// The lowered budget, nothing chosen yet.
    pub fn lower(&self) -> AccuracyIr {
        AccuracyIr {
            position: self.position,
            over: self.over,
            choice: None,
        }
    }
}

/// One way of stepping: an integrator and its substeps per step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scheme {
    /// The integrator.
    pub integrator: Integrator,
    /// Substeps per step.
    pub substeps: u32,
}

impl Scheme {
    /// Force evaluations per step: the cost the choice minimises (the update is bound by
    /// memory traffic only while a step evaluates the forces a few times; past that each
    /// evaluation adds arithmetic).
    pub fn evaluations(&self) -> u32 {
        stages(self.integrator) * self.substeps
    }

    /// `Verlet x2`.
    pub fn describe(&self) -> String {
        format!("{} x{}", self.integrator.name(), self.substeps)
    }
}

/// Force evaluations one substep of `integrator` makes.
pub fn stages(integrator: Integrator) -> u32 {
    match integrator {
        Integrator::Midpoint => 2,
        Integrator::Rk4 => 4,
        Integrator::Exact => 0,
        _ => 1,
    }
}

/// What the accuracy pass decided.
#[derive(Clone, Debug, PartialEq)]
pub enum Choice {
    /// The closed form: exact at any step, so the budget costs nothing.
    Exact,
    /// The cheapest scheme the f64 calibration found within the budget.
    Stepped {
        /// The scheme.
        scheme: Scheme,
        /// Its largest position error over the samples and the budget's seconds (m).
        estimated: f64,
        /// The next cheapest scheme of another integrator that also meets the budget, with
        /// its estimated error.
        runner_up: Option<(Scheme, f64)>,
        /// Sample particles the calibration followed.
        samples: usize,
        /// Milliseconds the calibration took.
        millis: f64,
    },
    /// The file chose the integrator and substeps: their estimated error, for the note (and
    /// a warning when it exceeds the budget).
    Kept {
        /// The file's scheme.
        scheme: Scheme,
        /// Its largest position error over the samples (m); None where no sample could be run.
        estimated: Option<f64>,
    },
    /// No particle of the group's own to calibrate with (a group fed by events alone): the
    /// file's scheme stands, and `plume accuracy` checks it.
    Uncalibrated {
        /// The file's scheme.
        scheme: Scheme,
    },
}

impl AccuracyIr {
    /// What was chosen, for the IR print and the WGSL's header: [`Self::describe`] without the
    /// runner-up and the calibration's time, so that it is the same on every run.
    pub fn reason(&self) -> String {
        let budget = format!("{:.1e} m over {} s", self.position, self.over);
        match &self.choice {
            Some(Choice::Stepped {
                scheme, estimated, ..
            }) => format!(
                "Auto with a budget of {budget}: {}, estimated {estimated:.1e} m in f64",
                scheme.describe()
            ),
            _ => self.describe(),
        }
    }

    /// The line `plume check` and `plume compile` print: what was chosen, with numbers.
    pub fn describe(&self) -> String {
        let budget = format!("{:.1e} m over {} s", self.position, self.over);
        match &self.choice {
            None => format!("budget {budget}: not yet chosen"),
            Some(Choice::Exact) => {
                format!("accuracy: Exact (the closed form), error 0 of {budget}; no stepping")
            }
            Some(Choice::Stepped {
                scheme,
                estimated,
                runner_up,
                samples,
                millis,
            }) => {
                let evaluations = match scheme.evaluations() {
                    1 => "1 force evaluation".to_string(),
                    n => format!("{n} force evaluations"),
                };
                let mut line = format!(
                    "accuracy: {}, estimated {estimated:.1e} m of {budget} ({evaluations} a step)",
                    scheme.describe()
                );
                if let Some((other, e)) = runner_up {
                    line += &format!(
                        "; {} would cost {:.1}x (estimated {e:.1e} m)",
                        other.describe(),
                        f64::from(other.evaluations()) / f64::from(scheme.evaluations())
                    );
                }
                line += &format!("; calibrated on {samples} particles in f64 in {millis:.0} ms");
                line
            }
            Some(Choice::Kept { scheme, estimated }) => match estimated {
                Some(e) => format!(
                    "accuracy: {} as the file says, estimated {e:.1e} m of {budget}",
                    scheme.describe()
                ),
                None => format!(
                    "accuracy: {} as the file says; no sample particles to estimate its error against {budget}",
                    scheme.describe()
                ),
            },
            Some(Choice::Uncalibrated { scheme }) => format!(
                "accuracy: {} (no particles of its own to calibrate with: fed by events); `plume accuracy` checks {budget}",
                scheme.describe()
            ),
        }
    }
}
