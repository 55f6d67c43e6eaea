//! Named expressions (`define: {"r": "length(x - vec3(0.0, 1.0, 0.0))"}`): written once and
//! read by name in any expression of the effect, as if their text stood there in parentheses.
//! Each is parsed here; the type checker expands a name where it is read, in the scope of that
//! place (`super::typed::check`), so one that reads `v` is an error only where `v` is not
//! known. A name that refers back to itself through others is an error at its definition, and
//! expansions are counted, so that definitions doubling one another cannot blow a tree up.

use std::collections::BTreeMap;

use super::parse::{Ast, AstKind};
use super::ExprError;

/// The most nodes the named expressions read by one expression may expand to in all.
pub(crate) const MAX_EXPANDED: usize = 16_384;

/// A named expression.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Define {
    /// Its name, as expressions read it.
    pub name: String,
    /// Its syntax tree (character ranges within its own string), or why there is none.
    pub body: Body,
}

/// What a named expression holds.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Body {
    /// Its syntax tree.
    Parsed(Ast),
    /// Its text does not parse (the mistake is reported at the definition).
    Broken,
    /// It refers back to itself (reported at the definition).
    Circular,
}

/// A mistake in a named expression: its name and the mistake (ranges within its string; a
/// circle of references spans the whole string).
pub(crate) type DefineError = (String, ExprError);

/// Parses `written` (name → text). Returns every definition, those that do not parse or that
/// take part in a circle of references without a tree (so that a place reading one says
/// so), and their mistakes.
pub(crate) fn parse_all(written: &BTreeMap<String, String>) -> (Vec<Define>, Vec<DefineError>) {
    let mut defines = Vec::new();
    let mut errors = Vec::new();
    for (name, text) in written {
        let parsed = super::lex::tokenize(text).and_then(|tokens| {
            if tokens.len() > super::MAX_TOKENS {
                let t = &tokens[super::MAX_TOKENS];
                return Err(ExprError::new(
                    format!("longer than {} tokens", super::MAX_TOKENS),
                    t.start,
                    t.end,
                ));
            }
            super::parse::parse(&tokens)
        });
        let body = match parsed {
            Ok(ast) => Body::Parsed(ast),
            Err(e) => {
                errors.push((name.clone(), e));
                Body::Broken
            }
        };
        defines.push(Define {
            name: name.clone(),
            body,
        });
    }
    // A definition on a circle of references cannot be expanded: report the circle, drop it.
    let mut circular = Vec::new();
    for d in &defines {
        if let Some(path) = circle_from(d, &defines) {
            let end = written[&d.name].chars().count();
            circular.push(d.name.clone());
            errors.push((
                d.name.clone(),
                ExprError::new(
                    format!(
                        "`{}` refers to itself ({}): named expressions may not refer to each other in a circle",
                        d.name,
                        path.join(" -> ")
                    ),
                    0,
                    end,
                ),
            ));
        }
    }
    for d in &mut defines {
        if circular.contains(&d.name) {
            d.body = Body::Circular;
        }
    }
    (defines, errors)
}

/// The names `ast` reads (variables, params, definitions alike), in order.
fn names_in<'a>(ast: &'a Ast, out: &mut Vec<&'a str>) {
    match &ast.kind {
        AstKind::Num(_) => {}
        AstKind::Name(n) => out.push(n),
        AstKind::Neg(a) | AstKind::Member(a, _, _) => names_in(a, out),
        AstKind::Binary(_, a, b) => {
            names_in(a, out);
            names_in(b, out);
        }
        AstKind::Call(_, _, args) => args.iter().for_each(|a| names_in(a, out)),
    }
}

/// A path of references from `start` back to itself, when there is one.
fn circle_from(start: &Define, defines: &[Define]) -> Option<Vec<String>> {
    // Depth-first over the definitions each one reads; `path` is the current chain.
    fn walk(
        at: &Define,
        start: &str,
        defines: &[Define],
        path: &mut Vec<String>,
        seen: &mut Vec<String>,
    ) -> bool {
        let Body::Parsed(ast) = &at.body else {
            return false;
        };
        let mut names = Vec::new();
        names_in(ast, &mut names);
        for n in names {
            if n == start {
                path.push(n.to_string());
                return true;
            }
            if seen.iter().any(|s| s == n) {
                continue;
            }
            if let Some(next) = defines.iter().find(|d| d.name == n) {
                seen.push(n.to_string());
                path.push(n.to_string());
                if walk(next, start, defines, path, seen) {
                    return true;
                }
                path.pop();
            }
        }
        false
    }
    let mut path = vec![start.name.clone()];
    let mut seen = Vec::new();
    walk(start, &start.name, defines, &mut path, &mut seen).then_some(path)
}
