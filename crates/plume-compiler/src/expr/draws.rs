//! Functions written in the language itself: random draws beyond `rand(k)` (directions on a
//! sphere, points in a ball, on a circle and in a disc, normally distributed numbers) and the
//! colour helper `hsv`. Each is a template that the checker expands where it is called (a
//! draw's over `rand(k)`, `rand(k + 1)`, ...; `hsv`'s over its arguments), so it is folded,
//! written to WGSL and interpreted in f64 like any expression: the GPU and the reference draw
//! the same numbers from the same hashes. Like `rand(k)`, a draw is the particle's own, the
//! same whenever it is read.

use super::lex::tokenize;
use super::parse::{parse, Ast};
use super::ExprError;

/// A draw: its name, how many consecutive `rand` streams it reads from its k on, and its
/// template (`K0`, `K1`, `K2` stand for k, k + 1, k + 2).
pub struct Draw {
    /// The function's name.
    pub name: &'static str,
    /// Streams read: k to k + streams − 1.
    pub streams: u32,
    /// What it means, for the docs and messages.
    pub meaning: &'static str,
    template: &'static str,
}

/// Every draw. `rand_sphere`: cos(polar) uniform (Archimedes), as the Sphere shape's surface;
/// `rand_ball`: that direction times a cube root; `rand_disc`: a circle's point times a square
/// root; `rand_normal`: Box–Muller, from 1 − rand (in (0, 1], so the log is finite).
pub const DRAWS: &[Draw] = &[
    Draw {
        name: "rand_sphere",
        streams: 2,
        meaning: "a direction uniform on the unit sphere (vec3)",
        template: "vec3(sqrt(max(0.0, 1.0 - (1.0 - 2.0 * rand(K0)) * (1.0 - 2.0 * rand(K0)))) * cos(6.2831853 * rand(K1) - 3.1415927), sqrt(max(0.0, 1.0 - (1.0 - 2.0 * rand(K0)) * (1.0 - 2.0 * rand(K0)))) * sin(6.2831853 * rand(K1) - 3.1415927), 1.0 - 2.0 * rand(K0))",
    },
    Draw {
        name: "rand_ball",
        streams: 3,
        meaning: "a point uniform in the unit ball (vec3)",
        template: "rand_sphere(K0) * pow(rand(K2), 0.33333333)",
    },
    Draw {
        name: "rand_circle",
        streams: 1,
        meaning: "a point uniform on the unit circle in the xy plane (vec3, z = 0)",
        template: "vec3(cos(6.2831853 * rand(K0) - 3.1415927), sin(6.2831853 * rand(K0) - 3.1415927), 0.0)",
    },
    Draw {
        name: "rand_disc",
        streams: 2,
        meaning: "a point uniform in the unit disc in the xy plane (vec3, z = 0)",
        template: "rand_circle(K0) * sqrt(rand(K1))",
    },
    Draw {
        name: "rand_normal",
        streams: 2,
        meaning: "a number of the standard normal distribution (f32; within ±5.8)",
        template: "sqrt(-2.0 * log(1.0 - rand(K0))) * cos(6.2831853 * rand(K1))",
    },
];

/// `hsv(h, s, v)`: the RGB of hue h (turns: 0 and 1 are red, 1/3 green, 2/3 blue),
/// saturation s and value v, as the common formula writes it:
/// v · mix(1, clamp(|fract(h + (1, 2/3, 1/3)) · 6 − 3| − 1, 0, 1), s).
const HSV: &str = "mix(vec3(1.0, 1.0, 1.0), clamp(abs(fract(vec3(a0 + 1.0, a0 + 0.6666667, a0 + 0.33333333)) * 6.0 - vec3(3.0, 3.0, 3.0)) - vec3(1.0, 1.0, 1.0), 0.0, 1.0), a1) * a2";

/// Expands `hsv(h, s, v)` at the call's characters `[start, end)`, its arguments `args`
/// standing for `a0`, `a1` and `a2`.
pub(crate) fn expand_hsv(args: &[Ast], (start, end): (usize, usize)) -> Result<Ast, ExprError> {
    let mut ast = parse(&tokenize(HSV)?)?;
    place(&mut ast, start, end);
    substitute(&mut ast, args);
    Ok(ast)
}

/// Puts `args[i]` where `a{i}` is named.
fn substitute(ast: &mut Ast, args: &[Ast]) {
    use super::parse::AstKind;
    match &mut ast.kind {
        AstKind::Name(name) => {
            if let Some(i) = name.strip_prefix('a').and_then(|i| i.parse::<usize>().ok()) {
                *ast = args[i].clone();
            }
        }
        AstKind::Num(_) => {}
        AstKind::Neg(a) | AstKind::Member(a, _, _) => substitute(a, args),
        AstKind::Binary(_, a, b) => {
            substitute(a, args);
            substitute(b, args);
        }
        AstKind::Call(_, _, call_args) => {
            for a in call_args {
                substitute(a, args);
            }
        }
    }
}

/// The draw called `name`, if it is one.
pub fn find(name: &str) -> Option<&'static Draw> {
    DRAWS.iter().find(|d| d.name == name)
}

impl Draw {
    /// The draw's expansion for its first stream `k` (already checked to fit under
    /// `max_rand`), every node placed at the call's characters `[start, end)`.
    pub(crate) fn expand(&self, k: u32, (start, end): (usize, usize)) -> Result<Ast, ExprError> {
        let text = self
            .template
            .replace("K0", &k.to_string())
            .replace("K1", &(k + 1).to_string())
            .replace("K2", &(k + 2).to_string());
        let mut ast = parse(&tokenize(&text)?)?;
        place(&mut ast, start, end);
        Ok(ast)
    }
}

fn place(ast: &mut Ast, start: usize, end: usize) {
    use super::parse::AstKind;
    ast.start = start;
    ast.end = end;
    match &mut ast.kind {
        AstKind::Num(_) | AstKind::Name(_) => {}
        AstKind::Neg(a) => place(a, start, end),
        AstKind::Member(a, _, range) => {
            *range = (start, end);
            place(a, start, end);
        }
        AstKind::Binary(_, a, b) => {
            place(a, start, end);
            place(b, start, end);
        }
        AstKind::Call(_, range, args) => {
            *range = (start, end);
            for a in args {
                place(a, start, end);
            }
        }
    }
}
