//! Semantic checks on deserialised values, each failure an error at the value's path.

use crate::base::diagnostics::Diagnostic;
use crate::base::path::ValuePath;
use crate::base::values::{Range, Vec3};

/// Collects semantic errors while the schema is walked.
#[derive(Debug, Default)]
pub(crate) struct Checker {
    /// The errors found so far, with display and lookup paths.
    pub errors: Vec<(Diagnostic, String)>,
}

impl Checker {
    /// Records an error at `path`.
    pub(crate) fn error(&mut self, path: &ValuePath, message: impl Into<String>) {
        self.errors.push((
            Diagnostic::error(path.display.clone(), message),
            path.lookup.clone(),
        ));
    }

    /// Records an error at characters `[start, end)` of the string at `path` (an expression's
    /// mistake): the lookup path carries the range as `path@start..end`, which
    /// [`crate::base::locate::SourceMap::find_in_string`] resolves to a line and column.
    pub(crate) fn error_in_string(
        &mut self,
        path: &ValuePath,
        start: usize,
        end: usize,
        message: impl Into<String>,
    ) {
        self.errors.push((
            Diagnostic::error(path.display.clone(), message),
            format!("{}@{start}..{end}", path.lookup),
        ));
    }

    /// `x` must be a finite number; returns whether it is.
    pub(crate) fn finite(&mut self, path: &ValuePath, x: f64) -> bool {
        if x.is_finite() {
            true
        } else {
            self.error(path, format!("must be a finite number, got {x}"));
            false
        }
    }

    /// `x` must be finite and > 0; returns whether it is.
    pub(crate) fn positive(&mut self, path: &ValuePath, x: f64) -> bool {
        let ok = self.finite(path, x) && x > 0.0;
        if x.is_finite() && !ok {
            self.error(path, format!("must be > 0, got {x}"));
        }
        ok
    }

    /// `x` must be finite and >= 0; returns whether it is.
    pub(crate) fn non_negative(&mut self, path: &ValuePath, x: f64) -> bool {
        let ok = self.finite(path, x) && x >= 0.0;
        if x.is_finite() && !ok {
            self.error(path, format!("must be >= 0, got {x}"));
        }
        ok
    }

    /// A core radius must be finite, > 0 and no larger than the force's `range`.
    pub(crate) fn core_radius(&mut self, path: &ValuePath, core: f64, range: f64) {
        if self.finite(path, core) {
            if core <= 0.0 {
                self.error(path, format!("must be > 0, got {core}"));
            } else if range.is_finite() && core > range {
                self.error(path, format!("must be <= range ({range}), got {core}"));
            }
        }
    }

    /// `x` must be finite and in `[lo, hi]`.
    pub(crate) fn within(&mut self, path: &ValuePath, x: f64, lo: f64, hi: f64) {
        if self.finite(path, x) && !(lo..=hi).contains(&x) {
            self.error(path, format!("must be in [{lo}, {hi}], got {x}"));
        }
    }

    /// Every component of `v` must be finite; returns whether they are.
    pub(crate) fn vec3(&mut self, path: &ValuePath, v: Vec3) -> bool {
        let mut ok = true;
        for (i, (name, x)) in [("x", v.0), ("y", v.1), ("z", v.2)].into_iter().enumerate() {
            ok &= self.finite(&path.component(i, name), x);
        }
        ok
    }

    /// `v` must be finite and have a length that can be normalised.
    pub(crate) fn direction(&mut self, path: &ValuePath, v: Vec3) {
        if self.vec3(path, v) && !is_normalizable(v) {
            self.error(
                path,
                format!(
                    "must be a non-zero direction, got ({}, {}, {})",
                    v.0, v.1, v.2
                ),
            );
        }
    }

    /// A `(min, max)` range: both finite and `min <= max`.
    pub(crate) fn range(&mut self, path: &ValuePath, r: Range) -> bool {
        let ok = self.finite(&path.component(0, "min"), r.0)
            & self.finite(&path.component(1, "max"), r.1);
        if ok && r.0 > r.1 {
            self.error(path, format!("min must be <= max, got ({}, {})", r.0, r.1));
            return false;
        }
        ok
    }

    /// Box corners: finite, and `min <= max` on every axis.
    pub(crate) fn box_corners(&mut self, path: &ValuePath, min: Vec3, max: Vec3) {
        let ok = self.vec3(&path.field("min"), min) & self.vec3(&path.field("max"), max);
        if ok && (min.0 > max.0 || min.1 > max.1 || min.2 > max.2) {
            self.error(
                &path.field("min"),
                format!(
                    "min must be <= max on every axis, got min ({}, {}, {}) and max ({}, {}, {})",
                    min.0, min.1, min.2, max.0, max.1, max.2
                ),
            );
        }
    }
}

/// True when `v` is long enough to normalise in f32 without underflow (and all finite).
pub(crate) fn is_normalizable(v: Vec3) -> bool {
    let l2 = v.0 * v.0 + v.1 * v.1 + v.2 * v.2;
    l2.is_finite() && l2 > 1e-20
}
