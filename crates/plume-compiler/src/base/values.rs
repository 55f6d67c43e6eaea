//! Value types shared by every part of the effect file and the IR: vectors, ranges, colour and
//! size stops, the integrator and state settings, and piecewise-linear gradients. Plain data
//! with serde's derive; they import nothing of the crate, so every layer can use them.

use glam::DVec3;
use serde::{Deserialize, Deserializer};

/// Reads an optional number written plainly (`core: 1.0`, not `core: Some(1.0)`): for
/// `#[serde(default, deserialize_with = "plain_some")]`, a missing field being `None`.
pub(crate) fn plain_some<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    f64::deserialize(d).map(Some)
}

/// A 3-vector written `(x, y, z)`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub struct Vec3(pub f64, pub f64, pub f64);

impl Vec3 {
    /// As a glam f64 vector.
    pub fn d(self) -> DVec3 {
        DVec3::new(self.0, self.1, self.2)
    }
}

/// A `(min, max)` interval; values are drawn uniformly from it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
pub struct Range(pub f64, pub f64);

/// Three counts written `(nx, ny, nz)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
pub struct Counts(pub u32, pub u32, pub u32);

/// An RGBA colour written `(r, g, b, a)`, each in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub struct Rgba(pub f64, pub f64, pub f64, pub f64);

/// A colour at a fraction of a particle's life, written `(t, (r, g, b, a))`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub(crate) struct ColorStop(pub f64, pub Rgba);

/// A sprite diameter in metres at a fraction of a particle's life, written `(t, size)`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub(crate) struct SizeStop(pub f64, pub f64);

/// The integration scheme.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
pub enum Integrator {
    /// Explicit (forward) Euler: first order, unstable for oscillation.
    Euler,
    /// Symplectic Euler: first order, bounded energy.
    SemiImplicitEuler,
    /// Latta's position Verlet (displacement form): second order.
    Verlet,
    /// Midpoint RK2: second order.
    Midpoint,
    /// Classic RK4: fourth order.
    Rk4,
    /// The closed-form solution (gravity, drag, noiseless wind only).
    Exact,
    /// Let the compiler choose: Exact where allowed, else SemiImplicitEuler.
    #[default]
    Auto,
}

impl Integrator {
    /// Every concrete integrator (not Auto), in order of increasing cost.
    pub const CONCRETE: [Integrator; 6] = [
        Integrator::Euler,
        Integrator::SemiImplicitEuler,
        Integrator::Verlet,
        Integrator::Midpoint,
        Integrator::Rk4,
        Integrator::Exact,
    ];

    /// The name as written in effect files.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Euler => "Euler",
            Integrator::SemiImplicitEuler => "SemiImplicitEuler",
            Integrator::Verlet => "Verlet",
            Integrator::Midpoint => "Midpoint",
            Integrator::Rk4 => "Rk4",
            Integrator::Exact => "Exact",
            Integrator::Auto => "Auto",
        }
    }

    /// Parses a name as written in effect files (case-insensitive, for the command line).
    pub fn from_name(s: &str) -> Option<Self> {
        [Integrator::Auto]
            .into_iter()
            .chain(Self::CONCRETE)
            .find(|i| i.name().eq_ignore_ascii_case(s))
    }
}

/// Whether particles keep state between steps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum State {
    /// Stateless wherever it is exact (the Exact integrator, no kills, no sort, no drops),
    /// else stateful.
    #[default]
    Auto,
    /// Always keep position and velocity per particle (to compare against the stateless
    /// kernel, or to sort by draw order).
    Stateful,
    /// Require the stateless kernel: an error naming the cause where it cannot be used.
    Stateless,
}

impl State {
    /// The name as written in effect files.
    pub fn name(self) -> &'static str {
        match self {
            State::Auto => "Auto",
            State::Stateful => "Stateful",
            State::Stateless => "Stateless",
        }
    }

    /// Parses a name as written in effect files (case-insensitive, for the command line).
    pub fn from_name(s: &str) -> Option<Self> {
        [State::Auto, State::Stateful, State::Stateless]
            .into_iter()
            .find(|i| i.name().eq_ignore_ascii_case(s))
    }
}

/// [`interpolate`] of scalar stops.
pub(crate) fn scalar_at(stops: &[(f64, f64)], t: f64) -> f64 {
    let stops: Vec<(f64, [f64; 1])> = stops.iter().map(|&(t, s)| (t, [s])).collect();
    interpolate(&stops, t)[0]
}

/// Piecewise-linear interpolation through stops (t increasing), constant beyond the ends.
pub(crate) fn interpolate<const N: usize>(stops: &[(f64, [f64; N])], t: f64) -> [f64; N] {
    let Some(first) = stops.first() else {
        return [0.0; N];
    };
    if t <= first.0 {
        return first.1;
    }
    for w in stops.windows(2) {
        let ((t0, a), (t1, b)) = (w[0], w[1]);
        if t <= t1 {
            let f = if t1 > t0 { (t - t0) / (t1 - t0) } else { 1.0 };
            return std::array::from_fn(|i| a[i] + (b[i] - a[i]) * f);
        }
    }
    stops[stops.len() - 1].1
}

pub(crate) fn default_colors() -> Vec<ColorStop> {
    vec![
        ColorStop(0.0, Rgba(1.0, 1.0, 1.0, 1.0)),
        ColorStop(1.0, Rgba(1.0, 1.0, 1.0, 0.0)),
    ]
}

/// `v / |v|`, or zero when `v` is too short to normalise (mirrors the WGSL guard).
pub(crate) fn safe_normalize(v: DVec3) -> DVec3 {
    let l2 = v.length_squared();
    if l2 > 1e-20 {
        v / l2.sqrt()
    } else {
        DVec3::ZERO
    }
}

/// `(0, 0, 0)`: the serde default of a placement's offset and rotation.
pub(crate) fn origin() -> Vec3 {
    Vec3(0.0, 0.0, 0.0)
}

/// `1.0`: the serde default of a placement's scale.
pub(crate) fn unit_scale() -> f64 {
    1.0
}

/// Reads the variant `Name(field: value, ...)` of an enum into a struct of its own, `T`, whose
/// fields are `fields`: how forces and colliders keep each variant's schema in the variant's
/// own module (serde's derive reads only struct variants written inside the enum).
pub(crate) fn struct_variant<'de, A, T>(
    variant: A,
    fields: &'static [&'static str],
) -> Result<T, A::Error>
where
    A: serde::de::VariantAccess<'de>,
    T: Deserialize<'de>,
{
    variant.struct_variant(fields, StructVariant(std::marker::PhantomData))
}

/// The visitor of [`struct_variant`]: the variant's named fields handed to `T`'s own
/// `Deserialize`.
struct StructVariant<T>(std::marker::PhantomData<T>);

impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for StructVariant<T> {
    type Value = T;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("named fields")
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<T, A::Error> {
        T::deserialize(serde::de::value::MapAccessDeserializer::new(map))
    }
}
