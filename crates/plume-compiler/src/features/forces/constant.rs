//! A constant acceleration: what Gravity and noiseless Wind lower to, folded into one term.

use glam::DVec3;

use super::{ForceTerm, Linear};
use crate::base::writer::{vec3_lit, Writer};

/// `a = accel` everywhere.
#[derive(Clone, Debug, PartialEq)]
pub struct ConstantTerm {
    /// The acceleration (m/s²).
    pub accel: DVec3,
    /// Source forces.
    pub origins: Vec<usize>,
}

impl ForceTerm for ConstantTerm {
    fn origins(&self) -> &[usize] {
        &self.origins
    }
    fn describe(&self) -> String {
        format!(
            "Constant a = ({}, {}, {})",
            self.accel.x, self.accel.y, self.accel.z
        )
    }
    fn can_act(&self) -> bool {
        self.accel != DVec3::ZERO
    }
    fn linear(&self) -> Option<Linear> {
        Some(Linear {
            accel: self.accel,
            ..Linear::default()
        })
    }
    fn emit_wgsl(&self, w: &mut Writer) {
        w.line(format!("a += {};", vec3_lit(self.accel)));
    }
    fn accel(&self, _x: DVec3, _v: DVec3, _t: f64) -> DVec3 {
        self.accel
    }
}
