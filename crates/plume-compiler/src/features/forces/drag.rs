//! Linear drag: `a = -k (v - fluid)`. Several drags merge into one with k = Σk and
//! fluid = Σ(k fluid) / Σk, the same acceleration for every v.

use glam::DVec3;
use serde::Deserialize;

use super::{ForceTerm, Stiffness};
use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::Vec3;
use crate::base::writer::{f32_lit, vec3_lit, Writer};

fn still() -> Vec3 {
    Vec3(0.0, 0.0, 0.0)
}

/// `Drag(k, fluid)` as written.
/// Field names, as written in effect files.
pub(crate) const FIELDS: &[&str] = &["k", "fluid"];

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Drag {
    /// Drag rate (1/s), >= 0.
    pub k: f64,
    /// Velocity of the fluid (m/s); default still air.
    #[serde(default = "still")]
    pub fluid: Vec3,
}

impl Drag {
    /// Checks `k >= 0` and a finite fluid velocity.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        c.non_negative(&path.field("k"), self.k);
        c.vec3(&path.field("fluid"), self.fluid);
    }

    /// Lowers to a drag term.
    pub(crate) fn lower(&self, origin: usize) -> DragTerm {
        DragTerm {
            k: self.k,
            fluid: self.fluid.d(),
            origins: vec![origin],
        }
    }
}

/// `a = -k (v - fluid)`.
#[derive(Clone, Debug, PartialEq)]
pub struct DragTerm {
    /// Rate (1/s).
    pub k: f64,
    /// Fluid velocity (m/s).
    pub fluid: DVec3,
    /// Source forces.
    pub origins: Vec<usize>,
}

impl DragTerm {
    /// Merges two drags into one with the same acceleration for every velocity.
    pub fn merge(&self, other: &DragTerm) -> DragTerm {
        let k = self.k + other.k;
        let fluid = if k > 0.0 {
            (self.fluid * self.k + other.fluid * other.k) / k
        } else {
            DVec3::ZERO
        };
        let mut origins = self.origins.clone();
        origins.extend_from_slice(&other.origins);
        DragTerm { k, fluid, origins }
    }
}

impl ForceTerm for DragTerm {
    fn origins(&self) -> &[usize] {
        &self.origins
    }
    fn describe(&self) -> String {
        format!(
            "Drag k = {} fluid = ({}, {}, {})",
            self.k, self.fluid.x, self.fluid.y, self.fluid.z
        )
    }
    fn linear(&self) -> Option<super::Linear> {
        Some(super::Linear {
            k: self.k,
            k_fluid: self.k * self.fluid,
            ..Default::default()
        })
    }
    fn can_act(&self) -> bool {
        self.k > 0.0
    }
    fn uses_velocity(&self) -> bool {
        true
    }
    fn stiffness(&self) -> Stiffness {
        Stiffness::Damping(self.k)
    }
    fn emit_wgsl(&self, w: &mut Writer) {
        if self.fluid == DVec3::ZERO {
            w.line(format!("a -= {} * v;", f32_lit(self.k)));
        } else {
            w.line(format!(
                "a += {} * ({} - v);",
                f32_lit(self.k),
                vec3_lit(self.fluid)
            ));
        }
    }
    fn accel(&self, _x: DVec3, v: DVec3, _t: f64) -> DVec3 {
        -self.k * (v - self.fluid)
    }
}
