//! The type checker: the syntax tree becomes the typed tree ([`super::tree`]), names resolved
//! to variables, parameters and functions (`names`), every node given a type, and
//! every mistake reported at its characters.

use super::parse::{Ast, AstKind, BinOp};
pub(crate) use super::tree::{AttrName, Expr, Node, Scope};
pub(crate) use super::vocab::{
    Op1, Op2, Op3, Ty, Var, EVERY_VARIABLE, FUNCTIONS, MAX_RAND, VARIABLES,
};
use super::ExprError;

/// Type-checks a syntax tree into a typed tree.
pub(crate) fn check(ast: &Ast, scope: &Scope) -> Result<Expr, ExprError> {
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
        AstKind::Name(name) => super::names::resolve(name, ast, scope, check),
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
        "abs" | "sqrt" | "exp" | "log" | "sin" | "cos" | "floor" | "fract" | "ceil" | "round"
        | "sign" | "tan" | "asin" | "acos" | "atan" | "log2" => {
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
                "ceil" => Op1::Ceil,
                "round" => Op1::Round,
                "sign" => Op1::Sign,
                "tan" => Op1::Tan,
                "asin" => Op1::Asin,
                "acos" => Op1::Acos,
                "atan" => Op1::Atan,
                "log2" => Op1::Log2,
                _ => Op1::Fract,
            };
            unary(op, ty, a)
        }
        "min" | "max" | "pow" | "atan2" | "step" | "rem" => {
            let ty = same_or_scalar()?;
            let op = match name {
                "min" => Op2::Min,
                "max" => Op2::Max,
                "pow" => Op2::Pow,
                "atan2" => Op2::Atan2,
                "rem" => Op2::Rem,
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
