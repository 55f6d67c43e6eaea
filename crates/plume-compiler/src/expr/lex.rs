//! The expression lexer: numbers, names and operators, each with its character range in the
//! string (the diagnostics point at it).

use super::ExprError;

/// One token of an expression.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Tok {
    /// A number literal, as written (`2`, `0.5`, `1e-3`).
    Num(f64),
    /// A variable, parameter or function name.
    Name(String),
    /// An operator or punctuation: `+ - * / < <= > >= == != ( ) , .`.
    Op(&'static str),
    /// The end of the string.
    End,
}

/// A token and the characters `[start, end)` it covers.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Token {
    /// What it is.
    pub(crate) tok: Tok,
    /// First character (0-based, in characters).
    pub start: usize,
    /// One past the last character.
    pub end: usize,
}

const OPERATORS: &[&str] = &[
    "<=", ">=", "==", "!=", "+", "-", "*", "/", "<", ">", "(", ")", ",", ".",
];

/// Splits `text` into tokens, ending with [`Tok::End`].
pub(crate) fn tokenize(text: &str) -> Result<Vec<Token>, ExprError> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_whitespace() {
            i += 1;
            continue;
        }
        let start = i;
        let starts_number =
            c.is_ascii_digit() || (c == '.' && chars.get(i + 1).is_some_and(char::is_ascii_digit));
        if starts_number {
            i = number_end(&chars, i);
            let literal: String = chars[start..i].iter().collect();
            let value: f64 = literal
                .parse()
                .map_err(|_| ExprError::new(format!("malformed number `{literal}`"), start, i))?;
            out.push(Token {
                tok: Tok::Num(value),
                start,
                end: i,
            });
            continue;
        }
        if c.is_alphabetic() || c == '_' {
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push(Token {
                tok: Tok::Name(chars[start..i].iter().collect()),
                start,
                end: i,
            });
            continue;
        }
        let op = OPERATORS.iter().find(|op| {
            op.chars()
                .enumerate()
                .all(|(k, oc)| chars.get(i + k) == Some(&oc))
        });
        match op {
            Some(op) => {
                i += op.chars().count();
                out.push(Token {
                    tok: Tok::Op(op),
                    start,
                    end: i,
                });
            }
            None => {
                return Err(ExprError::new(
                    format!("unexpected character `{c}`"),
                    start,
                    start + 1,
                ))
            }
        }
    }
    out.push(Token {
        tok: Tok::End,
        start: chars.len(),
        end: chars.len() + 1,
    });
    Ok(out)
}

/// The end of the number starting at `i`: digits, an optional fraction, an optional exponent.
/// A `.` followed by a letter is not part of it (`2.x` is `2` then `.x`, a type error later).
fn number_end(chars: &[char], mut i: usize) -> usize {
    let digits = |i: &mut usize| {
        while *i < chars.len() && chars[*i].is_ascii_digit() {
            *i += 1;
        }
    };
    digits(&mut i);
    if chars.get(i) == Some(&'.') && !chars.get(i + 1).is_some_and(|c| c.is_alphabetic()) {
        i += 1;
        digits(&mut i);
    }
    if matches!(chars.get(i), Some('e' | 'E')) {
        let mut j = i + 1;
        if matches!(chars.get(j), Some('+' | '-')) {
            j += 1;
        }
        if chars.get(j).is_some_and(char::is_ascii_digit) {
            i = j;
            digits(&mut i);
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toks(s: &str) -> Vec<Tok> {
        tokenize(s).unwrap().into_iter().map(|t| t.tok).collect()
    }

    #[test]
    fn numbers_names_and_operators() {
        assert_eq!(
            toks("-2.5e-1*v.x<=.5"),
            vec![
                Tok::Op("-"),
                Tok::Num(-0.25 * -1.0),
                Tok::Op("*"),
                Tok::Name("v".into()),
                Tok::Op("."),
                Tok::Name("x".into()),
                Tok::Op("<="),
                Tok::Num(0.5),
                Tok::End
            ]
        );
        assert_eq!(
            toks("2.x"),
            vec![Tok::Num(2.0), Tok::Op("."), Tok::Name("x".into()), Tok::End]
        );
    }

    #[test]
    fn bad_character_is_located() {
        let e = tokenize("x + $").unwrap_err();
        assert_eq!((e.start, e.end), (4, 5));
    }
}
