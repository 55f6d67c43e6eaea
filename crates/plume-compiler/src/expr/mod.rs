//! Custom expressions: a small typed language for accelerations (`Custom(accel: "...")`),
//! compiled like the rest of an effect. A string goes through the `lex`er and the [`parse`]r
//! into a syntax tree, the type checker ([`typed`]) turns it into a typed tree with every
//! mistake located inside the string, [`fold`] simplifies it, [`emit`] writes it to WGSL and
//! [`eval`] interprets the very same tree in f64 for the reference.
//!
//! Every operation is total: results are kept within ±[`VALUE_BOUND`] (so no product of two
//! values can overflow f32), division by (nearly) zero gives 0, `sqrt` and `log` of negatives,
//! `pow` of a non-positive base, `atan2(0, 0)` and `normalize` of a zero vector have finite
//! documented results (docs/effect-format.md, "Custom forces"). No NaN or Inf can come out.

pub mod define;
pub mod draws;
pub mod emit;
pub mod eval;
pub mod fold;
pub(crate) mod lex;
mod names;
pub mod parse;
pub mod tree;
pub mod typed;
pub(crate) mod vocab;

use std::collections::BTreeMap;

pub(crate) use typed::{Expr, Ty, Var};

/// Every value an expression computes stays within ±this: the product of two bounded values
/// (1e36) and a sum of three such products stay far below f32's largest (3.4e38), so no
/// operation can overflow before its result is clamped back.
pub const VALUE_BOUND: f64 = 1.0e18;
/// Divisors smaller than this in magnitude give 0: 1e18 / 1e-20 = 1e38 still fits in f32.
pub(crate) const DIV_FLOOR: f64 = 1.0e-20;
/// `log(x)` reads max(x, this): log(1e-30) = −69.1.
pub(crate) const LOG_FLOOR: f64 = 1.0e-30;
/// `exp` (and `pow`) clamp their exponent to [EXP_MIN, EXP_MAX]: e^EXP_MAX = [`VALUE_BOUND`],
/// e^EXP_MIN is a normal f32.
pub(crate) const EXP_MAX: f64 = 41.446_531_673_892_82;
/// See [`EXP_MAX`].
pub(crate) const EXP_MIN: f64 = -87.0;
/// `normalize(v)` is zero when |v|² is at most this (the same guard as the built-in forces').
pub(crate) const NORMALIZE_FLOOR: f64 = 1.0e-20;
/// The most tokens an expression may have: keeps the recursive passes' depth small.
pub(crate) const MAX_TOKENS: usize = 1024;

/// What an effect's expressions may name besides their variables: its `params` and `dt`.
#[derive(Clone, Copy, Debug)]
pub struct Names<'a> {
    /// The effect's named constants.
    pub params: &'a BTreeMap<String, f64>,
    /// The effect's step (s).
    pub dt: f64,
    /// Params are read at run time (`CompileOptions::live_params`), not folded.
    pub live: bool,
    /// The effect's attributes (`features::attributes`), in name order.
    pub(crate) attrs: &'a [typed::AttrName],
    /// The effect's named expressions (`define`).
    pub(crate) defines: &'a [define::Define],
}

impl<'a> Names<'a> {
    /// The scope of an expression evaluated at spawn, before the attributes hold values,
    /// that may read `vars` and whose value is `role` ("a position").
    pub(crate) fn scope(&self, vars: &'a [Var], role: &'a str) -> typed::Scope<'a> {
        typed::Scope {
            params: self.params,
            dt: self.dt,
            live: self.live,
            vars,
            role,
            attrs: self.attrs,
            reads_attrs: false,
            defines: self.defines,
            expanded: std::cell::Cell::new(0),
        }
    }

    /// [`Names::scope`] for an expression evaluated on a particle that has its attributes.
    pub(crate) fn scope_with_attrs(&self, vars: &'a [Var], role: &'a str) -> typed::Scope<'a> {
        typed::Scope {
            reads_attrs: true,
            ..self.scope(vars, role)
        }
    }
}

/// A mistake in an expression, at characters `[start, end)` of the string.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct ExprError {
    /// What is wrong.
    pub message: String,
    /// First character (0-based).
    pub start: usize,
    /// One past the last character.
    pub end: usize,
}

impl ExprError {
    /// An error over `[start, end)`.
    pub(crate) fn new(message: impl Into<String>, start: usize, end: usize) -> Self {
        Self {
            message: message.into(),
            start,
            end: end.max(start + 1),
        }
    }
}

/// Parses and type-checks `text` as an acceleration of type `want` (reading any variable),
/// then folds it. `params` are the effect's named constants and `dt` its step.
#[cfg(test)]
pub(crate) fn compile(
    text: &str,
    want: Ty,
    params: &BTreeMap<String, f64>,
    dt: f64,
) -> Result<Expr, ExprError> {
    compile_in(
        text,
        want,
        &typed::Scope {
            params,
            dt,
            live: false,
            vars: typed::VARIABLES,
            role: "an acceleration",
            attrs: &[],
            reads_attrs: false,
            defines: &[],
            expanded: std::cell::Cell::new(0),
        },
    )
}

/// Parses, type-checks and folds `text` as a value of type `want` in `scope`: with
/// `scope.live`, params are read at run time and never folded.
pub(crate) fn compile_in(text: &str, want: Ty, scope: &typed::Scope) -> Result<Expr, ExprError> {
    let tokens = lex::tokenize(text)?;
    if tokens.len() > MAX_TOKENS {
        let t = &tokens[MAX_TOKENS];
        return Err(ExprError::new(
            format!("longer than {MAX_TOKENS} tokens: split the force into several Custom terms"),
            t.start,
            t.end,
        ));
    }
    let ast = parse::parse(&tokens)?;
    let expr = typed::check(&ast, scope)?;
    if expr.ty != want {
        return Err(ExprError::new(
            format!(
                "the expression is a {}, but {} must be a {}{}",
                expr.ty.name(),
                scope.role,
                want.name(),
                if expr.ty == Ty::Scalar {
                    " (write vec3(a, b, c), or multiply a direction by it)"
                } else {
                    ""
                }
            ),
            ast.start,
            ast.end,
        ));
    }
    Ok(fold::fold(expr))
}

#[cfg(test)]
mod tests;
