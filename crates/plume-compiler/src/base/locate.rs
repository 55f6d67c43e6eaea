//! Finds where a value path (`forces[2].range`) sits in RON source text.
//!
//! serde and ron give spans only for syntax errors; semantic errors are found after
//! deserialisation and know only the value's path. This module walks the source once with a
//! small structural scanner (it understands just enough RON: identifiers, `(...)`, `[...]`,
//! `name: value`, literals, comments) and records the span of every value by its path. It never
//! fails: on text it does not understand it simply records less.

use std::collections::HashMap;

use crate::base::diagnostics::{Pos, Span};

/// Spans of values in a RON document, keyed by lookup path (`emitters[0].shape.radius`).
#[derive(Debug, Default)]
pub(crate) struct SourceMap {
    spans: HashMap<String, Span>,
}

impl SourceMap {
    /// Scans `source` and records the span of every value it can reach.
    pub(crate) fn build(source: &str) -> Self {
        let tokens = tokenize(source);
        let mut scanner = Scanner {
            tokens: &tokens,
            at: 0,
            map: SourceMap::default(),
        };
        scanner.value(String::new(), 0);
        scanner.map
    }

    /// The span of characters `[start, end)` of the string value at `path` (an expression's
    /// mistake), or the string's own span when the characters cannot be mapped.
    pub(crate) fn find_in_string(
        &self,
        source: &str,
        path: &str,
        start: usize,
        end: usize,
    ) -> Option<Span> {
        let whole = self.find(path)?;
        let Some(exact) = self.spans.get(path) else {
            return Some(whole);
        };
        let positions = string_positions(source, exact.start);
        let at = |k: usize| positions.get(k).copied();
        match (
            at(start),
            at(end.max(start + 1)).or_else(|| positions.last().copied()),
        ) {
            (Some(s), Some(e)) => Some(Span { start: s, end: e }),
            _ => Some(whole),
        }
    }

    /// The span of the value at `path`, or of its nearest recorded ancestor.
    pub(crate) fn find(&self, path: &str) -> Option<Span> {
        let mut p = path.to_string();
        loop {
            if let Some(s) = self.spans.get(&p) {
                return Some(*s);
            }
            // Drop the last segment: `.name` or `[i]`.
            let Some(cut) = p.rfind(['.', '[']) else {
                // A top-level field the file does not write: point at the document itself.
                return self.spans.get("").copied();
            };
            p.truncate(cut);
            if p.is_empty() {
                return self.spans.get("").copied();
            }
        }
    }
}

/// The source position of each character of the string literal starting at `open` (its
/// opening quote), decoded characters counted as the string's value counts them (an escape such
/// as `\n` is one character); one more entry for the closing quote.
fn string_positions(source: &str, open: Pos) -> Vec<Pos> {
    let mut out = Vec::new();
    let Some(line_text) = source.lines().nth(open.line - 1) else {
        return out;
    };
    // Walk from the opening quote through the rest of the source (strings may span lines).
    let line_start: usize = source
        .lines()
        .take(open.line - 1)
        .map(|l| l.len() + 1)
        .sum();
    let col_byte: usize = line_text
        .char_indices()
        .nth(open.col - 1)
        .map_or(line_text.len(), |(b, _)| b);
    let rest = &source[(line_start + col_byte).min(source.len())..];
    let mut chars = rest.chars().peekable();
    if chars.next() != Some('"') {
        return out;
    }
    let (mut line, mut col) = (open.line, open.col + 1);
    let advance = |c: char, line: &mut usize, col: &mut usize| {
        if c == '\n' {
            *line += 1;
            *col = 1;
        } else {
            *col += 1;
        }
    };
    while let Some(c) = chars.next() {
        out.push(Pos { line, col });
        if c == '"' {
            break;
        }
        advance(c, &mut line, &mut col);
        if c == '\\' {
            if let Some(e) = chars.next() {
                advance(e, &mut line, &mut col);
                if e == 'u' {
                    for c in chars.by_ref() {
                        advance(c, &mut line, &mut col);
                        if c == '}' {
                            break;
                        }
                    }
                }
            }
        }
    }
    out
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    Open(char),
    Close(char),
    Colon,
    Comma,
    Literal,
    /// A quoted string, its text between the quotes (a map's key names its entry).
    Str(String),
}

#[derive(Clone, Debug)]
struct Token {
    tok: Tok,
    span: Span,
}

fn tokenize(source: &str) -> Vec<Token> {
    let chars: Vec<char> = source.chars().collect();
    let mut out = Vec::new();
    let (mut i, mut line, mut col) = (0usize, 1usize, 1usize);
    // Advances one character, keeping line and column in step.
    let step = |i: &mut usize, line: &mut usize, col: &mut usize| {
        if chars[*i] == '\n' {
            *line += 1;
            *col = 1;
        } else {
            *col += 1;
        }
        *i += 1;
    };
    while i < chars.len() {
        let c = chars[i];
        let start = Pos { line, col };
        if c.is_whitespace() {
            step(&mut i, &mut line, &mut col);
            continue;
        }
        if c == '/' && chars.get(i + 1) == Some(&'/') {
            while i < chars.len() && chars[i] != '\n' {
                step(&mut i, &mut line, &mut col);
            }
            continue;
        }
        if c == '/' && chars.get(i + 1) == Some(&'*') {
            step(&mut i, &mut line, &mut col);
            step(&mut i, &mut line, &mut col);
            while i < chars.len() && !(chars[i] == '*' && chars.get(i + 1) == Some(&'/')) {
                step(&mut i, &mut line, &mut col);
            }
            for _ in 0..2 {
                if i < chars.len() {
                    step(&mut i, &mut line, &mut col);
                }
            }
            continue;
        }
        let tok = match c {
            '(' | '[' | '{' => {
                step(&mut i, &mut line, &mut col);
                Tok::Open(c)
            }
            ')' | ']' | '}' => {
                step(&mut i, &mut line, &mut col);
                Tok::Close(c)
            }
            ':' => {
                step(&mut i, &mut line, &mut col);
                Tok::Colon
            }
            ',' => {
                step(&mut i, &mut line, &mut col);
                Tok::Comma
            }
            '"' | '\'' => {
                step(&mut i, &mut line, &mut col);
                let first = i;
                while i < chars.len() && chars[i] != c {
                    if chars[i] == '\\' {
                        step(&mut i, &mut line, &mut col);
                    }
                    if i < chars.len() {
                        step(&mut i, &mut line, &mut col);
                    }
                }
                let text: String = chars[first..i.min(chars.len())].iter().collect();
                if i < chars.len() {
                    step(&mut i, &mut line, &mut col);
                }
                Tok::Str(text)
            }
            c if c.is_alphabetic() || c == '_' => {
                let mut name = String::new();
                while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                    name.push(chars[i]);
                    step(&mut i, &mut line, &mut col);
                }
                match name.as_str() {
                    "true" | "false" | "inf" | "NaN" => Tok::Literal,
                    _ => Tok::Ident(name),
                }
            }
            _ => {
                // Numbers and anything else: run to the next delimiter.
                let ends_literal = |i: usize| {
                    i >= chars.len()
                        || chars[i].is_whitespace()
                        || "()[]{}:,".contains(chars[i])
                        || (chars[i] == '/' && matches!(chars.get(i + 1), Some('/' | '*')))
                };
                while !ends_literal(i) {
                    step(&mut i, &mut line, &mut col);
                }
                Tok::Literal
            }
        };
        out.push(Token {
            tok,
            span: Span {
                start,
                end: Pos { line, col },
            },
        });
    }
    out
}

struct Scanner<'a> {
    tokens: &'a [Token],
    at: usize,
    map: SourceMap,
}

impl Scanner<'_> {
    fn peek(&self, k: usize) -> Option<&Tok> {
        self.tokens.get(self.at + k).map(|t| &t.tok)
    }

    fn record(&mut self, path: &str, span: Span) {
        self.map.spans.entry(path.to_string()).or_insert(span);
    }

    /// Scans one value at `path`; returns its span.
    fn value(&mut self, path: String, depth: usize) -> Option<Span> {
        if depth > 64 {
            return None;
        }
        let first = self.tokens.get(self.at)?.clone();
        let span = match first.tok {
            Tok::Literal | Tok::Str(_) => {
                self.at += 1;
                first.span
            }
            Tok::Ident(name) => {
                self.at += 1;
                if self.peek(0) == Some(&Tok::Open('(')) {
                    // `Some(x)` is transparent: the inner value has the same path.
                    let transparent = name == "Some";
                    let end = self.group(&path, depth, transparent);
                    Span {
                        start: first.span.start,
                        end: end.unwrap_or(first.span.end),
                    }
                } else {
                    first.span
                }
            }
            Tok::Open(_) => {
                let end = self.group(&path, depth, false);
                Span {
                    start: first.span.start,
                    end: end.unwrap_or(first.span.end),
                }
            }
            _ => return None,
        };
        self.record(&path, span);
        Some(span)
    }

    /// Scans a bracketed group starting at an open token; returns the end of its close token.
    fn group(&mut self, path: &str, depth: usize, transparent: bool) -> Option<Pos> {
        let open = match self.peek(0)? {
            Tok::Open(c) => *c,
            _ => return None,
        };
        self.at += 1;
        let is_struct =
            matches!(self.peek(0), Some(Tok::Ident(_))) && self.peek(1) == Some(&Tok::Colon);
        let mut index = 0usize;
        loop {
            match self.peek(0)? {
                Tok::Close(_) => {
                    let end = self.tokens[self.at].span.end;
                    self.at += 1;
                    return Some(end);
                }
                Tok::Comma => {
                    self.at += 1;
                }
                // A map's entry, `"key": value`: the key's span names the entry, its value's
                // the entry's fields, unless the value is a string.
                Tok::Str(key) if open == '{' && self.peek(1) == Some(&Tok::Colon) => {
                    let child = format!("{path}.{key}");
                    // A string value names the entry itself (so that a mistake inside it is
                    // found within it); any other value, the key.
                    if !matches!(self.peek(2), Some(Tok::Str(_))) {
                        self.record(&child, self.tokens[self.at].span);
                    }
                    self.at += 2;
                    if self.value(child, depth + 1).is_none() {
                        self.skip_one(depth)?;
                    }
                }
                _ if is_struct && open == '(' => {
                    let Some(Tok::Ident(name)) = self.peek(0).cloned() else {
                        self.skip_one(depth)?;
                        continue;
                    };
                    if self.peek(1) != Some(&Tok::Colon) {
                        self.skip_one(depth)?;
                        continue;
                    }
                    self.at += 2;
                    let child = if path.is_empty() {
                        name
                    } else {
                        format!("{path}.{name}")
                    };
                    if self.value(child, depth + 1).is_none() {
                        self.skip_one(depth)?;
                    }
                }
                _ => {
                    let child = if transparent {
                        path.to_string()
                    } else if open == '[' {
                        format!("{path}[{index}]")
                    } else {
                        format!("{path}.{index}")
                    };
                    index += 1;
                    if self.value(child, depth + 1).is_none() {
                        self.skip_one(depth)?;
                    }
                }
            }
        }
    }

    /// Skips one token (recovering from text the scanner does not understand).
    fn skip_one(&mut self, _depth: usize) -> Option<()> {
        if self.at < self.tokens.len() {
            self.at += 1;
            Some(())
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_nested_fields_and_list_items() {
        let src = "Effect(\n  capacity: 10,\n  forces: [\n    Gravity((0.0, -9.8, 0.0)),\n    Attractor(center: (0.0, 1.0, 0.0), range: -1.0, strength: 2.0),\n  ],\n  lifetime: Some((1.0, 2.0)),\n)";
        let map = SourceMap::build(src);
        let cap = map.find("capacity").unwrap();
        assert_eq!((cap.start.line, cap.start.col), (2, 13));
        let range = map.find("forces[1].range").unwrap();
        assert_eq!((range.start.line, range.start.col), (5, 47));
        assert_eq!(range.end.col - range.start.col, 4);
        let g = map.find("forces[0]").unwrap();
        assert_eq!((g.start.line, g.start.col), (4, 5));
        // Some(...) is transparent.
        let life = map.find("lifetime.0").unwrap();
        assert_eq!((life.start.line, life.start.col), (7, 19));
        // Unknown child falls back to the nearest ancestor.
        assert_eq!(map.find("forces[1].nope"), map.find("forces[1]"));
    }

    #[test]
    fn finds_map_entries_by_key() {
        let src =
            "Effect(\n  params: {\"k\": 1.0},\n  attributes: {\"heat\": (spawn: \"rand(0)\")},\n)";
        let map = SourceMap::build(src);
        let key = map.find("attributes.heat").unwrap();
        assert_eq!((key.start.line, key.start.col), (3, 16));
        let spawn = map.find("attributes.heat.spawn").unwrap();
        assert_eq!((spawn.start.line, spawn.start.col), (3, 32));
        assert_eq!(map.find("params.k").unwrap().start.col, 12);
    }

    #[test]
    fn survives_garbage() {
        let map = SourceMap::build("Effect( ( ] : , // x\n /* y");
        assert!(map.find("anything").is_none() || map.find("").is_some());
    }
}
