//! The f64 interpreter: the reference's meaning of every node, guards included. The WGSL
//! writer ([`super::emit`]) emits the same guards, so GPU and reference agree to f32 rounding.

use glam::DVec3;

use crate::base::gradient_noise;

use super::typed::{Expr, Node, Op1, Op2, Op3, Var};
use super::{DIV_FLOOR, EXP_MAX, EXP_MIN, LOG_FLOOR, NORMALIZE_FLOOR, VALUE_BOUND};

/// What an expression reads: the particle's state and the time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Inputs {
    /// Position (m).
    pub x: DVec3,
    /// Velocity (m/s).
    pub v: DVec3,
    /// Simulation time (s).
    pub t: f64,
    /// Age (s).
    pub age: f64,
    /// Lifetime (s), 0 when immortal.
    pub life: f64,
    /// The effect's seed mix and the particle's id, for `rand(k)`.
    pub seed_mix: u32,
    /// The particle's id.
    pub id: u32,
    /// Its index among its emitter's spawns, as the GPU's f32 holds it.
    pub index: f64,
    /// Where its spawn's frame sits in the world (an event's firing particle; zero else).
    pub origin: DVec3,
    /// Its attributes' values, by index (a number in `x`).
    pub attrs: Attrs,
}

/// The most attributes an effect may declare.
pub(crate) const MAX_ATTRIBUTES: usize = 16;

/// A particle's attribute values, by index: a vector, or a number in `x`.
pub(crate) type Attrs = [DVec3; MAX_ATTRIBUTES];

/// A value: a number, a vector or a comparison's result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    /// A number.
    S(f64),
    /// A vector.
    V(DVec3),
    /// A truth value.
    B(bool),
}

impl Value {
    /// The number (a vector's x for robustness; the checker never mixes them).
    pub fn s(self) -> f64 {
        match self {
            Value::S(x) => x,
            Value::V(v) => v.x,
            Value::B(b) => f64::from(u8::from(b)),
        }
    }

    /// As a vector: a number stands for (s, s, s).
    pub fn v(self) -> DVec3 {
        match self {
            Value::V(v) => v,
            other => DVec3::splat(other.s()),
        }
    }

    fn b(self) -> bool {
        matches!(self, Value::B(true))
    }
}

/// Applies `f` per component, a scalar standing for (s, s, s) beside a vector.
fn zip(a: Value, b: Value, f: impl Fn(f64, f64) -> f64) -> Value {
    match (a, b) {
        (Value::S(x), Value::S(y)) => Value::S(f(x, y)),
        _ => {
            let (x, y) = (a.v(), b.v());
            Value::V(DVec3::new(f(x.x, y.x), f(x.y, y.y), f(x.z, y.z)))
        }
    }
}

fn zip3(a: Value, b: Value, c: Value, f: impl Fn(f64, f64, f64) -> f64) -> Value {
    match (a, b, c) {
        (Value::S(x), Value::S(y), Value::S(z)) => Value::S(f(x, y, z)),
        _ => {
            let (x, y, z) = (a.v(), b.v(), c.v());
            Value::V(DVec3::new(
                f(x.x, y.x, z.x),
                f(x.y, y.y, z.y),
                f(x.z, y.z, z.z),
            ))
        }
    }
}

fn map(a: Value, f: impl Fn(f64) -> f64) -> Value {
    match a {
        Value::V(v) => Value::V(DVec3::new(f(v.x), f(v.y), f(v.z))),
        other => Value::S(f(other.s())),
    }
}

/// Keeps a result within ±[`VALUE_BOUND`].
pub fn bound(x: f64) -> f64 {
    x.clamp(-VALUE_BOUND, VALUE_BOUND)
}

/// Guarded division: 0 where |b| < [`DIV_FLOOR`].
pub(crate) fn div(a: f64, b: f64) -> f64 {
    if b.abs() < DIV_FLOOR {
        0.0
    } else {
        bound(a / b)
    }
}

/// Guarded power: 0 for a <= 0, else e^(b ln max(a, LOG_FLOOR)) with the exponent clamped.
pub fn pow(a: f64, b: f64) -> f64 {
    if a > 0.0 {
        (b * a.max(LOG_FLOOR).ln()).clamp(EXP_MIN, EXP_MAX).exp()
    } else {
        0.0
    }
}

/// Guarded smoothstep: the Hermite step of (a − e0) / (e1 − e0) clamped to [0, 1].
pub fn smoothstep(e0: f64, e1: f64, a: f64) -> f64 {
    let u = div(a - e0, e1 - e0).clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

/// Evaluates `e` for one particle.
pub(crate) fn eval(e: &Expr, inp: &Inputs) -> Value {
    match &e.node {
        Node::Scalar(x) => Value::S(*x),
        Node::Param { value, .. } => Value::S(*value),
        Node::Vector(v) => Value::V(*v),
        Node::Var(var) => match var {
            Var::X => Value::V(
                inp.x
                    .clamp(DVec3::splat(-VALUE_BOUND), DVec3::splat(VALUE_BOUND)),
            ),
            Var::V => Value::V(
                inp.v
                    .clamp(DVec3::splat(-VALUE_BOUND), DVec3::splat(VALUE_BOUND)),
            ),
            Var::T => Value::S(inp.t),
            Var::Age => Value::S(inp.age),
            Var::Life => Value::S(inp.life),
            Var::Index => Value::S(inp.index),
            Var::Origin => Value::V(
                inp.origin
                    .clamp(DVec3::splat(-VALUE_BOUND), DVec3::splat(VALUE_BOUND)),
            ),
        },
        Node::Attr(i) => {
            let a = inp.attrs[usize::from(*i)]
                .clamp(DVec3::splat(-VALUE_BOUND), DVec3::splat(VALUE_BOUND));
            match e.ty {
                super::Ty::Vec3 => Value::V(a),
                _ => Value::S(a.x),
            }
        }
        Node::Rand(k) => Value::S(crate::base::rng::unit(crate::base::rng::rand_u32(
            inp.seed_mix,
            inp.id,
            crate::base::rng::stream::CUSTOM + k,
        ))),
        Node::Unary(op, a) => {
            let a = eval(a, inp);
            match op {
                Op1::Neg => map(a, |x| -x),
                Op1::Abs => map(a, f64::abs),
                Op1::Floor => map(a, f64::floor),
                Op1::Fract => map(a, |x| x - x.floor()),
                Op1::Ceil => map(a, f64::ceil),
                Op1::Round => map(a, f64::round_ties_even),
                Op1::Sign => map(a, |x| {
                    if x > 0.0 {
                        1.0
                    } else if x < 0.0 {
                        -1.0
                    } else {
                        0.0
                    }
                }),
                Op1::Tan => map(a, |x| bound(x.tan())),
                Op1::Asin => map(a, |x| x.clamp(-1.0, 1.0).asin()),
                Op1::Acos => map(a, |x| x.clamp(-1.0, 1.0).acos()),
                Op1::Atan => map(a, f64::atan),
                Op1::Log2 => map(a, |x| x.max(LOG_FLOOR).log2()),
                Op1::Sqrt => map(a, |x| x.max(0.0).sqrt()),
                Op1::Exp => map(a, |x| x.clamp(EXP_MIN, EXP_MAX).exp()),
                Op1::Log => map(a, |x| x.max(LOG_FLOOR).ln()),
                Op1::Sin => map(a, f64::sin),
                Op1::Cos => map(a, f64::cos),
                Op1::Length => Value::S(bound(a.v().length())),
                Op1::Normalize => {
                    let v = a.v();
                    let l2 = v.length_squared();
                    Value::V(if l2 > NORMALIZE_FLOOR {
                        v / l2.sqrt()
                    } else {
                        DVec3::ZERO
                    })
                }
                Op1::Component(i) => Value::S(a.v()[usize::from(*i)]),
                Op1::Noise => {
                    Value::S(gradient_noise::noise(gradient_noise::EXPRESSION_KEY, a.v()))
                }
                Op1::Curl => Value::V(
                    gradient_noise::curl(gradient_noise::EXPRESSION_KEY, a.v())
                        .clamp(DVec3::splat(-VALUE_BOUND), DVec3::splat(VALUE_BOUND)),
                ),
            }
        }
        Node::Binary(op, a, b) => {
            let (a, b) = (eval(a, inp), eval(b, inp));
            match op {
                Op2::Add => zip(a, b, |x, y| bound(x + y)),
                Op2::Sub => zip(a, b, |x, y| bound(x - y)),
                Op2::Mul => zip(a, b, |x, y| bound(x * y)),
                Op2::Div => zip(a, b, div),
                Op2::Min => zip(a, b, f64::min),
                Op2::Max => zip(a, b, f64::max),
                Op2::Pow => zip(a, b, pow),
                Op2::Atan2 => zip(a, b, |y, x| {
                    if y == 0.0 && x == 0.0 {
                        0.0
                    } else {
                        y.atan2(x)
                    }
                }),
                Op2::Step => zip(a, b, |edge, x| if x >= edge { 1.0 } else { 0.0 }),
                Op2::Rem => zip(a, b, |x, y| {
                    if y.abs() >= DIV_FLOOR {
                        x - y * (x / y).trunc()
                    } else {
                        0.0
                    }
                }),
                Op2::Dot => Value::S(bound(a.v().dot(b.v()))),
                Op2::Cross => {
                    let c = a.v().cross(b.v());
                    Value::V(c.clamp(DVec3::splat(-VALUE_BOUND), DVec3::splat(VALUE_BOUND)))
                }
                Op2::Compare(c) => Value::B(c.compare(a.s(), b.s())),
            }
        }
        Node::Ternary(op, a, b, c) => {
            let (a, b, c) = (eval(a, inp), eval(b, inp), eval(c, inp));
            match op {
                Op3::Vec3 => Value::V(DVec3::new(a.s(), b.s(), c.s())),
                Op3::Clamp => zip3(a, b, c, |x, lo, hi| x.max(lo).min(hi)),
                Op3::Mix => zip3(a, b, c, |x, y, s| bound(x + bound(y - x) * s)),
                Op3::Smoothstep => zip3(a, b, c, smoothstep),
                Op3::Select => {
                    if c.b() {
                        b
                    } else {
                        a
                    }
                }
            }
        }
    }
}
