//! A small WGSL writer: indentation-aware lines and blocks, and literal formatting.
//!
//! Code generation calls these methods while walking the IR; nothing is produced by
//! substituting into text templates, so every emitted line comes from an IR decision.

use glam::DVec3;

/// Accumulates WGSL source with consistent indentation.
#[derive(Debug, Default)]
pub struct Writer {
    out: String,
    indent: usize,
}

impl Writer {
    /// An empty writer.
    pub fn new() -> Self {
        Self::default()
    }

    /// Writes one line at the current indentation.
    pub fn line(&mut self, text: impl AsRef<str>) {
        let text = text.as_ref();
        if text.is_empty() {
            self.out.push('\n');
            return;
        }
        for _ in 0..self.indent {
            self.out.push_str("    ");
        }
        self.out.push_str(text);
        self.out.push('\n');
    }

    /// Writes an empty line.
    pub fn blank(&mut self) {
        self.out.push('\n');
    }

    /// Writes `header {`, runs `body` one level deeper, then writes `}`.
    pub fn block(&mut self, header: impl AsRef<str>, body: impl FnOnce(&mut Writer)) {
        let header = header.as_ref();
        if header.is_empty() {
            self.line("{");
        } else {
            self.line(format!("{header} {{"));
        }
        self.indent += 1;
        body(self);
        self.indent -= 1;
        self.line("}");
    }

    /// Writes a `// comment` line.
    pub fn comment(&mut self, text: impl AsRef<str>) {
        self.line(format!("// {}", text.as_ref()));
    }

    /// The source written so far.
    pub fn finish(self) -> String {
        self.out
    }
}

/// Formats an f64 as a WGSL f32 literal: always with a decimal point or exponent, never
/// NaN or Inf (the compiler validates finiteness before code generation; a value beyond
/// f32's range is clamped so the module still validates).
pub(crate) fn f32_lit(x: f64) -> String {
    let x = if x.is_finite() { x } else { 0.0 };
    let v = (x as f32).clamp(-f32::MAX, f32::MAX);
    // `{:?}` prints the shortest text that round-trips the f32, e.g. `0.1`, `1e-7`.
    let s = format!("{v:?}");
    if s.contains('.') || s.contains('e') || s.contains("inf") || s.contains("NaN") {
        s
    } else {
        format!("{s}.0")
    }
}

/// Formats a vector as `vec3<f32>(x, y, z)`.
pub(crate) fn vec3_lit(v: DVec3) -> String {
    format!(
        "vec3<f32>({}, {}, {})",
        f32_lit(v.x),
        f32_lit(v.y),
        f32_lit(v.z)
    )
}

/// Formats a u32 as a WGSL literal (`7u`).
pub(crate) fn u32_lit(x: u32) -> String {
    format!("{x}u")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn literals_are_valid_wgsl_floats() {
        assert_eq!(f32_lit(1.0), "1.0");
        assert_eq!(f32_lit(-9.81), "-9.81");
        assert_eq!(f32_lit(1e-7), "1e-7");
        assert_eq!(f32_lit(f64::NAN), "0.0");
        assert_eq!(f32_lit(1e300), format!("{:?}", f32::MAX));
        assert_eq!(u32_lit(3), "3u");
    }

    #[test]
    fn blocks_indent() {
        let mut w = Writer::new();
        w.block("fn f()", |w| w.line("return;"));
        assert_eq!(w.finish(), "fn f() {\n    return;\n}\n");
    }
}
