//! Lifetimes as whole steps, drawn with integer arithmetic so the GPU and the CPU reference
//! agree exactly on which step a particle dies (float comparisons of age against lifetime
//! disagree whenever a lifetime lands within rounding of a step boundary).
//!
//! A particle dies at the end of the first step at which age >= lifetime. Deaths only happen
//! at step ends, so it lives a whole number of steps n: here n is drawn uniformly from
//! [ceil(min / dt), ceil(max / dt)] (at least 1). The kernels store `die_at`, the index of the
//! step whose update kills it: spawn step + n - 1. Age is never stored: the CPU derives it from
//! the id's spawn step, as (steps done - spawn step) * dt in f64, so it never drifts.

/// The integer lifetime draw of one emitter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LifetimeSteps {
    /// Fewest steps a particle lives (>= 1; a starting age's draw may start at 0).
    pub first: u32,
    /// Number of possible step counts (>= 1): n in [first, first + span).
    pub span: u32,
    /// How many high bits of the random word are used, so that the product fits in 32 bits.
    pub bits: u32,
}

/// Marks a particle that never dies.
pub(crate) const NEVER: u32 = u32::MAX;

/// Tolerance for a lifetime that is an exact multiple of dt written in decimal.
const MULTIPLE_EPS: f64 = 1e-9;

impl LifetimeSteps {
    /// The draw for lifetimes uniform in `[min, max]` seconds at step `dt`.
    /// Returns None when the step counts do not fit in 31 bits.
    pub fn new(min: f64, max: f64, dt: f64) -> Option<Self> {
        let lo = (min / dt - MULTIPLE_EPS).ceil().max(1.0);
        Self::between(lo, (max / dt - MULTIPLE_EPS).ceil().max(lo))
    }

    /// The draw of whole step counts from `lo` to `hi` (whole numbers, lo <= hi); None when
    /// they do not fit in 31 bits.
    fn between(lo: f64, hi: f64) -> Option<Self> {
        if hi >= f64::from(1u32 << 31) || hi.is_nan() {
            return None;
        }
        let (first, last) = (lo as u32, hi as u32);
        let span = last - first + 1;
        let span_bits = 32 - span.leading_zeros();
        Some(Self {
            first,
            span,
            bits: (32 - span_bits).min(24),
        })
    }

    /// The draw for starting ages uniform in `[min, max]` seconds at step `dt`, as whole steps
    /// rounded to the nearest (0 allowed). None when they do not fit in 31 bits.
    pub fn ages(min: f64, max: f64, dt: f64) -> Option<Self> {
        let lo = (min / dt).round().max(0.0);
        Self::between(lo, (max / dt).round().max(lo))
    }

    /// Steps lived, from the raw random word `u`: first + floor(top `bits` of u * span / 2^bits).
    pub fn draw(&self, u: u32) -> u32 {
        self.first + (((u >> (32 - self.bits)) * self.span) >> self.bits)
    }

    /// The WGSL expression of [`Self::draw`] for a `u32` named `lu`.
    pub fn wgsl(&self) -> String {
        self.wgsl_of("lu")
    }

    /// The WGSL expression of [`Self::draw`] for the `u32` named `word`.
    pub(crate) fn wgsl_of(&self, word: &str) -> String {
        format!(
            "{}u + ((({word} >> {}u) * {}u) >> {}u)",
            self.first,
            32 - self.bits,
            self.span,
            self.bits
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_counts_cover_the_range_and_never_overflow() {
        let dt = 1.0 / 60.0;
        let l = LifetimeSteps::new(2.5, 3.5, dt).unwrap();
        assert_eq!((l.first, l.first + l.span - 1), (150, 210));
        assert_eq!(l.draw(0), 150);
        assert_eq!(l.draw(u32::MAX), 210);
        // An exact multiple of dt written in decimal is not rounded up a step.
        assert_eq!(LifetimeSteps::new(1.0, 1.0, 0.01).unwrap().first, 100);
        // Shorter than a step: one step.
        assert_eq!(LifetimeSteps::new(1e-6, 1e-6, dt).unwrap().draw(12345), 1);
        // Huge spans still fit: the product never exceeds 32 bits.
        let big = LifetimeSteps::new(1.0, 1e9, 1.0).unwrap();
        assert_eq!(big.draw(0), big.first);
        assert!(big.draw(u32::MAX) < big.first + big.span);
        assert!(u64::from(u32::MAX >> (32 - big.bits)) * u64::from(big.span) < 1 << 32);
        assert!(LifetimeSteps::new(1.0, 1e12, 1e-3).is_none());
    }
}
