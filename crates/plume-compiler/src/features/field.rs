//! Baked force fields (the thesis "Particle Systems Using 3D Vector Fields"): the forces that
//! depend only on position (and time) are evaluated at the nodes of a 3D grid by a `bake`
//! kernel, once or every step, and the update samples the grid instead of evaluating them.
//!
//! Nodes sit at min + (i / (n - 1)) (max - min) for i in 0..n on each axis, both bounds
//! included. A particle at x has grid coordinates u = (x - min) / (max - min) (n - 1):
//! - Nearest: the node at round(u);
//! - Trilinear: the 8 nodes around u, weighted by the fractional parts.
//!
//! Outside the bounds (any u outside [0, n - 1]) the forces are evaluated per particle as if
//! there were no grid, so a field never changes the physics far from where it was baked, only
//! the cost. Velocity-dependent terms (drag) and constant terms always stay evaluated.

use glam::DVec3;
use serde::Deserialize;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::Vec3;
use crate::base::writer::{u32_lit, vec3_lit, Writer};
use crate::features::forces::Term;

/// How grid values are read between nodes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Filter {
    /// The nearest node.
    Nearest,
    /// Trilinear interpolation of the 8 surrounding nodes.
    #[default]
    Trilinear,
}

/// When the grid is baked.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Refresh {
    /// Once, at time 0 (only for fields that do not change with time).
    #[default]
    Once,
    /// At the start of every step, at the step's time.
    EveryStep,
}

/// `field:` as written: evaluate forces per particle (the default) or bake them into a grid.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
pub enum Field {
    /// Every force evaluated per particle, per substep.
    #[default]
    Evaluated,
    /// Position-dependent forces baked into a grid and sampled.
    Baked {
        /// Nodes per axis, each at least 2.
        resolution: (u32, u32, u32),
        /// The grid's lower corner (m).
        min: Vec3,
        /// The grid's upper corner (m).
        max: Vec3,
        /// Nearest or trilinear sampling.
        #[serde(default)]
        filter: Filter,
        /// Once or every step.
        #[serde(default)]
        refresh: Refresh,
    },
}

/// The most nodes a grid may have: 256³ (256 MiB of vec4<f32>), past every binding limit
/// anyway on most adapters.
pub(crate) const MAX_NODES: u64 = 256 * 256 * 256;

impl Field {
    /// Checks resolution, bounds, and that a time-dependent force is baked every step.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker, time_dependent: Option<usize>) {
        let Field::Baked {
            resolution,
            min,
            max,
            refresh,
            ..
        } = self
        else {
            return;
        };
        let p = path.variant("Baked");
        let (nx, ny, nz) = *resolution;
        if nx < 2 || ny < 2 || nz < 2 {
            c.error(
                &p.field("resolution"),
                format!("every axis needs at least 2 nodes, got ({nx}, {ny}, {nz})"),
            );
        } else if u64::from(nx)
            .checked_mul(u64::from(ny))
            .and_then(|n| n.checked_mul(u64::from(nz)))
            .is_none_or(|n| n > MAX_NODES)
        {
            c.error(
                &p.field("resolution"),
                format!("({nx}, {ny}, {nz}) is more than {MAX_NODES} nodes (256³)"),
            );
        }
        let finite = c.vec3(&p.field("min"), *min) & c.vec3(&p.field("max"), *max);
        if finite && !(min.0 < max.0 && min.1 < max.1 && min.2 < max.2) {
            c.error(
                &p.field("max"),
                format!(
                    "must be above min on every axis, got min ({}, {}, {}) and max ({}, {}, {})",
                    min.0, min.1, min.2, max.0, max.1, max.2
                ),
            );
        }
        if let (Refresh::Once, Some(i)) = (refresh, time_dependent) {
            c.error(
                &p.field("refresh"),
                format!("forces[{i}] changes with time (noise), so a grid baked once would freeze it: use refresh: EveryStep"),
            );
        }
    }

    /// Lowers to the IR's field, or None when forces are evaluated.
    pub(crate) fn lower(&self) -> Option<FieldIr> {
        match self {
            Field::Evaluated => None,
            Field::Baked {
                resolution,
                min,
                max,
                filter,
                refresh,
            } => Some(FieldIr {
                resolution: [resolution.0, resolution.1, resolution.2],
                min: min.d(),
                max: max.d(),
                filter: *filter,
                refresh: *refresh,
            }),
        }
    }
}

/// A baked field in the IR.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldIr {
    /// Nodes per axis.
    pub resolution: [u32; 3],
    /// Lower corner (m).
    pub min: DVec3,
    /// Upper corner (m).
    pub max: DVec3,
    /// Sampling.
    pub filter: Filter,
    /// When it is baked.
    pub refresh: Refresh,
}

impl FieldIr {
    /// Number of nodes.
    pub fn nodes(&self) -> u64 {
        self.resolution.iter().map(|&n| u64::from(n)).product()
    }

    /// One line for `--emit ir`.
    pub fn describe(&self) -> String {
        format!(
            "baked field {}x{}x{} over ({}, {}, {}) .. ({}, {}, {}), {:?}, {:?}",
            self.resolution[0],
            self.resolution[1],
            self.resolution[2],
            self.min.x,
            self.min.y,
            self.min.z,
            self.max.x,
            self.max.y,
            self.max.z,
            self.filter,
            self.refresh
        )
    }

    fn scale(&self) -> DVec3 {
        let n = DVec3::new(
            f64::from(self.resolution[0] - 1),
            f64::from(self.resolution[1] - 1),
            f64::from(self.resolution[2] - 1),
        );
        n / (self.max - self.min)
    }

    /// The position of node (i, j, k).
    pub(crate) fn node_position(&self, i: u32, j: u32, k: u32) -> DVec3 {
        self.min + DVec3::new(f64::from(i), f64::from(j), f64::from(k)) / self.scale()
    }

    /// f64 reference of the bake: the baked terms' sum at every node, x fastest.
    pub fn bake(&self, terms: &[Term], t: f64) -> Vec<DVec3> {
        let [nx, ny, nz] = self.resolution;
        let mut out = Vec::with_capacity(self.nodes() as usize);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let x = self.node_position(i, j, k);
                    out.push(baked_sum(terms, x, t));
                }
            }
        }
        out
    }

    /// f64 reference of the sampling, or None outside the bounds (evaluate there instead).
    pub fn sample(&self, nodes: &[DVec3], x: DVec3) -> Option<DVec3> {
        let u = (x - self.min) * self.scale();
        let [nx, ny, nz] = self.resolution;
        let top = DVec3::new(f64::from(nx - 1), f64::from(ny - 1), f64::from(nz - 1));
        if !(u.cmpge(DVec3::ZERO).all() && u.cmple(top).all()) {
            return None;
        }
        let at = |i: u32, j: u32, k: u32| nodes[(i + nx * (j + ny * k)) as usize];
        match self.filter {
            Filter::Nearest => {
                let r = u.round();
                Some(at(r.x as u32, r.y as u32, r.z as u32))
            }
            Filter::Trilinear => {
                // The cell's lower corner, kept one below the top so u = n - 1 uses the last cell.
                let c = u.floor().min(top - DVec3::ONE).max(DVec3::ZERO);
                let f = u - c;
                let (i, j, k) = (c.x as u32, c.y as u32, c.z as u32);
                let lerp = |a: DVec3, b: DVec3, t: f64| a + (b - a) * t;
                let x00 = lerp(at(i, j, k), at(i + 1, j, k), f.x);
                let x10 = lerp(at(i, j + 1, k), at(i + 1, j + 1, k), f.x);
                let x01 = lerp(at(i, j, k + 1), at(i + 1, j, k + 1), f.x);
                let x11 = lerp(at(i, j + 1, k + 1), at(i + 1, j + 1, k + 1), f.x);
                Some(lerp(lerp(x00, x10, f.y), lerp(x01, x11, f.y), f.z))
            }
        }
    }

    /// WGSL: `field_eval` (the baked terms' sum), `field_sample` (grid or fallback) and the
    /// `bake` kernel. Expects `field: array<vec4<f32>>` bound.
    pub(crate) fn emit_wgsl(&self, w: &mut Writer, terms: &[Term]) {
        let [nx, ny, nz] = self.resolution;
        w.line(format!("const FIELD_NX: u32 = {};", u32_lit(nx)));
        w.line(format!("const FIELD_NY: u32 = {};", u32_lit(ny)));
        w.line(format!("const FIELD_NZ: u32 = {};", u32_lit(nz)));
        w.line(format!(
            "const FIELD_MIN: vec3<f32> = {};",
            vec3_lit(self.min)
        ));
        w.line(format!(
            "const FIELD_SCALE: vec3<f32> = {};",
            vec3_lit(self.scale())
        ));
        w.line(format!(
            "const FIELD_STEP: vec3<f32> = {};",
            vec3_lit(DVec3::ONE / self.scale())
        ));
        w.comment("The forces the grid holds, evaluated at x.");
        w.block("fn field_eval(x: vec3<f32>, t: f32) -> vec3<f32>", |w| {
            w.line("var a = vec3<f32>(0.0);");
            for term in terms.iter().filter(|t| t.as_dyn().bakeable()) {
                term.as_dyn().emit_wgsl(w);
            }
            w.line("return a;");
        });
        w.block("fn field_at(i: u32, j: u32, k: u32) -> vec3<f32>", |w| {
            w.line("return field[i + FIELD_NX * (j + FIELD_NY * k)].xyz;");
        });
        w.comment("The grid's value at x, or the forces evaluated there outside the bounds.");
        w.block("fn field_sample(x: vec3<f32>, t: f32) -> vec3<f32>", |w| {
            w.line("let u = (x - FIELD_MIN) * FIELD_SCALE;");
            w.line("let top = vec3<f32>(f32(FIELD_NX - 1u), f32(FIELD_NY - 1u), f32(FIELD_NZ - 1u));");
            w.block("if (!(all(u >= vec3<f32>(0.0)) && all(u <= top)))", |w| {
                w.line("return field_eval(x, t);");
            });
            match self.filter {
                Filter::Nearest => {
                    w.line("let r = vec3<u32>(round(u));");
                    w.line("return field_at(r.x, r.y, r.z);");
                }
                Filter::Trilinear => {
                    w.line("let c = clamp(floor(u), vec3<f32>(0.0), top - vec3<f32>(1.0));");
                    w.line("let f = u - c;");
                    w.line("let i = u32(c.x);");
                    w.line("let j = u32(c.y);");
                    w.line("let k = u32(c.z);");
                    w.line("let x00 = mix(field_at(i, j, k), field_at(i + 1u, j, k), f.x);");
                    w.line("let x10 = mix(field_at(i, j + 1u, k), field_at(i + 1u, j + 1u, k), f.x);");
                    w.line("let x01 = mix(field_at(i, j, k + 1u), field_at(i + 1u, j, k + 1u), f.x);");
                    w.line("let x11 = mix(field_at(i, j + 1u, k + 1u), field_at(i + 1u, j + 1u, k + 1u), f.x);");
                    w.line("return mix(mix(x00, x10, f.y), mix(x01, x11, f.y), f.z);");
                }
            }
        });
        w.comment("One thread per node: the forces at the node, at this step's time.");
        w.line("@compute @workgroup_size(WORKGROUP)");
        w.block(
            "fn bake(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
            |w| {
                crate::base::kernel::emit_thread_index(w, "n", Some("FIELD_NX * FIELD_NY * FIELD_NZ"));
                w.line("let i = n % FIELD_NX;");
                w.line("let j = (n / FIELD_NX) % FIELD_NY;");
                w.line("let k = n / (FIELD_NX * FIELD_NY);");
                w.line("let x = FIELD_MIN + vec3<f32>(f32(i), f32(j), f32(k)) * FIELD_STEP;");
                w.line("field[n] = vec4<f32>(field_eval(x, params.time), 0.0);");
            },
        );
    }
}

/// The sum of the bakeable terms at (x, t) in f64.
pub fn baked_sum(terms: &[Term], x: DVec3, t: f64) -> DVec3 {
    terms
        .iter()
        .filter(|term| term.as_dyn().bakeable())
        .map(|term| term.as_dyn().accel(x, DVec3::ZERO, t))
        .sum()
}
