//! The typed expression tree, and the type checker that builds it from the syntax tree:
//! names resolved to variables, parameters and functions, every node given a type, and every
//! mistake reported at its characters.

use std::collections::BTreeMap;

use glam::DVec3;

use super::parse::{Ast, AstKind, BinOp};
pub use super::vocab::{closest, Op1, Op2, Op3, Ty, Var, FUNCTIONS, MAX_RAND, VARIABLES};
use super::ExprError;

/// A node of the typed tree.
#[derive(Clone, Debug, PartialEq)]
pub enum Node {
    /// A scalar constant.
    Scalar(f64),
    /// A vector constant.
    Vector(DVec3),
    /// A variable.
    Var(Var),
    /// `rand(k)`: the particle's k-th uniform number in [0, 1).
    Rand(u32),
    /// The value of the effect's `index`-th attribute (in the file's name order), as the
    /// place evaluating the expression holds it.
    Attr(u8),
    /// A parameter that the host may change at run time (compiled with live params): the
    /// `index`-th of the effect's `params` in name order, and its value now (f64 of the f32
    /// the GPU reads, which the reference evaluates).
    Param {
        /// Its place among the effect's params, in name order.
        index: u32,
        /// Its current value.
        value: f64,
    },
    /// One operand.
    Unary(Op1, Box<Expr>),
    /// Two operands.
    Binary(Op2, Box<Expr>, Box<Expr>),
    /// Three operands.
    Ternary(Op3, Box<Expr>, Box<Expr>, Box<Expr>),
}

/// A typed expression.
#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    /// What it computes.
    pub node: Node,
    /// Its type.
    pub ty: Ty,
}

impl Expr {
    /// A node of a known type.
    pub fn new(node: Node, ty: Ty) -> Self {
        Self { node, ty }
    }

    /// The children, in order.
    pub fn children(&self) -> Vec<&Expr> {
        match &self.node {
            Node::Unary(_, a) => vec![a],
            Node::Binary(_, a, b) => vec![a, b],
            Node::Ternary(_, a, b, c) => vec![a, b, c],
            _ => Vec::new(),
        }
    }

    /// Every variable the expression reads (after folding, only those that matter).
    pub fn reads(&self, var: Var) -> bool {
        matches!(self.node, Node::Var(v) if v == var)
            || self.children().iter().any(|c| c.reads(var))
    }

    /// Whether it reads attribute `index` (after folding, only where it matters).
    pub fn reads_attr(&self, index: u8) -> bool {
        matches!(self.node, Node::Attr(i) if i == index)
            || self.children().iter().any(|c| c.reads_attr(index))
    }

    /// Every attribute it reads, as a bit set of indices.
    pub fn attrs_read(&self) -> u64 {
        let own = match self.node {
            Node::Attr(i) => 1u64 << i,
            _ => 0,
        };
        self.children()
            .iter()
            .fold(own, |set, c| set | c.attrs_read())
    }

    /// Whether it reads the gradient noise through `op` ([`Op1::Noise`] or [`Op1::Curl`]): the
    /// module then needs its helpers.
    pub fn uses(&self, op: Op1) -> bool {
        matches!(&self.node, Node::Unary(o, _) if *o == op)
            || self.children().iter().any(|c| c.uses(op))
    }

    /// True when it draws random numbers.
    pub fn draws_random(&self) -> bool {
        matches!(self.node, Node::Rand(_)) || self.children().iter().any(|c| c.draws_random())
    }

    /// Sets every [`Node::Param`] of index `index` to `value`.
    pub fn set_param(&mut self, index: u32, value: f64) {
        match &mut self.node {
            Node::Param { index: i, value: v } if *i == index => *v = value,
            Node::Unary(_, a) => a.set_param(index, value),
            Node::Binary(_, a, b) => {
                a.set_param(index, value);
                b.set_param(index, value);
            }
            Node::Ternary(_, a, b, c) => {
                a.set_param(index, value);
                b.set_param(index, value);
                c.set_param(index, value);
            }
            _ => {}
        }
    }

    /// Number of nodes.
    pub fn size(&self) -> usize {
        1 + self.children().iter().map(|c| c.size()).sum::<usize>()
    }
}

/// What an expression may name: the variables of where it is evaluated, the effect's params
/// and `dt`, its step.
pub struct Scope<'a> {
    /// The effect's `params`.
    pub params: &'a BTreeMap<String, f64>,
    /// The effect's dt (s).
    pub dt: f64,
    /// Params are read at run time ([`Node::Param`]) instead of folded as constants.
    pub live: bool,
    /// The variables it may read ([`VARIABLES`] for a force; fewer at spawn).
    pub vars: &'a [Var],
    /// What its value is, for messages: "an acceleration".
    pub role: &'a str,
    /// The effect's attributes, in name order.
    pub attrs: &'a [AttrName],
    /// Whether the attributes hold values where this expression is evaluated (not at spawn,
    /// where they are being given theirs).
    pub reads_attrs: bool,
    /// The effect's named expressions (`define`), expanded where they are read.
    pub defines: &'a [super::define::Define],
    /// Nodes the named expressions read so far have expanded to (at most
    /// [`super::define::MAX_EXPANDED`]).
    pub expanded: std::cell::Cell<usize>,
}

/// An attribute as expressions see it: its name, type, and its value when it never changes
/// from a constant (then reading it is reading the constant).
#[derive(Clone, Debug, PartialEq)]
pub struct AttrName {
    /// As written in the file.
    pub name: String,
    /// Its type.
    pub ty: Ty,
    /// Its value for every particle, when it is a constant that never changes.
    pub constant: Option<DVec3>,
}

impl Scope<'_> {
    /// The variables as messages list them: "x, v, t, age, life and dt".
    pub(super) fn names(&self) -> String {
        let mut names: Vec<&str> = self.vars.iter().map(|v| v.name()).collect();
        names.push("dt");
        let last = names.pop().unwrap_or("dt");
        match names.is_empty() {
            true => last.to_string(),
            false => format!("{} and {last}", names.join(", ")),
        }
    }
}

/// Type-checks a syntax tree into a typed tree.
pub fn check(ast: &Ast, scope: &Scope) -> Result<Expr, ExprError> {
    let err = |msg: String| ExprError::new(msg, ast.start, ast.end);
    match &ast.kind {
        AstKind::Num(x) => {
            if x.abs() > super::VALUE_BOUND {
                return Err(err(format!(
                    "the number {x} is beyond ±{:e}, the range expressions compute in",
                    super::VALUE_BOUND
                )));
            }
            Ok(Expr::new(Node::Scalar(*x), Ty::Scalar))
        }
        AstKind::Name(name) => super::names::resolve(name, ast, scope),
        AstKind::Neg(a) => {
            let a = check(a, scope)?;
            numeric(&a, ast, "-")?;
            let ty = a.ty;
            Ok(Expr::new(Node::Unary(Op1::Neg, Box::new(a)), ty))
        }
        AstKind::Binary(op, a, b) => {
            let (ea, eb) = (check(a, scope)?, check(b, scope)?);
            let sym = op.symbol();
            numeric(&ea, a, sym)?;
            numeric(&eb, b, sym)?;
            let ty = match op {
                BinOp::Add | BinOp::Sub => {
                    if ea.ty != eb.ty {
                        return Err(err(format!(
                            "`{sym}` needs two values of one type, got {} {sym} {} (write vec3(s, s, s) to make a vec3 of a number)",
                            ea.ty.name(),
                            eb.ty.name()
                        )));
                    }
                    ea.ty
                }
                BinOp::Mul | BinOp::Div => broadcast(ea.ty, eb.ty),
                _ => {
                    for (e, side) in [(&ea, a), (&eb, b)] {
                        if e.ty != Ty::Scalar {
                            return Err(ExprError::new(
                                format!("`{sym}` compares numbers, got a {}", e.ty.name()),
                                side.start,
                                side.end,
                            ));
                        }
                    }
                    Ty::Bool
                }
            };
            let op2 = match op {
                BinOp::Add => Op2::Add,
                BinOp::Sub => Op2::Sub,
                BinOp::Mul => Op2::Mul,
                BinOp::Div => Op2::Div,
                c => Op2::Compare(*c),
            };
            Ok(Expr::new(Node::Binary(op2, Box::new(ea), Box::new(eb)), ty))
        }
        AstKind::Member(a, name, (s, e)) => {
            let ea = check(a, scope)?;
            let index = match name.as_str() {
                "x" => 0,
                "y" => 1,
                "z" => 2,
                _ => {
                    return Err(ExprError::new(
                        format!("unknown component `.{name}`: a vec3 has .x, .y and .z"),
                        *s,
                        *e,
                    ))
                }
            };
            if ea.ty != Ty::Vec3 {
                return Err(ExprError::new(
                    format!("`.{name}` needs a vec3, got a {}", ea.ty.name()),
                    a.start,
                    a.end,
                ));
            }
            Ok(Expr::new(
                Node::Unary(Op1::Component(index), Box::new(ea)),
                Ty::Scalar,
            ))
        }
        AstKind::Call(name, name_span, args) => call(name, *name_span, args, ast, scope),
    }
}

/// A value usable in arithmetic: not a bool.
fn numeric(e: &Expr, at: &Ast, what: &str) -> Result<(), ExprError> {
    if e.ty == Ty::Bool {
        return Err(ExprError::new(
            format!("`{what}` needs a number or a vec3, got a bool (a comparison): use select(a, b, condition)"),
            at.start,
            at.end,
        ));
    }
    Ok(())
}

/// The type of an operation applied per component where a scalar stands for (s, s, s).
fn broadcast(a: Ty, b: Ty) -> Ty {
    if a == Ty::Vec3 || b == Ty::Vec3 {
        Ty::Vec3
    } else {
        Ty::Scalar
    }
}

fn call(
    name: &str,
    (ns, ne): (usize, usize),
    args: &[Ast],
    ast: &Ast,
    scope: &Scope,
) -> Result<Expr, ExprError> {
    let Some(&(_, arity)) = FUNCTIONS.iter().find(|(f, _)| *f == name) else {
        let known: Vec<&str> = FUNCTIONS.iter().map(|(f, _)| *f).collect();
        return Err(ExprError::new(
            format!(
                "unknown function `{name}`; the functions are {}",
                known.join(", ")
            ),
            ns,
            ne,
        ));
    };
    if args.len() != arity {
        return Err(ExprError::new(
            format!(
                "`{name}` takes {arity} argument{}, got {}",
                if arity == 1 { "" } else { "s" },
                args.len()
            ),
            ast.start,
            ast.end,
        ));
    }
    if name == "hsv" {
        let typed: Vec<Expr> = args
            .iter()
            .map(|a| check(a, scope))
            .collect::<Result<_, _>>()?;
        if let Some(i) = typed.iter().position(|e| e.ty != Ty::Scalar) {
            return Err(ExprError::new(
                format!(
                    "argument {} of `hsv` (hue, saturation, value) must be a f32, got a {}",
                    i + 1,
                    typed[i].ty.name()
                ),
                args[i].start,
                args[i].end,
            ));
        }
        return check(
            &super::draws::expand_hsv(args, (ast.start, ast.end))?,
            scope,
        );
    }
    if let Some(draw) = super::draws::find(name) {
        let last = MAX_RAND + 1 - draw.streams;
        return match args[0].kind {
            AstKind::Num(k) if k.fract() == 0.0 && (0.0..=f64::from(last)).contains(&k) => {
                check(&draw.expand(k as u32, (ast.start, ast.end))?, scope)
            }
            _ => Err(ExprError::new(
                format!(
                    "{name}(k) reads rand(k) to rand(k + {}): k is a whole number from 0 to {last}, written as a literal",
                    draw.streams - 1
                ),
                args[0].start,
                args[0].end,
            )),
        };
    }
    if name == "rand" {
        return match args[0].kind {
            AstKind::Num(k) if k.fract() == 0.0 && (0.0..=f64::from(MAX_RAND)).contains(&k) => {
                Ok(Expr::new(Node::Rand(k as u32), Ty::Scalar))
            }
            _ => Err(ExprError::new(
                format!(
                    "rand(k) takes a whole number k from 0 to {MAX_RAND}, written as a literal"
                ),
                args[0].start,
                args[0].end,
            )),
        };
    }
    let typed: Vec<Expr> = args
        .iter()
        .map(|a| check(a, scope))
        .collect::<Result<_, _>>()?;
    let tys: Vec<Ty> = typed.iter().map(|e| e.ty).collect();
    let arg_err = |i: usize, msg: String| ExprError::new(msg, args[i].start, args[i].end);
    let want = |i: usize, ty: Ty| -> Result<(), ExprError> {
        if tys[i] != ty {
            return Err(arg_err(
                i,
                format!(
                    "argument {} of `{name}` must be a {}, got a {}",
                    i + 1,
                    ty.name(),
                    tys[i].name()
                ),
            ));
        }
        Ok(())
    };
    for (i, ty) in tys.iter().enumerate() {
        let bool_ok = name == "select" && i == 2;
        if *ty == Ty::Bool && !bool_ok {
            return Err(arg_err(
                i,
                format!(
                    "argument {} of `{name}` must be a number or a vec3, got a bool",
                    i + 1
                ),
            ));
        }
    }
    // The first argument's type is the result's for the per-component functions; the others
    // must match it or be scalars (which stand for (s, s, s)).
    let same_or_scalar = || -> Result<Ty, ExprError> {
        let ty = tys.iter().copied().fold(Ty::Scalar, broadcast);
        for (i, t) in tys.iter().enumerate() {
            if *t != ty && *t != Ty::Scalar {
                return Err(arg_err(
                    i,
                    format!(
                        "argument {} of `{name}` must be a {} or a number",
                        i + 1,
                        ty.name()
                    ),
                ));
            }
        }
        Ok(ty)
    };
    let mut it = typed.into_iter();
    let mut next = || Box::new(it.next().expect("arity checked"));
    let unary = |op: Op1, ty: Ty, a: Box<Expr>| Ok(Expr::new(Node::Unary(op, a), ty));
    match name {
        "vec3" => {
            for i in 0..3 {
                want(i, Ty::Scalar)?;
            }
            Ok(Expr::new(
                Node::Ternary(Op3::Vec3, next(), next(), next()),
                Ty::Vec3,
            ))
        }
        "dot" | "cross" => {
            want(0, Ty::Vec3)?;
            want(1, Ty::Vec3)?;
            let (op, ty) = if name == "dot" {
                (Op2::Dot, Ty::Scalar)
            } else {
                (Op2::Cross, Ty::Vec3)
            };
            Ok(Expr::new(Node::Binary(op, next(), next()), ty))
        }
        "length" => {
            want(0, Ty::Vec3)?;
            unary(Op1::Length, Ty::Scalar, next())
        }
        "noise" => {
            want(0, Ty::Vec3)?;
            unary(Op1::Noise, Ty::Scalar, next())
        }
        "curl" => {
            want(0, Ty::Vec3)?;
            unary(Op1::Curl, Ty::Vec3, next())
        }
        "normalize" => {
            want(0, Ty::Vec3)?;
            unary(Op1::Normalize, Ty::Vec3, next())
        }
        "abs" | "sqrt" | "exp" | "log" | "sin" | "cos" | "floor" | "fract" => {
            let a = next();
            let ty = a.ty;
            let op = match name {
                "abs" => Op1::Abs,
                "sqrt" => Op1::Sqrt,
                "exp" => Op1::Exp,
                "log" => Op1::Log,
                "sin" => Op1::Sin,
                "cos" => Op1::Cos,
                "floor" => Op1::Floor,
                _ => Op1::Fract,
            };
            unary(op, ty, a)
        }
        "min" | "max" | "pow" | "atan2" | "step" => {
            let ty = same_or_scalar()?;
            let op = match name {
                "min" => Op2::Min,
                "max" => Op2::Max,
                "pow" => Op2::Pow,
                "atan2" => Op2::Atan2,
                _ => Op2::Step,
            };
            Ok(Expr::new(Node::Binary(op, next(), next()), ty))
        }
        "clamp" | "mix" | "smoothstep" => {
            let ty = same_or_scalar()?;
            let op = match name {
                "clamp" => Op3::Clamp,
                "mix" => Op3::Mix,
                _ => Op3::Smoothstep,
            };
            Ok(Expr::new(Node::Ternary(op, next(), next(), next()), ty))
        }
        "select" => {
            want(2, Ty::Bool)?;
            let (a, b) = (next(), next());
            if a.ty != b.ty {
                return Err(ExprError::new(
                    format!(
                        "select's first two arguments must have one type, got {} and {}",
                        a.ty.name(),
                        b.ty.name()
                    ),
                    args[0].start,
                    args[1].end,
                ));
            }
            let ty = a.ty;
            Ok(Expr::new(Node::Ternary(Op3::Select, a, b, next()), ty))
        }
        _ => unreachable!("every function in FUNCTIONS is handled"),
    }
}
