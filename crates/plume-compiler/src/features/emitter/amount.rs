//! An emitter's rate and burst, written as a number or as the name of a param
//! (`rate: "flow"`): a param the file gives, which a host compiling with live params changes
//! at run time (`Effect::set_param`), so game code can open and close an emitter. The
//! schedule (`stages/schedule.rs`) holds the value, which the GPU runtime and the reference
//! both set from the same f32.

use std::collections::BTreeMap;

use serde::de::{self, Deserialize, Deserializer, Unexpected, Visitor};

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::expr::Names;

/// A number, or the name of a param that gives it.
///
/// ```
/// use plume_compiler::emitter::Amount;
///
/// let effect = plume_compiler::parse(
///     r#"Effect(name: "valve", capacity: 100, params: {"flow": 40.0},
///        emitters: [Emitter(rate: "flow", shape: Point((0.0, 0.0, 0.0)),
///                           velocity: Constant((0.0, 1.0, 0.0)))])"#,
/// )
/// .unwrap();
/// let rate = &effect.emitters[0].rate;
/// assert_eq!(rate, &Amount::Param("flow".into()));
/// assert_eq!(rate.value(&effect.params), 40.0);
/// // A host writing an emitter in code gives the number itself.
/// let mut emitter = effect.emitters[0].clone();
/// emitter.rate = Amount::Value(250.0);
/// assert_eq!(emitter.rate.value(&effect.params), 250.0);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub enum Amount<T> {
    /// The number itself.
    Value(T),
    /// The param of this name.
    Param(String),
    /// A whole number drawn anew for each burst, uniform from the first to the second
    /// (`burst: (1, 100)`; a burst count only).
    Range(T, T),
}

impl<T: Default> Default for Amount<T> {
    fn default() -> Self {
        Amount::Value(T::default())
    }
}

/// An amount in the IR: its value as the effect compiles, and with live params the index of
/// the param it follows (in `EffectIr::live_params`, name order).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct AmountIr<T> {
    /// The value (the param's, as the file gives it, for a param).
    pub value: T,
    /// The live param it follows, when it is one and params are live.
    pub param: Option<usize>,
}

/// What an amount's number is: a rate (particles a second, at least 0) or a burst (whole
/// particles, a param's value rounded and kept within u32).
pub trait AmountKind: Copy + Default + PartialEq {
    /// This amount as a param of value `x` makes it.
    fn from_param(x: f64) -> Self;
    /// As an f64, for the checks.
    fn as_f64(self) -> f64;
    /// The number as the file writes it, when this kind holds it.
    fn from_written(x: Written) -> Option<Self>;
    /// What the file should write, for messages.
    const EXPECTING: &'static str;
    /// Whether a range of two may stand for it (drawn anew each time).
    const RANGES: bool;
}

/// A number as a file writes it.
#[derive(Clone, Copy, Debug)]
pub enum Written {
    /// A whole number, not negative.
    Unsigned(u64),
    /// A whole number.
    Signed(i64),
    /// A number with a point or an exponent.
    Float(f64),
}

impl AmountKind for f64 {
    fn from_param(x: f64) -> Self {
        x.max(0.0)
    }
    fn as_f64(self) -> f64 {
        self
    }
    fn from_written(x: Written) -> Option<Self> {
        Some(match x {
            Written::Unsigned(u) => u as f64,
            Written::Signed(i) => i as f64,
            Written::Float(f) => f,
        })
    }
    const EXPECTING: &'static str = "a number, or the name of a param in quotes";
    const RANGES: bool = false;
}

impl AmountKind for u32 {
    fn from_param(x: f64) -> Self {
        x.max(0.0).round().min(f64::from(u32::MAX)) as u32
    }
    fn as_f64(self) -> f64 {
        f64::from(self)
    }
    fn from_written(x: Written) -> Option<Self> {
        match x {
            Written::Unsigned(u) => u32::try_from(u).ok(),
            Written::Signed(i) => u32::try_from(i).ok(),
            Written::Float(_) => None,
        }
    }
    const EXPECTING: &'static str = "a whole number from 0 to 4294967295, a range of two such `(lo, hi)` drawn anew for each burst, or the name of a param in quotes";
    const RANGES: bool = true;
}

struct AmountVisitor<T>(std::marker::PhantomData<T>);

impl<T: AmountKind> AmountVisitor<T> {
    fn number<E: de::Error>(&self, x: Written, unexpected: Unexpected) -> Result<Amount<T>, E> {
        T::from_written(x)
            .map(Amount::Value)
            .ok_or_else(|| E::invalid_value(unexpected, self))
    }
}

impl<'de, T: AmountKind> Visitor<'de> for AmountVisitor<T> {
    type Value = Amount<T>;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(T::EXPECTING)
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Self::Value, E> {
        self.number(Written::Unsigned(v), Unexpected::Unsigned(v))
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Self::Value, E> {
        self.number(Written::Signed(v), Unexpected::Signed(v))
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Self::Value, E> {
        self.number(Written::Float(v), Unexpected::Float(v))
    }

    fn visit_str<E: de::Error>(self, v: &str) -> Result<Self::Value, E> {
        Ok(Amount::Param(v.to_string()))
    }

    fn visit_seq<A: de::SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        if !T::RANGES {
            return Err(de::Error::invalid_type(Unexpected::Seq, &self));
        }
        let mut next = |i| -> Result<T, A::Error> {
            let x: u64 = seq
                .next_element()?
                .ok_or_else(|| de::Error::invalid_length(i, &self))?;
            T::from_written(Written::Unsigned(x))
                .ok_or_else(|| de::Error::invalid_value(Unexpected::Unsigned(x), &self))
        };
        let (lo, hi) = (next(0)?, next(1)?);
        Ok(Amount::Range(lo, hi))
    }
}

impl<'de, T: AmountKind> Deserialize<'de> for Amount<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(AmountVisitor(std::marker::PhantomData))
    }
}

impl<T: AmountKind> Amount<T> {
    /// The value as the effect compiles (a param's as the file gives it; 0 for a param the
    /// file lacks, which `Amount::check` refuses).
    pub fn value(&self, params: &BTreeMap<String, f64>) -> T {
        match self {
            Amount::Value(v) => *v,
            Amount::Param(name) => params.get(name).map_or(T::default(), |&x| T::from_param(x)),
            // Estimates read a drawn count's mean.
            Amount::Range(lo, hi) => T::from_param(0.5 * (lo.as_f64() + hi.as_f64())),
        }
    }

    /// Records in `c` a negative number or a param the file does not give, at `path`.
    pub(crate) fn check(&self, c: &mut Checker, path: &ValuePath, names: Names) {
        match self {
            Amount::Value(v) => {
                c.non_negative(path, v.as_f64());
            }
            Amount::Param(name) if !names.params.contains_key(name) => {
                let known: Vec<&str> = names.params.keys().map(String::as_str).collect();
                c.error(
                    path,
                    match known.is_empty() {
                        true => format!("reads the param `{name}`, but the file has no params"),
                        false => format!(
                            "reads the param `{name}`, which the file does not give; its params are {}",
                            known.join(", ")
                        ),
                    },
                );
            }
            Amount::Param(_) => {}
            Amount::Range(lo, hi) => {
                if lo.as_f64() > hi.as_f64() {
                    c.error(
                        path,
                        format!(
                            "a range must be (lo, hi) with lo <= hi, got ({}, {})",
                            lo.as_f64(),
                            hi.as_f64()
                        ),
                    );
                }
            }
        }
    }

    /// The lowered amount (after [`Amount::check`] passed): with live params, a param's value
    /// is the f32 the host's would be and its index is kept.
    pub(crate) fn lower(&self, names: Names) -> AmountIr<T> {
        match self {
            Amount::Value(v) => AmountIr {
                value: *v,
                param: None,
            },
            Amount::Param(name) if names.live => AmountIr {
                value: T::from_param(f64::from(names.params[name] as f32)),
                param: names.params.keys().position(|k| k == name),
            },
            Amount::Param(_) => AmountIr {
                value: self.value(names.params),
                param: None,
            },
            // The draw's range is the emitter's (`EmitterIr::burst_range`); the value its low end.
            Amount::Range(lo, _) => AmountIr {
                value: *lo,
                param: None,
            },
        }
    }
}
