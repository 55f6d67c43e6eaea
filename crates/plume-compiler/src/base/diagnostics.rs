//! Diagnostics: errors and warnings with a location, rendered like rustc's.
//!
//! A diagnostic carries a message, an optional value path (`forces[2] (Attractor).range`)
//! and an optional source span. Rendering needs the file name and the source text so it can
//! show the offending line with a caret under the span.

use std::fmt;

/// How serious a diagnostic is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    /// The effect compiles, but something is likely wrong (instability, precision loss).
    Warning,
    /// The effect does not compile.
    Error,
}

impl fmt::Display for Severity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Severity::Warning => f.write_str("warning"),
            Severity::Error => f.write_str("error"),
        }
    }
}

/// A position in the source: 1-based line and column (columns count characters).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct Pos {
    /// 1-based line number.
    pub line: usize,
    /// 1-based column, in characters.
    pub col: usize,
}

/// A source range `[start, end)`; `end` may lie on a later line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Span {
    /// First character of the range.
    pub(crate) start: Pos,
    /// One past the last character of the range.
    pub(crate) end: Pos,
}

/// One error or warning.
#[derive(Clone, Debug, PartialEq)]
pub struct Diagnostic {
    /// Error or warning.
    pub severity: Severity,
    /// The value's path as shown to users, e.g. `forces[2] (Attractor).range`; empty for syntax errors.
    pub path: String,
    /// What is wrong, and where useful what to do about it.
    pub message: String,
    /// Where in the source the problem is, when it can be found.
    pub span: Option<Span>,
}

impl Diagnostic {
    /// An error at a value path (the span is filled in later by the locator).
    pub fn error(path: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            severity: Severity::Error,
            path: path.into(),
            message: message.into(),
            span: None,
        }
    }

    /// A warning at a value path.
    pub fn warning(path: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            severity: Severity::Warning,
            path: path.into(),
            message: message.into(),
            span: None,
        }
    }

    /// The one-line headline: `path: message`, or just the message without a path.
    pub(crate) fn headline(&self) -> String {
        if self.path.is_empty() {
            self.message.clone()
        } else {
            format!("{}: {}", self.path, self.message)
        }
    }

    /// Renders the diagnostic like rustc: `file:line:col: error: ...`, then the source line and a caret.
    pub fn render(&self, file_name: &str, source: &str) -> String {
        let mut out = String::new();
        match self.span {
            Some(span) => {
                out.push_str(&format!(
                    "{}:{}:{}: {}: {}\n",
                    file_name,
                    span.start.line,
                    span.start.col,
                    self.severity,
                    self.headline()
                ));
                if let Some(line_text) = source.lines().nth(span.start.line.saturating_sub(1)) {
                    let number = span.start.line.to_string();
                    let gutter = " ".repeat(number.len());
                    let line_len = line_text.chars().count();
                    // Underline to the end of the span when it stays on this line, else one caret.
                    let width = if span.end.line == span.start.line && span.end.col > span.start.col
                    {
                        span.end.col - span.start.col
                    } else {
                        1
                    };
                    let width = width.min(line_len.saturating_sub(span.start.col - 1).max(1));
                    // Tabs keep their width in the caret line so the caret stays under the value.
                    let pad: String = line_text
                        .chars()
                        .take(span.start.col - 1)
                        .map(|c| if c == '\t' { '\t' } else { ' ' })
                        .collect();
                    out.push_str(&format!("{gutter} |\n"));
                    out.push_str(&format!("{number} | {line_text}\n"));
                    out.push_str(&format!("{gutter} | {pad}{}\n", "^".repeat(width)));
                }
            }
            None => {
                out.push_str(&format!(
                    "{}: {}: {}\n",
                    file_name,
                    self.severity,
                    self.headline()
                ));
            }
        }
        out
    }
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.span {
            Some(s) => write!(
                f,
                "{}:{}: {}: {}",
                s.start.line,
                s.start.col,
                self.severity,
                self.headline()
            ),
            None => write!(f, "{}: {}", self.severity, self.headline()),
        }
    }
}

/// A list of diagnostics: the error type of compilation, and the warnings of a success.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Diagnostics {
    /// In the order they were found.
    pub items: Vec<Diagnostic>,
}

impl Diagnostics {
    /// Adds one diagnostic.
    pub fn push(&mut self, d: Diagnostic) {
        self.items.push(d);
    }

    /// True when there is nothing to report.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// Renders every item, rustc-style, separated by blank lines.
    pub fn render(&self, file_name: &str, source: &str) -> String {
        self.items
            .iter()
            .map(|d| d.render(file_name, source))
            .collect::<Vec<_>>()
            .join("\n")
    }
}

impl fmt::Display for Diagnostics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for d in &self.items {
            writeln!(f, "{d}")?;
        }
        Ok(())
    }
}

impl std::error::Error for Diagnostics {}
