//! The expression parser: tokens to a syntax tree with character ranges, by precedence
//! climbing. Lowest to highest: comparisons (`< <= > >= == !=`, not chained), `+ -`, `* /`,
//! unary `-`, then calls, member access (`.x .y .z`) and parentheses.

use super::lex::{Tok, Token};
use super::ExprError;

/// Deeper nesting than this is refused (a recursive parser must not overflow the stack on
/// generated input).
pub(crate) const MAX_DEPTH: usize = 64;

/// A binary operator as written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum BinOp {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*`
    Mul,
    /// `/`
    Div,
    /// `<`
    Lt,
    /// `<=`
    Le,
    /// `>`
    Gt,
    /// `>=`
    Ge,
    /// `==`
    Eq,
    /// `!=`
    Ne,
}

impl BinOp {
    fn of(op: &str) -> Option<(BinOp, u8)> {
        Some(match op {
            "<" => (BinOp::Lt, 1),
            "<=" => (BinOp::Le, 1),
            ">" => (BinOp::Gt, 1),
            ">=" => (BinOp::Ge, 1),
            "==" => (BinOp::Eq, 1),
            "!=" => (BinOp::Ne, 1),
            "+" => (BinOp::Add, 2),
            "-" => (BinOp::Sub, 2),
            "*" => (BinOp::Mul, 3),
            "/" => (BinOp::Div, 3),
            _ => return None,
        })
    }

    /// The operator as written.
    pub(crate) fn symbol(self) -> &'static str {
        match self {
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Mul => "*",
            BinOp::Div => "/",
            BinOp::Lt => "<",
            BinOp::Le => "<=",
            BinOp::Gt => ">",
            BinOp::Ge => ">=",
            BinOp::Eq => "==",
            BinOp::Ne => "!=",
        }
    }

    /// Applies a comparison (false for the arithmetic operators).
    pub(crate) fn compare(self, a: f64, b: f64) -> bool {
        match self {
            BinOp::Lt => a < b,
            BinOp::Le => a <= b,
            BinOp::Gt => a > b,
            BinOp::Ge => a >= b,
            BinOp::Eq => a == b,
            BinOp::Ne => a != b,
            _ => false,
        }
    }

    /// True for the comparisons (they give a bool).
    pub(crate) fn is_comparison(self) -> bool {
        matches!(
            self,
            BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne
        )
    }
}

/// A syntax tree node and the characters it covers.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Ast {
    /// What it is.
    pub kind: AstKind,
    /// First character.
    pub start: usize,
    /// One past the last character.
    pub end: usize,
}

/// The shapes of syntax.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum AstKind {
    /// A number literal.
    Num(f64),
    /// A variable or parameter name.
    Name(String),
    /// Unary minus.
    Neg(Box<Ast>),
    /// A binary operation.
    Binary(BinOp, Box<Ast>, Box<Ast>),
    /// A function call: name, the name's range, arguments.
    Call(String, (usize, usize), Vec<Ast>),
    /// Member access `e.name`, with the member's range.
    Member(Box<Ast>, String, (usize, usize)),
}

/// Parses a whole expression; trailing tokens are an error.
pub(crate) fn parse(tokens: &[Token]) -> Result<Ast, ExprError> {
    let mut p = Parser { tokens, at: 0 };
    if p.peek().tok == Tok::End {
        return Err(ExprError::new(
            "empty expression: write an acceleration such as `vec3(0.0, -9.81, 0.0)`",
            0,
            1,
        ));
    }
    let ast = p.expr(0, 0)?;
    let t = p.peek();
    match &t.tok {
        Tok::End => Ok(ast),
        Tok::Op(")") => Err(ExprError::new(
            "unmatched `)`: no `(` opens it",
            t.start,
            t.end,
        )),
        _ => Err(ExprError::new(
            format!(
                "expected an operator or the end, found {}",
                describe(&t.tok)
            ),
            t.start,
            t.end,
        )),
    }
}

struct Parser<'a> {
    tokens: &'a [Token],
    at: usize,
}

fn describe(t: &Tok) -> String {
    match t {
        Tok::Num(x) => format!("the number `{x}`"),
        Tok::Name(n) => format!("`{n}`"),
        Tok::Op(o) => format!("`{o}`"),
        Tok::End => "the end of the expression".into(),
    }
}

impl Parser<'_> {
    fn peek(&self) -> &Token {
        &self.tokens[self.at.min(self.tokens.len() - 1)]
    }

    fn next(&mut self) -> Token {
        let t = self.peek().clone();
        if self.at < self.tokens.len() - 1 {
            self.at += 1;
        }
        t
    }

    /// The binary operator ahead, if it binds tighter than `min`.
    fn binary_above(&self, min: u8) -> Option<(BinOp, u8)> {
        match &self.peek().tok {
            Tok::Op(o) => BinOp::of(o).filter(|x| x.1 > min),
            _ => None,
        }
    }

    /// Operators binding tighter than `min` (1 comparison, 2 additive, 3 multiplicative).
    fn expr(&mut self, min: u8, depth: usize) -> Result<Ast, ExprError> {
        let mut lhs = self.unary(depth)?;
        while let Some((op, prec)) = self.binary_above(min) {
            self.next();
            let rhs = self.expr(prec, depth + 1)?;
            if op.is_comparison() && self.binary_above(0).is_some_and(|(b, _)| b.is_comparison()) {
                let t = self.peek();
                return Err(ExprError::new(
                    "comparisons do not chain: compare two values, then use select()",
                    t.start,
                    t.end,
                ));
            }
            lhs = Ast {
                start: lhs.start,
                end: rhs.end,
                kind: AstKind::Binary(op, Box::new(lhs), Box::new(rhs)),
            };
        }
        Ok(lhs)
    }

    fn unary(&mut self, depth: usize) -> Result<Ast, ExprError> {
        if depth > MAX_DEPTH {
            let t = self.peek();
            return Err(ExprError::new(
                format!("nested more than {MAX_DEPTH} levels deep"),
                t.start,
                t.end,
            ));
        }
        if self.peek().tok == Tok::Op("-") {
            let minus = self.next();
            let inner = self.unary(depth + 1)?;
            return Ok(Ast {
                start: minus.start,
                end: inner.end,
                kind: AstKind::Neg(Box::new(inner)),
            });
        }
        let mut e = self.primary(depth)?;
        while self.peek().tok == Tok::Op(".") {
            self.next();
            let t = self.next();
            match t.tok {
                Tok::Name(n) => {
                    e = Ast {
                        start: e.start,
                        end: t.end,
                        kind: AstKind::Member(Box::new(e), n, (t.start, t.end)),
                    }
                }
                other => {
                    return Err(ExprError::new(
                        format!(
                            "expected a component name (x, y or z) after `.`, found {}",
                            describe(&other)
                        ),
                        t.start,
                        t.end,
                    ))
                }
            }
        }
        Ok(e)
    }

    fn primary(&mut self, depth: usize) -> Result<Ast, ExprError> {
        let t = self.next();
        match t.tok {
            Tok::Num(x) => Ok(Ast {
                kind: AstKind::Num(x),
                start: t.start,
                end: t.end,
            }),
            Tok::Name(name) => {
                if self.peek().tok != Tok::Op("(") {
                    return Ok(Ast {
                        kind: AstKind::Name(name),
                        start: t.start,
                        end: t.end,
                    });
                }
                let open = self.next();
                let mut args = Vec::new();
                if self.peek().tok != Tok::Op(")") {
                    loop {
                        args.push(self.expr(0, depth + 1)?);
                        if self.peek().tok == Tok::Op(",") {
                            self.next();
                            continue;
                        }
                        break;
                    }
                }
                let close = self.next();
                if close.tok != Tok::Op(")") {
                    return Err(unclosed(&open, &close, "`)` or `,`"));
                }
                Ok(Ast {
                    kind: AstKind::Call(name, (t.start, t.end), args),
                    start: t.start,
                    end: close.end,
                })
            }
            Tok::Op("(") => {
                let inner = self.expr(0, depth + 1)?;
                let close = self.next();
                if close.tok != Tok::Op(")") {
                    return Err(unclosed(&t, &close, "`)`"));
                }
                Ok(Ast {
                    kind: inner.kind,
                    start: t.start,
                    end: close.end,
                })
            }
            other => Err(ExprError::new(
                format!("expected a value, found {}", describe(&other)),
                t.start,
                t.end,
            )),
        }
    }
}

/// The error for a `(` whose `)` is missing: it points at the `(` (where the mistake is
/// easiest to see) and says what came instead.
fn unclosed(open: &Token, found: &Token, expected: &str) -> ExprError {
    ExprError::new(
        format!(
            "unclosed `(`: expected {expected}, found {}",
            describe(&found.tok)
        ),
        open.start,
        open.end,
    )
}

#[cfg(test)]
mod tests {
    use super::super::lex::tokenize;
    use super::*;

    fn p(s: &str) -> Result<Ast, ExprError> {
        parse(&tokenize(s)?)
    }

    #[test]
    fn precedence_and_ranges() {
        let a = p("1 + 2 * x.y").unwrap();
        let AstKind::Binary(BinOp::Add, _, rhs) = &a.kind else {
            panic!("{a:?}")
        };
        assert!(matches!(rhs.kind, AstKind::Binary(BinOp::Mul, _, _)));
        assert_eq!((rhs.start, rhs.end), (4, 11));
        assert_eq!((a.start, a.end), (0, 11));
    }

    #[test]
    fn errors_point_at_the_offending_token() {
        let e = p("vec3(1, 2").unwrap_err();
        assert_eq!((e.start, e.end), (4, 5), "{}", e.message);
        assert!(p("").unwrap_err().message.contains("empty"));
        let e = p("x)").unwrap_err();
        assert_eq!(e.start, 1);
        let e = p("1 < x < 2").unwrap_err();
        assert!(e.message.contains("chain"), "{}", e.message);
        let deep = "(".repeat(200) + "x" + &")".repeat(200);
        assert!(p(&deep).unwrap_err().message.contains("nested"));
    }
}
