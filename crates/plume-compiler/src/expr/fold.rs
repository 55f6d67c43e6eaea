//! Folding: constant subtrees are evaluated once at compile time (with the reference's
//! guarded semantics, in f64), and terms that cannot matter are dropped: `e + 0`, `e * 1`,
//! `e * 0` (0, since every value is finite), `0 / e`, `--e`, and a `select` whose condition is
//! constant. An expression that folds to the zero vector cannot act, and is pruned like any term.

use glam::DVec3;

use super::eval::{eval, Inputs, Value};
use super::typed::{Expr, Node, Op1, Op2, Op3, Ty};
use super::DIV_FLOOR;

/// True for a subtree with no variables and no random numbers.
pub(crate) fn is_constant(e: &Expr) -> bool {
    match &e.node {
        Node::Scalar(_) | Node::Vector(_) => true,
        Node::Var(_) | Node::Rand(_) | Node::Param { .. } | Node::Attr(_) => false,
        _ => e.children().into_iter().all(is_constant),
    }
}

/// The constant's value, if `e` is a constant leaf.
fn leaf(e: &Expr) -> Option<DVec3> {
    match e.node {
        Node::Scalar(x) => Some(DVec3::splat(x)),
        Node::Vector(v) => Some(v),
        _ => None,
    }
}

fn is(e: &Expr, value: f64) -> bool {
    leaf(e) == Some(DVec3::splat(value))
}

/// The zero of type `ty`.
fn zero(ty: Ty) -> Expr {
    match ty {
        Ty::Vec3 => Expr::new(Node::Vector(DVec3::ZERO), ty),
        _ => Expr::new(Node::Scalar(0.0), ty),
    }
}

/// `e` as a value of type `ty`: itself, or a scalar constant widened to a vector.
fn widen(e: Expr, ty: Ty) -> Option<Expr> {
    if e.ty == ty {
        return Some(e);
    }
    match (e.node, ty) {
        (Node::Scalar(x), Ty::Vec3) => Some(Expr::new(Node::Vector(DVec3::splat(x)), ty)),
        _ => None,
    }
}

/// Folds `e` bottom-up.
pub(crate) fn fold(e: Expr) -> Expr {
    let ty = e.ty;
    let node = match e.node {
        Node::Unary(op, a) => Node::Unary(op, Box::new(fold(*a))),
        Node::Binary(op, a, b) => Node::Binary(op, Box::new(fold(*a)), Box::new(fold(*b))),
        Node::Ternary(op, a, b, c) => Node::Ternary(
            op,
            Box::new(fold(*a)),
            Box::new(fold(*b)),
            Box::new(fold(*c)),
        ),
        leaf => leaf,
    };
    let e = Expr::new(node, ty);
    if ty != Ty::Bool && !matches!(e.node, Node::Scalar(_) | Node::Vector(_)) && is_constant(&e) {
        return match eval(&e, &Inputs::default()) {
            Value::V(v) => Expr::new(Node::Vector(v), ty),
            other => Expr::new(Node::Scalar(other.s()), ty),
        };
    }
    simplify(e)
}

fn simplify(e: Expr) -> Expr {
    let ty = e.ty;
    match e.node {
        Node::Binary(Op2::Add, a, b) if is(&b, 0.0) => *a,
        Node::Binary(Op2::Add, a, b) if is(&a, 0.0) => *b,
        Node::Binary(Op2::Sub, a, b) if is(&b, 0.0) => *a,
        Node::Binary(Op2::Sub, a, b) if is(&a, 0.0) => Expr::new(Node::Unary(Op1::Neg, b), ty),
        Node::Binary(Op2::Mul, a, b) if is(&a, 0.0) || is(&b, 0.0) => zero(ty),
        Node::Binary(Op2::Div, a, _) if is(&a, 0.0) => zero(ty),
        // A constant divisor the guard refuses on every component: the quotient is 0.
        Node::Binary(Op2::Div, _, b)
            if leaf(&b).is_some_and(|d| d.abs().max_element() < DIV_FLOOR) =>
        {
            zero(ty)
        }
        Node::Binary(Op2::Mul, a, b) if is(&b, 1.0) && a.ty == ty => *a,
        Node::Binary(Op2::Mul, a, b) if is(&a, 1.0) && b.ty == ty => *b,
        Node::Binary(Op2::Div, a, b) if is(&b, 1.0) && a.ty == ty => *a,
        Node::Unary(Op1::Neg, a) if matches!(a.node, Node::Unary(Op1::Neg, _)) => {
            let Node::Unary(_, inner) = a.node else {
                unreachable!()
            };
            *inner
        }
        Node::Ternary(Op3::Select, f, t, c) if is_constant(&c) => {
            let picked = if matches!(eval(&c, &Inputs::default()), Value::B(true)) {
                *t
            } else {
                *f
            };
            widen(picked, ty).expect("select's branches share its type")
        }
        Node::Ternary(Op3::Select, f, t, _) if f == t => *f,
        node => Expr::new(node, ty),
    }
}

/// True when `e` is a constant whose every component passes the division guard.
pub(crate) fn is_safe_divisor(e: &Expr) -> bool {
    leaf(e).is_some_and(|d| d.abs().min_element() >= DIV_FLOOR)
}

/// True when `e` is the zero vector: an acceleration that cannot act.
pub(crate) fn is_zero(e: &Expr) -> bool {
    matches!(e.node, Node::Vector(v) if v == DVec3::ZERO)
}
