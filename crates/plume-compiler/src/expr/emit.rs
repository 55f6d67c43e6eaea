//! The WGSL writer for expressions: one `let` per node (so a deep tree is a flat list of
//! statements and a guard can name its operands twice), with the guards of [`super::eval`].
//! User text never reaches the shader: only the tree does.

use super::typed::{Expr, Node, Op1, Op2, Op3, Ty, Var};
use super::{DIV_FLOOR, EXP_MAX, EXP_MIN, LOG_FLOOR, NORMALIZE_FLOOR, VALUE_BOUND};
use crate::base::writer::{f32_lit, vec3_lit, Writer};

/// Names the WGSL in scope must provide for the variables: position and velocity (`vec3<f32>`),
/// the time `t`, and for age, life and rand the module's particle context
/// (`emit_context`).
pub struct Emitter<'w> {
    w: &'w mut Writer,
    next: usize,
    /// Each `let`'s right-hand side and its name: a computation written twice (`x.y` in three
    /// places) is bound once, since operands are named canonically.
    bound: std::collections::HashMap<String, String>,
    /// The stream base `rand(k)` draws from.
    pub(crate) rand_stream: u32,
}

fn lit(ty: Ty, x: f64) -> String {
    match ty {
        Ty::Vec3 => format!("vec3<f32>({})", f32_lit(x)),
        _ => f32_lit(x),
    }
}

fn widen(value: String, from: Ty, to: Ty) -> String {
    if from == Ty::Scalar && to == Ty::Vec3 {
        format!("vec3<f32>({value})")
    } else {
        value
    }
}

impl<'w> Emitter<'w> {
    /// An emitter writing into `w`.
    pub(crate) fn new(w: &'w mut Writer, rand_stream: u32) -> Self {
        Self {
            w,
            next: 0,
            bound: std::collections::HashMap::new(),
            rand_stream,
        }
    }

    fn bind(&mut self, value: String) -> String {
        if let Some(name) = self.bound.get(&value) {
            return name.clone();
        }
        let name = format!("e{}", self.next);
        self.next += 1;
        self.w.line(format!("let {name} = {value};"));
        self.bound.insert(value, name.clone());
        name
    }

    fn bounded(&mut self, ty: Ty, value: String) -> String {
        self.bind(format!(
            "clamp({value}, {}, {})",
            lit(ty, -VALUE_BOUND),
            lit(ty, VALUE_BOUND)
        ))
    }

    /// Writes the statements for `e` and returns the WGSL expression (a name or a literal)
    /// holding its value.
    pub(crate) fn value(&mut self, e: &Expr) -> String {
        let ty = e.ty;
        match &e.node {
            Node::Scalar(x) => f32_lit(*x),
            // Live params ride in the step parameters, four to a vec4.
            Node::Param { index, .. } => format!("params.user[{}u][{}u]", index / 4, index % 4),
            Node::Vector(v) => vec3_lit(*v),
            Node::Var(var) => match var {
                Var::X => "cx".into(),
                Var::V => "cv".into(),
                Var::T => "t".into(),
                Var::Age => "age".into(),
                Var::Life => "ctx_life".into(),
                Var::Index => "index".into(),
                // A private variable the event spawn sets before `emit_E` (zero otherwise).
                Var::Origin => "spawn_origin".into(),
            },
            // The place evaluating it binds each attribute it holds as `a{index}`.
            Node::Attr(i) => format!("a{i}"),
            Node::Rand(k) => self.bind(format!(
                "rand_unit(ctx_id, {}u)",
                self.rand_stream.wrapping_add(*k)
            )),
            Node::Unary(op, a) => {
                let at = a.ty;
                let a = self.value(a);
                match op {
                    Op1::Neg => self.bind(format!("-({a})")),
                    Op1::Abs
                    | Op1::Floor
                    | Op1::Fract
                    | Op1::Sin
                    | Op1::Cos
                    | Op1::Ceil
                    | Op1::Round
                    | Op1::Sign
                    | Op1::Atan => {
                        let f = match op {
                            Op1::Abs => "abs",
                            Op1::Floor => "floor",
                            Op1::Fract => "fract",
                            Op1::Sin => "sin",
                            Op1::Ceil => "ceil",
                            Op1::Round => "round",
                            Op1::Sign => "sign",
                            Op1::Atan => "atan",
                            _ => "cos",
                        };
                        self.bind(format!("{f}({a})"))
                    }
                    Op1::Tan => self.bounded(at, format!("tan({a})")),
                    Op1::Asin | Op1::Acos => {
                        let f = if *op == Op1::Asin { "asin" } else { "acos" };
                        self.bind(format!(
                            "{f}(clamp({a}, {}, {}))",
                            lit(at, -1.0),
                            lit(at, 1.0)
                        ))
                    }
                    Op1::Log2 => self.bind(format!("log2(max({a}, {}))", lit(at, LOG_FLOOR))),
                    Op1::Sqrt => self.bind(format!("sqrt(max({a}, {}))", lit(at, 0.0))),
                    Op1::Exp => self.bind(format!(
                        "exp(clamp({a}, {}, {}))",
                        lit(at, EXP_MIN),
                        lit(at, EXP_MAX)
                    )),
                    Op1::Log => self.bind(format!("log(max({a}, {}))", lit(at, LOG_FLOOR))),
                    Op1::Length => self.bind(format!("min(length({a}), {})", f32_lit(VALUE_BOUND))),
                    Op1::Normalize => {
                        let l2 = self.bind(format!("dot({a}, {a})"));
                        let floor = f32_lit(NORMALIZE_FLOOR);
                        self.bind(format!(
                            "select(vec3<f32>(0.0), {a} * inverseSqrt(max({l2}, {floor})), {l2} > {floor})"
                        ))
                    }
                    Op1::Noise => self.bind(format!(
                        "grad_noise({}u, {a})",
                        crate::base::gradient_noise::EXPRESSION_KEY
                    )),
                    Op1::Curl => self.bind(format!(
                        "turb_curl({}u, {a})",
                        crate::base::gradient_noise::EXPRESSION_KEY
                    )),
                    Op1::Component(i) => {
                        self.bind(format!("{a}.{}", ["x", "y", "z"][usize::from(*i)]))
                    }
                }
            }
            Node::Binary(op, a, b) => {
                let (at, bt) = (a.ty, b.ty);
                // A constant divisor the guard would pass anyway needs no guard.
                let plain_divisor = *op == Op2::Div && super::fold::is_safe_divisor(b);
                let (a, b) = (self.value(a), self.value(b));
                // Operands of per-component functions as the result's type.
                let (wa, wb) = (widen(a.clone(), at, ty), widen(b.clone(), bt, ty));
                match op {
                    Op2::Add => self.bounded(ty, format!("{a} + {b}")),
                    Op2::Sub => self.bounded(ty, format!("{a} - {b}")),
                    Op2::Mul => self.bounded(ty, format!("{a} * {b}")),
                    Op2::Div if plain_divisor => self.bounded(ty, format!("{wa} / {wb}")),
                    Op2::Div => {
                        let ok = self.bind(format!("abs({wb}) >= {}", lit(ty, DIV_FLOOR)));
                        let q = self
                            .bounded(ty, format!("{wa} / select({}, {wb}, {ok})", lit(ty, 1.0)));
                        self.bind(format!("select({}, {q}, {ok})", lit(ty, 0.0)))
                    }
                    Op2::Min => self.bind(format!("min({wa}, {wb})")),
                    Op2::Max => self.bind(format!("max({wa}, {wb})")),
                    Op2::Pow => self.bind(format!(
                        "select({}, exp(clamp({wb} * log(max({wa}, {})), {}, {})), {wa} > {})",
                        lit(ty, 0.0),
                        lit(ty, LOG_FLOOR),
                        lit(ty, EXP_MIN),
                        lit(ty, EXP_MAX),
                        lit(ty, 0.0)
                    )),
                    Op2::Atan2 => {
                        let z = lit(ty, 0.0);
                        self.bind(format!(
                            "select(atan2({wa}, {wb}), {z}, ({wa} == {z}) & ({wb} == {z}))"
                        ))
                    }
                    Op2::Step => self.bind(format!("step({wa}, {wb})")),
                    Op2::Rem => {
                        let ok = self.bind(format!("abs({wb}) >= {}", lit(ty, DIV_FLOOR)));
                        let q = self.bind(format!(
                            "trunc({wa} / select({}, {wb}, {ok}))",
                            lit(ty, 1.0)
                        ));
                        self.bind(format!("select({}, {wa} - {wb} * {q}, {ok})", lit(ty, 0.0)))
                    }
                    Op2::Dot => self.bounded(Ty::Scalar, format!("dot({a}, {b})")),
                    Op2::Cross => self.bounded(Ty::Vec3, format!("cross({a}, {b})")),
                    Op2::Compare(c) => self.bind(format!("{a} {} {b}", c.symbol())),
                }
            }
            Node::Ternary(op, a, b, c) => {
                let (at, bt, ct) = (a.ty, b.ty, c.ty);
                let (a, b, c) = (self.value(a), self.value(b), self.value(c));
                let (wa, wb, wc) = (
                    widen(a.clone(), at, ty),
                    widen(b.clone(), bt, ty),
                    widen(c.clone(), ct, ty),
                );
                match op {
                    Op3::Vec3 => self.bind(format!("vec3<f32>({a}, {b}, {c})")),
                    Op3::Clamp => self.bind(format!("min(max({wa}, {wb}), {wc})")),
                    Op3::Mix => {
                        let span = self.bounded(ty, format!("{wb} - {wa}"));
                        self.bounded(ty, format!("{wa} + {span} * {wc}"))
                    }
                    Op3::Smoothstep => {
                        let d = self.bind(format!("{wb} - {wa}"));
                        let ok = self.bind(format!("abs({d}) >= {}", lit(ty, DIV_FLOOR)));
                        let q = self.bounded(
                            ty,
                            format!("({wc} - {wa}) / select({}, {d}, {ok})", lit(ty, 1.0)),
                        );
                        let u = self.bind(format!(
                            "clamp(select({}, {q}, {ok}), {}, {})",
                            lit(ty, 0.0),
                            lit(ty, 0.0),
                            lit(ty, 1.0)
                        ));
                        self.bind(format!("{u} * {u} * ({} - 2.0 * {u})", lit(ty, 3.0)))
                    }
                    Op3::Select => self.bind(format!("select({a}, {b}, {c})")),
                }
            }
        }
    }
}
