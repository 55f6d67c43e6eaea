//! Accuracy budgets (`accuracy`): the error an author accepts, stated in metres over the first
//! seconds of each particle's life. This module owns the budget's schema, its checks, its
//! lowered form and what the compiler chose to meet it; the choice itself is made by
//! `calibration::accuracy` from f64 runs of sample particles (`reference::calibrate`), and
//! `plume accuracy` checks the budget on the GPU.

use glam::DVec3;
use serde::{Deserialize, Deserializer};

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::Integrator;

/// An accuracy budget: each particle's position stays within `position` metres of its exact
/// (f64) trajectory, or its image within `pixels` of the exact one's as the effect's camera
/// sees it in an image `height` pixels tall, over the first `over` seconds of its life (or
/// its whole life, if shorter). One of `position` and `pixels`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Accuracy {
    /// The largest distance (m) from the exact trajectory.
    #[serde(default, deserialize_with = "crate::base::values::plain_some")]
    pub position: Option<f64>,
    /// The largest distance on screen (pixels) from the exact trajectory's image.
    #[serde(default, deserialize_with = "crate::base::values::plain_some")]
    pub pixels: Option<f64>,
    /// The image height (pixels) a pixel budget is for.
    #[serde(default = "default_height")]
    pub height: u32,
    /// Seconds of each particle's life the budget covers.
    #[serde(default = "default_over")]
    pub over: f64,
}

fn default_over() -> f64 {
    4.0
}

fn default_height() -> u32 {
    720
}

/// Reads `accuracy: (position: .., over: ..)` (or `Accuracy(..)`) as a budget: the field is
/// optional, but written without `Some`.
pub(crate) fn deserialize_budget<'de, D: Deserializer<'de>>(
    d: D,
) -> Result<Option<Accuracy>, D::Error> {
    Accuracy::deserialize(d).map(Some)
}

/// The most steps a budget's window may span: the compiler runs its samples through every one
/// of them for each scheme it tries (20,000 steps of 1/60 s are 5.5 minutes).
pub(crate) const MAX_WINDOW_STEPS: f64 = 20_000.0;

/// Checks a budget at `path`, for steps of `dt` seconds.
pub(crate) fn check(c: &mut Checker, path: &ValuePath, budget: &Accuracy, dt: f64) {
    match (budget.position, budget.pixels) {
        (Some(p), None) => {
            c.positive(&path.field("position"), p);
        }
        (None, Some(p)) => {
            c.positive(&path.field("pixels"), p);
        }
        (Some(_), Some(_)) => c.error(
            &path.field("pixels"),
            "a budget is in metres (`position`) or on screen (`pixels`), not both",
        ),
        (None, None) => c.error(
            path,
            "a budget needs `position` (metres) or `pixels` (on screen through the effect's camera)",
        ),
    }
    if budget.height == 0 {
        c.error(&path.field("height"), "must be at least 1 pixel");
    }
    c.positive(&path.field("over"), budget.over);
    if dt > 0.0 && budget.over / dt > MAX_WINDOW_STEPS {
        c.error(
            &path.field("over"),
            format!(
                "{} s is {:.0} steps of {dt} s; a budget is calibrated over at most {MAX_WINDOW_STEPS} steps ({:.1} s at this dt)",
                budget.over,
                (budget.over / dt).ceil(),
                MAX_WINDOW_STEPS * dt
            ),
        );
    }
}

/// What a budget is measured in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Measure {
    /// Metres, anywhere.
    Metres,
    /// Pixels of an image this many pixels tall, through the effect's camera.
    Pixels {
        /// The image's height.
        height: u32,
    },
}

/// The budget, lowered, with what was chosen to meet it.
#[derive(Clone, Debug, PartialEq)]
pub struct AccuracyIr {
    /// The largest error, in `measure`'s unit.
    pub limit: f64,
    /// What the error is measured in.
    pub measure: Measure,
    /// Seconds of each particle's life it covers.
    pub over: f64,
    /// What the compiler chose and why; None until the accuracy pass has run.
    pub choice: Option<Choice>,
    /// Whether the budget leaves room to store each particle's motion (velocity, or Verlet's
    /// displacement) in 16-bit floats: the accuracy pass measures the chosen scheme with
    /// its motion rounded to half precision after every step, and keeps the halves when that
    /// error stays within the scheme's share of the budget too.
    pub half_motion: bool,
    /// The chosen scheme's estimated error with its motion in halves, where it was measured.
    pub half_estimate: Option<f64>,
    /// For a group fed by events alone, the sample it is calibrated on: a burst of its event's
    /// spawn rule at the parent's first firing (`EffectSpec::sample_burst`). None: the group's own
    /// emitters' first particles.
    pub sample_burst: Option<crate::features::bursts::Burst>,
    /// The camera a pixel budget is measured through when it is not the effect's own (a
    /// host's: `CompileOptions::accuracy_camera`).
    pub(crate) host_camera: Option<BudgetCamera>,
    /// Whether the choice was taken from an earlier calibration of the same content in this
    /// process (`calibration::accuracy::choose`) rather than calibrated here.
    pub remembered: bool,
    /// The effect's content, its seed aside, as the key a calibration is remembered by (set
    /// by the compile driver; None: not remembered).
    pub content: Option<u64>,
}

/// A camera a pixel budget is measured through (a pinhole at `eye` looking at `target`,
/// `fov_y` degrees tall).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BudgetCamera {
    /// Where it is (m).
    pub eye: DVec3,
    /// What it looks at (m).
    pub target: DVec3,
    /// Vertical field of view (degrees).
    pub fov_y: f64,
}

impl Accuracy {
    /// The lowered budget, nothing chosen yet (checked: one of `position` and `pixels`).
    pub fn lower(&self) -> AccuracyIr {
        let (limit, measure) = match (self.position, self.pixels) {
            (_, Some(px)) => (
                px,
                Measure::Pixels {
                    height: self.height,
                },
            ),
            (p, None) => (p.unwrap_or(0.0), Measure::Metres),
        };
        AccuracyIr {
            limit,
            measure,
            over: self.over,
            choice: None,
            half_motion: false,
            half_estimate: None,
            sample_burst: None,
            host_camera: None,
            remembered: false,
            content: None,
        }
    }
}

/// Where a camera puts points in an image: the pixel distance between two points' images (a
/// pinhole camera looking from `eye` at `target`, `fov_y` degrees tall, `height` pixels tall).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Screen {
    eye: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    /// Pixels per unit of (lateral offset / depth).
    scale: f64,
}

impl Screen {
    /// The camera at `eye` looking at `target` (world up +y; +z where it looks straight up or
    /// down).
    pub fn new(eye: DVec3, target: DVec3, fov_y: f64, height: u32) -> Self {
        let forward = (target - eye).try_normalize().unwrap_or(DVec3::NEG_Z);
        let right = forward
            .cross(DVec3::Y)
            .try_normalize()
            .unwrap_or_else(|| forward.cross(DVec3::Z).normalize());
        Self {
            eye,
            forward,
            right,
            up: right.cross(forward),
            scale: f64::from(height) / (2.0 * (fov_y.to_radians() / 2.0).tan()),
        }
    }

    /// The depth of `x` along the view axis (m).
    pub fn depth(&self, x: DVec3) -> f64 {
        (x - self.eye).dot(self.forward)
    }

    /// `x`'s image in pixels from the image's centre; None behind or at the eye (not drawn).
    fn image(&self, x: DVec3) -> Option<(f64, f64)> {
        let d = x - self.eye;
        let z = d.dot(self.forward);
        (z > 1e-6).then(|| {
            (
                self.scale * d.dot(self.right) / z,
                self.scale * d.dot(self.up) / z,
            )
        })
    }

    /// The pixel distance between `a`'s and `b`'s images; 0 where either is not in front of
    /// the camera.
    pub fn pixels(&self, a: DVec3, b: DVec3) -> f64 {
        match (self.image(a), self.image(b)) {
            (Some(p), Some(q)) => ((p.0 - q.0).powi(2) + (p.1 - q.1).powi(2)).sqrt(),
            _ => 0.0,
        }
    }

    /// Pixels a lateral shift of `metres` at `x` moves its image by (0 behind the camera).
    pub(crate) fn pixels_of(&self, metres: f64, x: DVec3) -> f64 {
        let z = self.depth(x);
        if z > 1e-6 {
            self.scale * metres / z
        } else {
            0.0
        }
    }
}

/// One way of stepping: an integrator and its substeps per step.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
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
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
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
    /// No particle of the group's own to calibrate with (a group fed by events alone whose
    /// parent never fired in the f64 run that looks for a sample burst): the file's scheme
    /// stands, and `plume accuracy` checks it.
    Uncalibrated {
        /// The file's scheme.
        scheme: Scheme,
    },
}

impl AccuracyIr {
    /// The unit of the budget and its estimates: `m` or `px`.
    pub fn unit(&self) -> &'static str {
        match self.measure {
            Measure::Metres => "m",
            Measure::Pixels { .. } => "px",
        }
    }

    /// `1.0e-2 m over 4 s`, or `5.0e-1 px (a 720-pixel image from the effect's camera) over 4 s`.
    pub fn budget(&self) -> String {
        match self.measure {
            Measure::Metres => format!("{:.1e} m over {} s", self.limit, self.over),
            Measure::Pixels { height } => format!(
                "{:.1e} px (a {height}-pixel image from the {} camera) over {} s",
                self.limit,
                if self.host_camera.is_some() {
                    "host's"
                } else {
                    "effect's"
                },
                self.over
            ),
        }
    }

    /// What was chosen, for the IR print and the WGSL's header: [`Self::describe`] without the
    /// runner-up and the calibration's time, so that it is the same on every run.
    pub fn reason(&self) -> String {
        let budget = self.budget();
        match &self.choice {
            Some(Choice::Stepped {
                scheme, estimated, ..
            }) => format!(
                "Auto with a budget of {budget}: {}, estimated {estimated:.1e} {} in f64{}",
                scheme.describe(),
                self.unit(),
                if self.half_motion {
                    "; motion stored in 16-bit floats"
                } else {
                    ""
                }
            ),
            _ => self.describe(),
        }
    }

    /// The line `plume check` and `plume compile` print: what was chosen, with numbers.
    pub fn describe(&self) -> String {
        let budget = self.budget();
        let unit = self.unit();
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
                    "accuracy: {}, estimated {estimated:.1e} {unit} of {budget} ({evaluations} a step)",
                    scheme.describe()
                );
                if let Some((other, e)) = runner_up {
                    line += &format!(
                        "; {} would cost {:.1}x (estimated {e:.1e} {unit})",
                        other.describe(),
                        f64::from(other.evaluations()) / f64::from(scheme.evaluations())
                    );
                }
                match (self.half_motion, self.half_estimate) {
                    (true, Some(e)) => {
                        line += &format!(
                            "; motion stored in 16-bit floats (estimated {e:.1e} {unit} with them)"
                        )
                    }
                    (false, Some(e)) => {
                        line += &format!(
                            "; motion kept in 32-bit floats (16-bit would stray {e:.1e} {unit})"
                        )
                    }
                    _ => {}
                }
                let sample = match &self.sample_burst {
                    Some(b) => format!(
                        " of a sample burst at ({:.2}, {:.2}, {:.2}), where its parent first fires,",
                        b.offset[0], b.offset[1], b.offset[2]
                    ),
                    None => String::new(),
                };
                line += &format!(
                    "; calibrated on {samples} particles{sample} in f64 in {millis:.0} ms{}",
                    if self.remembered {
                        " (remembered from an earlier compile of the same content)"
                    } else {
                        ""
                    }
                );
                line
            }
            Some(Choice::Kept { scheme, estimated }) => match estimated {
                Some(e) => format!(
                    "accuracy: {} as the file says, estimated {e:.1e} {unit} of {budget}",
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
