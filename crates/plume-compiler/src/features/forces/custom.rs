//! A custom acceleration written as an expression: `Custom(accel: "-k * (x - vec3(0, 1, 0))")`.
//! The expression language lives in [`crate::expr`]; this module owns the force's schema, its
//! checks (errors located inside the string), its lowering (an expression that folds to a
//! constant becomes a constant term, so Exact and stateless still apply), its WGSL and its f64
//! reference, and its stiffness, estimated by sampling the Jacobian over the emitters' region.

use glam::{DMat3, DVec3};
use serde::Deserialize;

use super::{ForceTerm, ParticleCtx, Stiffness, Term};
use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::writer::{f32_lit, Writer};
use crate::expr::eval::{eval, Inputs};
use crate::expr::typed::Node;
use crate::expr::{self, Expr, Ty, Var};
use crate::features::emitter::EmitterIr;

/// Field names, as written in effect files.
pub(crate) const FIELDS: &[&str] = &["accel"];

/// What a custom force's expressions may name besides the variables: the effect's `params`
/// and its `dt`.
pub(crate) use crate::expr::Names as Scope;

fn typed(scope: Scope<'_>) -> expr::typed::Scope<'_> {
    scope.scope_with_attrs(expr::typed::VARIABLES, "an acceleration")
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Custom {
    /// The acceleration (m/s²), an expression of type vec3.
    pub accel: String,
}

impl Custom {
    /// Parses and type-checks the expression; a mistake is an error at its characters.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker, scope: Scope) {
        if let Err(e) = expr::compile_in(&self.accel, Ty::Vec3, &typed(scope)) {
            c.error_in_string(&path.field("accel"), e.start, e.end, e.message);
        }
    }

    /// Lowers to a term: a constant term when the expression folds to a constant, else a
    /// custom term. Call only after [`Custom::check`] found no error.
    pub(crate) fn lower(&self, origin: usize, seed_mix: u32, scope: Scope) -> Term {
        let expr = expr::compile_in(&self.accel, Ty::Vec3, &typed(scope))
            .expect("checked before lowering");
        if let Node::Vector(accel) = expr.node {
            return Term::Constant(super::constant::ConstantTerm {
                accel,
                origins: vec![origin],
            });
        }
        Term::Custom(CustomTerm {
            expr,
            origins: vec![origin],
            seed_mix,
            stiffness: Stiffness::None,
        })
    }
}

/// A custom term in the IR: the folded expression tree.
#[derive(Clone, Debug, PartialEq)]
pub struct CustomTerm {
    /// The typed, folded expression.
    pub expr: Expr,
    /// Source forces.
    pub origins: Vec<usize>,
    /// The effect's seed mix, for `rand(k)`.
    pub seed_mix: u32,
    /// Estimated by `estimate_stiffness` at lowering.
    pub stiffness: Stiffness,
}

/// The rand streams of custom expressions start here (below are the spawn's).
pub(crate) use crate::base::rng::stream::CUSTOM as RAND_STREAM;

impl CustomTerm {
    /// Whether the term reads the particle context (id, age or lifetime).
    pub(crate) fn needs_context(&self) -> bool {
        self.expr.reads(Var::Age)
            || self.expr.reads(Var::Life)
            || self.expr.draws_random()
            || self.expr.attrs_read() != 0
    }

    /// Whether the term reads the particle's age or lifetime (the layout then keeps the
    /// spawn step).
    pub(crate) fn reads_age_or_life(&self) -> bool {
        self.expr.reads(Var::Age) || self.expr.reads(Var::Life)
    }

    /// Estimates the step-size limit: the largest spectral norms of ∂a/∂x (ω² of an
    /// oscillation) and ∂a/∂v (a damping rate) by central differences at points over the
    /// emitters' region grown by a second of their fastest spawn speed, at velocities up to
    /// that speed, at t = 0 and, for a term that reads the age, at ages over a particle's life
    /// (never at its spawn alone); whichever binds harder at step `h` is kept. An estimate: a
    /// stiffness outside the sampled region or at another time is not seen.
    pub(crate) fn estimate_stiffness(&mut self, emitters: &[EmitterIr], h: f64) {
        let speed = emitters
            .iter()
            .map(|e| e.velocity.max_speed())
            .fold(0.0, f64::max);
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for e in emitters {
            let r = DVec3::splat(e.shape.extent() + speed + 1.0);
            lo = lo.min(e.shape.center() - r);
            hi = hi.max(e.shape.center() + r);
        }
        if emitters.is_empty() {
            (lo, hi) = (DVec3::splat(-1.0), DVec3::splat(1.0));
        }
        const N: usize = 7;
        let mut worst_w2: f64 = 0.0;
        let mut worst_k: f64 = 0.0;
        let velocities = [
            DVec3::ZERO,
            DVec3::X * speed,
            DVec3::Y * speed,
            DVec3::Z * -speed,
        ];
        // A term that reads the age is sampled over a particle's life, not at its spawn: what
        // acts only in a particle's first steps (a kick at spawn) cannot grow an error step
        // after step, so it is not a stiffness. From 4 substeps of age to 1024 (17 s at 60 Hz),
        // within the longest lifetime when every particle dies.
        let longest = emitters
            .iter()
            .map(|e| e.lifetime.map(|l| l.1))
            .try_fold(0.0, |most: f64, life| life.map(|l| most.max(l)))
            .unwrap_or(f64::INFINITY);
        let ages: Vec<f64> = match self.expr.reads(Var::Age) {
            true => [4.0, 16.0, 64.0, 256.0, 1024.0]
                .iter()
                .map(|n| n * h)
                .enumerate()
                .filter(|&(i, age)| i == 0 || age < longest)
                .map(|(_, age)| age)
                .collect(),
            false => vec![0.0],
        };
        for i in 0..N * N * N {
            let f = DVec3::new((i % N) as f64, ((i / N) % N) as f64, (i / (N * N)) as f64)
                / (N - 1) as f64;
            let x = lo + (hi - lo) * f;
            for (v, &age0) in velocities
                .iter()
                .flat_map(|v| ages.iter().map(move |a| (*v, a)))
            {
                let ctx = ParticleCtx {
                    id: i as u32,
                    age0,
                    ..ParticleCtx::default()
                };
                let jx = jacobian(|p| self.accel_at(p, v, 0.0, &ctx), x);
                worst_w2 = worst_w2.max(spectral_norm(jx));
                if self.expr.reads(Var::V) {
                    let jv = jacobian(|q| self.accel_at(x, q, 0.0, &ctx), v);
                    worst_k = worst_k.max(spectral_norm(jv));
                }
            }
        }
        // Compare against the tighter of the two limits (2 for k h and ω h alike).
        let (w, k) = (worst_w2.sqrt(), worst_k);
        self.stiffness = if w == 0.0 && k == 0.0 {
            Stiffness::None
        } else if w * h >= k * h {
            Stiffness::Oscillation(w)
        } else {
            Stiffness::Damping(k)
        };
    }
}

/// ∂f/∂p by central differences with steps relative to |p|.
fn jacobian(f: impl Fn(DVec3) -> DVec3, p: DVec3) -> DMat3 {
    let mut cols = [DVec3::ZERO; 3];
    for (axis, col) in cols.iter_mut().enumerate() {
        let e = 1e-4 * p[axis].abs().max(1.0);
        let mut step = DVec3::ZERO;
        step[axis] = e;
        *col = (f(p + step) - f(p - step)) / (2.0 * e);
    }
    DMat3::from_cols(cols[0], cols[1], cols[2])
}

/// The largest singular value of `m`, by power iteration on mᵀm.
fn spectral_norm(m: DMat3) -> f64 {
    let mtm = m.transpose() * m;
    let mut u = DVec3::new(0.6, 0.7, 0.4);
    let mut s = 0.0;
    for _ in 0..32 {
        let w = mtm * u;
        let l = w.length();
        if !(l.is_finite() && l > 0.0) {
            return if l.is_finite() { 0.0 } else { f64::MAX };
        }
        s = l;
        u = w / l;
    }
    s.sqrt()
}

/// Declares the particle context that custom terms read through `ctx_*` (its id for rand, its
/// age at the step's start and that time, its lifetime), set by the kernels before any
/// `accel` call ([`emit_set_context`]).
pub(crate) fn emit_context(w: &mut Writer) {
    w.comment("The particle a custom force is evaluated for: set before every accel call.");
    w.line("var<private> ctx_id: u32;");
    w.line("var<private> ctx_age0: f32;");
    w.line("var<private> ctx_t0: f32;");
    w.line("var<private> ctx_life: f32;");
}

/// Sets the particle context: `id`, `born` and `die_at` are WGSL u32 expressions (`die_at`
/// None when no emitter sets a lifetime, `born` None when the age is not read).
pub(crate) fn emit_set_context(
    w: &mut Writer,
    dt: f64,
    id: &str,
    born: Option<&str>,
    die_at: Option<&str>,
) {
    w.line(format!("ctx_id = {id};"));
    w.line("ctx_t0 = params.time;");
    match born {
        Some(born) => {
            w.line(format!(
                "ctx_age0 = f32(params.step - {born}) * {};",
                f32_lit(dt)
            ));
            match die_at {
                Some(die_at) => w.line(format!(
                    "ctx_life = select(0.0, f32({die_at} - {born} + 1u) * {}, {die_at} != DEAD);",
                    f32_lit(dt)
                )),
                None => w.line("ctx_life = 0.0;"),
            }
        }
        None => {
            w.line("ctx_age0 = 0.0;");
            w.line("ctx_life = 0.0;");
        }
    }
}

impl ForceTerm for CustomTerm {
    fn origins(&self) -> &[usize] {
        &self.origins
    }
    fn describe(&self) -> String {
        let mut reads: Vec<&str> = expr::typed::VARIABLES
            .iter()
            .filter(|v| self.expr.reads(**v))
            .map(|v| v.name())
            .collect();
        if self.expr.attrs_read() != 0 {
            reads.push("attributes");
        }
        format!(
            "Custom ({} nodes after folding; reads {}{})",
            self.expr.size(),
            if reads.is_empty() {
                "nothing".to_string()
            } else {
                reads.join(", ")
            },
            if self.expr.draws_random() {
                ", rand"
            } else {
                ""
            }
        )
    }
    fn can_act(&self) -> bool {
        !expr::fold::is_zero(&self.expr)
    }
    fn uses_velocity(&self) -> bool {
        self.expr.reads(Var::V)
    }
    fn uses_time(&self) -> bool {
        self.expr.reads(Var::T) || self.expr.reads(Var::Age)
    }
    fn reads_whole_time(&self) -> bool {
        self.expr.reads(Var::T)
    }
    fn closed_form_blocker(&self) -> String {
        let mut reads: Vec<&str> = [Var::V, Var::T, Var::Age, Var::X]
            .into_iter()
            .filter(|v| self.expr.reads(*v))
            .map(|v| v.name())
            .collect();
        if self.expr.attrs_read() != 0 {
            reads.push("the particle's attributes");
        }
        if reads.is_empty() {
            "draws random numbers per particle".into()
        } else {
            format!("is a custom expression that reads {}", reads.join(" and "))
        }
    }
    fn stiffness_field(&self) -> &'static str {
        "accel"
    }
    fn stiffness(&self) -> Stiffness {
        self.stiffness
    }
    fn stiffness_is_estimate(&self) -> bool {
        true
    }
    fn emit_wgsl(&self, w: &mut Writer) {
        w.block("", |w| {
            let bound = f32_lit(expr::VALUE_BOUND);
            let clamp =
                |var: &str| format!("clamp({var}, vec3<f32>(-{bound}), vec3<f32>({bound}))");
            if self.expr.reads(Var::X) {
                w.line(format!("let cx = {};", clamp("x")));
            }
            if self.expr.reads(Var::V) {
                w.line(format!("let cv = {};", clamp("v")));
            }
            if self.expr.reads(Var::Age) {
                w.line("let age = ctx_age0 + (t - ctx_t0);");
            }
            let read = self.expr.attrs_read();
            for i in (0..64).filter(|i| read & (1u64 << i) != 0) {
                w.line(format!("let a{i} = ctx_a{i};"));
            }
            let mut e = expr::emit::Emitter::new(w, RAND_STREAM);
            let value = e.value(&self.expr);
            w.line(format!("a += {value};"));
        });
    }
    fn accel(&self, x: DVec3, v: DVec3, t: f64) -> DVec3 {
        self.accel_at(x, v, t, &ParticleCtx::default())
    }
    fn accel_at(&self, x: DVec3, v: DVec3, t: f64, p: &ParticleCtx) -> DVec3 {
        let inputs = Inputs {
            x,
            v,
            t,
            age: p.age0 + (t - p.t0),
            life: p.life,
            seed_mix: self.seed_mix,
            id: p.id,
            attrs: p.attrs,
            ..Inputs::default()
        };
        eval(&self.expr, &inputs).v()
    }
}
