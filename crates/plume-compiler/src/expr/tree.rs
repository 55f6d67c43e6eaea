//! The typed expression tree: its nodes, with their types, and the scope that says what an
//! expression may name where it is evaluated.

use std::collections::BTreeMap;

use glam::DVec3;

use super::vocab::{Op1, Op2, Op3, Ty, Var};
/// A node of the typed tree.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Node {
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
    pub(crate) node: Node,
    /// Its type.
    pub(crate) ty: Ty,
}

impl Expr {
    /// A node of a known type.
    pub(crate) fn new(node: Node, ty: Ty) -> Self {
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
    pub(crate) fn reads(&self, var: Var) -> bool {
        matches!(self.node, Node::Var(v) if v == var)
            || self.children().iter().any(|c| c.reads(var))
    }

    /// Every attribute it reads, as a bit set of indices.
    pub(crate) fn attrs_read(&self) -> u64 {
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
    pub(crate) fn uses(&self, op: Op1) -> bool {
        matches!(&self.node, Node::Unary(o, _) if *o == op)
            || self.children().iter().any(|c| c.uses(op))
    }

    /// True when it draws random numbers.
    pub(crate) fn draws_random(&self) -> bool {
        matches!(self.node, Node::Rand(_)) || self.children().iter().any(|c| c.draws_random())
    }

    /// Sets every `Node::Param` of index `index` to `value`.
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
    /// Params are read at run time (`Node::Param`) instead of folded as constants.
    pub live: bool,
    /// The variables it may read (`VARIABLES` for a force; fewer at spawn).
    pub(crate) vars: &'a [Var],
    /// What its value is, for messages: "an acceleration".
    pub role: &'a str,
    /// The effect's attributes, in name order.
    pub(crate) attrs: &'a [AttrName],
    /// Whether the attributes hold values where this expression is evaluated (not at spawn,
    /// where they are being given theirs).
    pub(crate) reads_attrs: bool,
    /// The effect's named expressions (`define`), expanded where they are read.
    pub(crate) defines: &'a [super::define::Define],
    /// Nodes the named expressions read so far have expanded to (at most
    /// `MAX_EXPANDED`).
    pub expanded: std::cell::Cell<usize>,
}

/// An attribute as expressions see it: its name, type, and its value when it never changes
/// from a constant (then reading it is reading the constant).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct AttrName {
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
