//! Spawn values written as expressions: `shape: Custom("...")` (a position) and
//! `velocity: Custom("...")`. The expression language is the custom forces' ([`crate::expr`]):
//! checked with its mistakes located inside the string, folded, written to WGSL from the tree
//! and interpreted from the same tree in f64 by the reference. At spawn there is no age yet and
//! no velocity; a position reads `t` (the spawn step's time), `rand(k)`, params and `dt`, and a
//! velocity also reads `x`, the position just drawn.

use glam::DVec3;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::rng::stream;
use crate::base::writer::{f32_lit, Writer};
use crate::expr::eval::{eval, Inputs};
use crate::expr::{self, Expr, Names, Ty, Var};

/// Which spawn value an expression sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum SpawnValue {
    /// The position (m).
    Position,
    /// The velocity (m/s).
    Velocity,
}

impl SpawnValue {
    fn vars(self) -> &'static [Var] {
        match self {
            SpawnValue::Position => &[Var::T, Var::Index, Var::Origin],
            SpawnValue::Velocity => &[Var::X, Var::T, Var::Origin],
        }
    }

    fn role(self) -> &'static str {
        match self {
            SpawnValue::Position => "a spawn position",
            SpawnValue::Velocity => "a spawn velocity",
        }
    }

    /// Parses, type-checks and folds `text`; a mistake is located inside it.
    pub(super) fn compile(self, text: &str, names: Names) -> Result<Expr, expr::ExprError> {
        expr::compile_in(text, Ty::Vec3, &names.scope(self.vars(), self.role()))
    }

    /// Records a mistake in `text` in `c`, at its characters in the string at `path`.
    pub(super) fn check(self, text: &str, path: &ValuePath, c: &mut Checker, names: Names) {
        if let Err(e) = self.compile(text, names) {
            c.error_in_string(path, e.start, e.end, e.message);
        }
    }
}

/// Emits the statements that evaluate `e` inside an emitter's `emit_e(id, k, step)` and assign
/// it to `target` (`s.x` or `s.v`), in a block of its own (its `let`s are its own): the spawn
/// step's time is `f32(step) * dt`, `x` the position already drawn.
pub(super) fn emit(w: &mut Writer, e: &Expr, target: &str, dt: f64) {
    w.block("", |w| {
        if e.draws_random() {
            w.line("let ctx_id = id;");
        }
        if e.reads(Var::T) {
            w.line(format!("let t = f32(step) * {};", f32_lit(dt)));
        }
        if e.reads(Var::Index) {
            w.line("let index = f32(k);");
        }
        if e.reads(Var::X) {
            let bound = f32_lit(expr::VALUE_BOUND);
            w.line(format!(
                "let cx = clamp(s.x, vec3<f32>(-{bound}), vec3<f32>({bound}));"
            ));
        }
        let mut emitter = expr::emit::Emitter::new(w, stream::CUSTOM);
        let value = emitter.value(e);
        w.line(format!("{target} = {value};"));
    });
}

/// The f64 twin of [`emit`]: `e` for particle `id` of an effect of `seed_mix`, the `k`-th
/// of its emitter, spawned at time `t` at position `x` in a frame at `origin`.
pub(super) fn value(
    e: &Expr,
    seed_mix: u32,
    (id, k): (u32, u32),
    (t, origin): (f64, DVec3),
    x: DVec3,
) -> DVec3 {
    eval(
        e,
        &Inputs {
            x,
            t,
            seed_mix,
            id,
            // The kernel's `f32(k)`.
            index: f64::from(k as f32),
            origin,
            ..Inputs::default()
        },
    )
    .v()
}

/// The spawns an expression's extent or speed is estimated from.
pub(crate) const ESTIMATE_SPAWNS: u32 = 256;
