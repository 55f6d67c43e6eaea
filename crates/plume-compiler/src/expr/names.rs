//! Name resolution for the type checker: a name in an expression is a variable, `dt`, an
//! attribute, a named expression (expanded here, in the reading place's scope), a param (a
//! vector param from its three components), or a mistake that says what the names are and
//! which known one is nearest.

use glam::DVec3;

use super::parse::{Ast, AstKind};
use super::tree::{Expr, Node, Scope};
use super::vocab::{closest, Op3, Ty, EVERY_VARIABLE, FUNCTIONS};
use super::ExprError;

/// The type checker, which a named expression is checked with where it is read (passed in,
/// so that this module does not import the checker that calls it).
pub(super) type Check = fn(&Ast, &Scope) -> Result<Expr, ExprError>;

/// The typed expression `name` (written at `ast`) stands for in `scope`.
pub(super) fn resolve(
    name: &str,
    ast: &Ast,
    scope: &Scope,
    check: Check,
) -> Result<Expr, ExprError> {
    let err = |msg: String| ExprError::new(msg, ast.start, ast.end);
    if let Some(v) = EVERY_VARIABLE.iter().find(|v| v.name() == name) {
        if !scope.vars.contains(v) {
            return Err(err(format!(
                "`{name}` is not known here: {} may read {}",
                scope.role,
                scope.names()
            )));
        }
        return Ok(Expr::new(Node::Var(*v), v.ty()));
    }
    if name == "dt" {
        return Ok(Expr::new(Node::Scalar(scope.dt), Ty::Scalar));
    }
    if let Some(i) = scope.attrs.iter().position(|a| a.name == *name) {
        let attr = &scope.attrs[i];
        if !scope.reads_attrs {
            return Err(err(format!(
                "the attribute `{name}` has no value yet: {} is computed at spawn, before the attributes get theirs",
                scope.role
            )));
        }
        return Ok(match attr.constant {
            Some(c) if attr.ty == Ty::Vec3 => Expr::new(Node::Vector(c), Ty::Vec3),
            Some(c) => Expr::new(Node::Scalar(c.x), Ty::Scalar),
            None => Expr::new(Node::Attr(i as u8), attr.ty),
        });
    }
    if let Some(d) = scope.defines.iter().find(|d| d.name == *name) {
        let ast = match &d.body {
            super::define::Body::Parsed(ast) => ast,
            super::define::Body::Broken => {
                return Err(err(format!(
                    "the named expression `{name}` has a mistake (define.{name})"
                )))
            }
            super::define::Body::Circular => {
                return Err(err(format!(
                    "the named expression `{name}` refers to itself in a circle (define.{name})"
                )))
            }
        };
        let e = check(ast, scope)
            .map_err(|inner| err(format!("in `{name}` (define.{name}): {}", inner.message)))?;
        let total = scope.expanded.get() + e.size();
        if total > super::define::MAX_EXPANDED {
            return Err(err(format!(
                "the named expressions read here expand to more than {} nodes: read a shorter one, or fewer",
                super::define::MAX_EXPANDED
            )));
        }
        scope.expanded.set(total);
        return Ok(e);
    }
    if let Some(value) = scope.params.get(name) {
        if scope.live {
            let index = scope.params.keys().position(|k| k == name).unwrap_or(0);
            let value = f64::from(*value as f32);
            let index = index as u32;
            return Ok(Expr::new(Node::Param { index, value }, Ty::Scalar));
        }
        return Ok(Expr::new(Node::Scalar(*value), Ty::Scalar));
    }
    // A vector param is held as its three components.
    let parts = ["x", "y", "z"].map(|c| format!("{name}.{c}"));
    if parts.iter().all(|p| scope.params.contains_key(p)) {
        let [x, y, z] = parts.map(|p| {
            check(
                &Ast {
                    kind: AstKind::Name(p),
                    start: ast.start,
                    end: ast.end,
                },
                scope,
            )
        });
        return Ok(match (x?, y?, z?) {
            (
                Expr {
                    node: Node::Scalar(x),
                    ..
                },
                Expr {
                    node: Node::Scalar(y),
                    ..
                },
                Expr {
                    node: Node::Scalar(z),
                    ..
                },
            ) => Expr::new(Node::Vector(DVec3::new(x, y, z)), Ty::Vec3),
            (x, y, z) => Expr::new(
                Node::Ternary(Op3::Vec3, Box::new(x), Box::new(y), Box::new(z)),
                Ty::Vec3,
            ),
        });
    }
    if FUNCTIONS.iter().any(|(f, _)| *f == name) {
        return Err(err(format!(
            "`{name}` is a function: call it, `{name}(...)`"
        )));
    }
    // A vector param by its name, once.
    let mut params: Vec<&str> = scope
        .params
        .keys()
        .map(|k| k.strip_suffix(".x").unwrap_or(k))
        .filter(|k| !k.ends_with(".y") && !k.ends_with(".z"))
        .collect();
    params.dedup();
    let attrs: Vec<&str> = match scope.reads_attrs {
        true => scope.attrs.iter().map(|a| a.name.as_str()).collect(),
        false => Vec::new(),
    };
    let known = scope
        .vars
        .iter()
        .map(|v| v.name())
        .chain(["dt"])
        .chain(attrs.iter().copied())
        .chain(scope.defines.iter().map(|d| d.name.as_str()))
        .chain(params.iter().copied());
    let hint = match closest(name, known) {
        Some(near) => format!("did you mean `{near}`? "),
        None => String::new(),
    };
    Err(err(format!(
        "unknown name `{name}`: {hint}the variables are {}{}{}",
        scope.names(),
        if attrs.is_empty() {
            String::new()
        } else {
            format!(", the attributes are {}", attrs.join(", "))
        },
        if params.is_empty() {
            ", and the file has no params".to_string()
        } else {
            format!(", and the params are {}", params.join(", "))
        }
    )))
}
