//! Forces: each module owns one force's schema, checks, lowering to IR terms, WGSL and f64
//! reference. Adding a force means adding a module here and a variant to [`Force`] and [`Term`].
//!
//! Forces are accelerations `a(x, v, t)`, summed. Schemas are what users write; terms are what
//! the IR keeps after lowering (Gravity and noiseless Wind both lower to a [`constant`] term).

pub mod attractor;
pub mod constant;
pub mod custom;
pub mod drag;
pub mod flock;
pub mod noise;
pub mod turbulence;
pub(crate) mod vector_field;
pub mod vortex;
pub mod wind;

use glam::DVec3;

use serde::de::{self, Deserialize, Deserializer, EnumAccess, VariantAccess};

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::{struct_variant, Vec3};
use crate::base::writer::Writer;

/// A force as written in an effect file.
#[derive(Clone, Debug, PartialEq)]
pub enum Force {
    /// Constant acceleration `a = g`.
    Gravity(Vec3),
    /// Linear drag toward a fluid velocity.
    Drag(drag::Drag),
    /// Constant push plus optional smooth noise.
    Wind(wind::Wind),
    /// The thesis's gravity point.
    Attractor(attractor::Attractor),
    /// The thesis's vortex, with its bugs fixed.
    Vortex(vortex::Vortex),
    /// Flocking: forces between particles (at most one per effect).
    Flock(flock::Flock),
    /// An acceleration written as an expression.
    Custom(custom::Custom),
    /// Divergence-free curl noise.
    Turbulence(turbulence::Turbulence),
    /// An imported vector field (FGA file), trilinear.
    VectorField(vector_field::VectorField),
}

impl Force {
    /// The variant's name as written in effect files.
    pub fn name(&self) -> &'static str {
        match self {
            Force::Gravity(_) => "Gravity",
            Force::Drag(_) => "Drag",
            Force::Wind(_) => "Wind",
            Force::Attractor(_) => "Attractor",
            Force::Vortex(_) => "Vortex",
            Force::Flock(_) => "Flock",
            Force::Custom(_) => "Custom",
            Force::Turbulence(_) => "Turbulence",
            Force::VectorField(_) => "VectorField",
        }
    }

    /// Checks the force's parameters; `path` already names the variant, `scope` holds what
    /// expressions may name besides their variables.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker, scope: custom::Scope) {
        match self {
            Force::Gravity(g) => {
                c.vec3(&path.inner(), *g);
            }
            Force::Drag(f) => f.check(path, c),
            Force::Wind(f) => f.check(path, c),
            Force::Attractor(f) => f.check(path, c),
            Force::Vortex(f) => f.check(path, c),
            Force::Flock(f) => f.check(path, c),
            Force::Custom(f) => f.check(path, c, scope),
            Force::Turbulence(f) => f.check(path, c),
            Force::VectorField(f) => f.check(path, c),
        }
    }

    /// Whether the force changes with time where a baked field holds it (a noisy Wind): a
    /// grid baked once would freeze it.
    pub(crate) fn changes_when_baked(&self) -> bool {
        matches!(self, Force::Wind(w) if w.noise != 0.0)
    }

    /// For a force an effect may have only one of: what to do instead of a second.
    pub(crate) fn at_most_one(&self) -> Option<&'static str> {
        match self {
            Force::Flock(_) => Some("an effect has one flock (merge their strengths into one)"),
            Force::VectorField(_) => Some("an effect samples one (resample them into one file)"),
            _ => None,
        }
    }

    /// The flock a Flock force lowers to (`EffectIr::flock`); None for every other force.
    pub(crate) fn lower_flock(&self, origin: usize) -> Option<flock::FlockIr> {
        match self {
            Force::Flock(flock) => Some(flock.lower(origin)),
            _ => None,
        }
    }

    /// Lowers to IR terms; `origin` is the force's index in the file, `seed` the effect's seed.
    /// A Flock lowers to no term: it couples particles, so it is `EffectIr::flock` instead.
    pub(crate) fn lower(&self, origin: usize, seed: u32, scope: custom::Scope) -> Vec<Term> {
        match self {
            Force::Gravity(g) => vec![Term::Constant(constant::ConstantTerm {
                accel: g.d(),
                origins: vec![origin],
            })],
            Force::Drag(f) => vec![Term::Drag(f.lower(origin))],
            Force::Wind(f) => f.lower(origin, seed),
            Force::Attractor(f) => vec![Term::Attractor(f.lower(origin))],
            Force::Vortex(f) => vec![Term::Vortex(f.lower(origin))],
            Force::Flock(_) => Vec::new(),
            Force::Custom(f) => vec![f.lower(origin, crate::base::rng::seed_mix(seed), scope)],
            Force::Turbulence(f) => vec![Term::Turbulence(f.lower(origin, seed))],
            Force::VectorField(f) => f.lower(origin).map(Term::VectorField).into_iter().collect(),
        }
    }
}

/// Variant names, as written in effect files.
pub const VARIANTS: &[&str] = &[
    "Gravity",
    "Drag",
    "Wind",
    "Attractor",
    "Vortex",
    "Flock",
    "Custom",
    "Turbulence",
    "VectorField",
];

/// The variant names (serde reports unknown ones with the list of expected names).
#[derive(serde::Deserialize)]
#[serde(variant_identifier)]
enum Kind {
    Gravity,
    Drag,
    Wind,
    Attractor,
    Vortex,
    Flock,
    Custom,
    Turbulence,
    VectorField,
}

struct ForceVisitor;

impl<'de> de::Visitor<'de> for ForceVisitor {
    type Value = Force;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(
            "a force: Gravity, Drag, Wind, Attractor, Vortex, Flock, Custom, Turbulence or VectorField",
        )
    }
    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<Force, A::Error> {
        let (kind, variant): (Kind, _) = data.variant()?;
        Ok(match kind {
            Kind::Gravity => Force::Gravity(variant.newtype_variant()?),
            Kind::Drag => Force::Drag(struct_variant(variant, drag::FIELDS)?),
            Kind::Wind => Force::Wind(struct_variant(variant, wind::FIELDS)?),
            Kind::Attractor => Force::Attractor(struct_variant(variant, attractor::FIELDS)?),
            Kind::Vortex => Force::Vortex(struct_variant(variant, vortex::FIELDS)?),
            Kind::Flock => Force::Flock(struct_variant(variant, flock::FIELDS)?),
            Kind::Custom => Force::Custom(struct_variant(variant, custom::FIELDS)?),
            Kind::Turbulence => Force::Turbulence(struct_variant(variant, turbulence::FIELDS)?),
            Kind::VectorField => Force::VectorField(struct_variant(variant, vector_field::FIELDS)?),
        })
    }
}

impl<'de> Deserialize<'de> for Force {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_enum("Force", VARIANTS, ForceVisitor)
    }
}

/// How a term limits the step size, for the stability analysis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stiffness {
    /// No step-size limit from this term.
    None,
    /// Linear damping rate k (1/s): the limit is on k*h.
    Damping(f64),
    /// Oscillation frequency omega (rad/s): the limit is on omega*h.
    Oscillation(f64),
}

/// A pull toward a centre (or an axis) with a soft core, for the core-transit check: a particle
/// that falls in from the edge crosses the core at about `fall_speed`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoreWell {
    /// Speed (m/s) gained falling from the range's edge to the centre, from rest.
    pub fall_speed: f64,
    /// Core radius (m).
    pub core: f64,
}

impl CoreWell {
    /// The well of a pull `strength` · clamp(1 − r/range) · min(r, core)/core, whose depth is
    /// ∫₀^range of it = strength (range/2 − core/2 + core²/(6 range)).
    pub fn of(strength: f64, core: f64, range: f64) -> Self {
        let depth = strength * (0.5 * range - 0.5 * core + core * core / (6.0 * range));
        CoreWell {
            fall_speed: (2.0 * depth.max(0.0)).sqrt(),
            core,
        }
    }
}

/// What a force may read about the particle besides x, v and t (custom expressions read it).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ParticleCtx {
    /// The particle's id (for its random numbers).
    pub id: u32,
    /// Its age (s) at time `t0`.
    pub age0: f64,
    /// The time (s) `age0` was taken at: the age at time t is age0 + (t - t0).
    pub t0: f64,
    /// Its lifetime (s), 0 when it never dies.
    pub life: f64,
    /// Its attributes' values (`features::attributes`) at the step's start, by index.
    pub attrs: crate::expr::eval::Attrs,
}

/// A term's part of the acceleration g − k (v − u) that the Exact integrator solves in closed
/// form ([`ForceTerm::linear`]): `accel` adds to g, `k` to k and `k_fluid` to k u.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Linear {
    /// Constant acceleration (m/s²).
    pub accel: DVec3,
    /// Drag rate (1/s).
    pub k: f64,
    /// The drag rate times the fluid's velocity the drag pulls toward.
    pub k_fluid: DVec3,
}

/// WGSL functions that force terms and expressions share ([`ForceTerm::wgsl_helpers`]): the
/// module writes each set once, in the order of their keys.
#[derive(Clone, Copy, Debug)]
pub struct WgslHelpers {
    /// Names the set: terms that return the same key share one copy.
    pub key: &'static str,
    /// Writes the functions.
    pub emit: fn(&mut Writer),
}

/// The gradient noise's curl (`turb_gradient`, `turb_curl`): Turbulence and the expressions'
/// `curl` and `noise` call it.
pub(crate) const CURL_HELPERS: WgslHelpers = WgslHelpers {
    key: "curl",
    emit: crate::base::gradient_noise::emit_curl_helpers,
};

/// The gradient noise (`grad_noise`) the expressions' `noise` calls, besides the curl's.
pub(crate) const GRADIENT_NOISE_HELPERS: WgslHelpers = WgslHelpers {
    key: "gradient noise",
    emit: crate::base::gradient_noise::emit_noise_helper,
};

/// What every IR force term provides: WGSL, the f64 reference, and facts for the passes.
pub trait ForceTerm {
    /// Indices in the file's `forces` list that this term came from.
    fn origins(&self) -> &[usize];
    /// One line for `--emit ir`.
    fn describe(&self) -> String;
    /// False when the term is zero everywhere (the prune pass drops it).
    fn can_act(&self) -> bool;
    /// Whether the acceleration depends on velocity.
    fn uses_velocity(&self) -> bool {
        false
    }
    /// Whether the acceleration depends on time.
    fn uses_time(&self) -> bool {
        false
    }
    /// Whether the term needs the whole simulation time in kernels rather than time modulo
    /// the noise period.
    fn reads_whole_time(&self) -> bool {
        false
    }
    /// Whether a baked field may hold this term: it depends on position (and time) only, and
    /// is worth a grid (not a constant).
    fn bakeable(&self) -> bool {
        false
    }
    /// Why the Exact integrator cannot integrate this term (after `"forces[i] (Name) "`).
    fn closed_form_blocker(&self) -> String {
        "has no closed form".into()
    }
    /// Whether [`ForceTerm::stiffness`] is an estimate (sampled) rather than derived.
    fn stiffness_is_estimate(&self) -> bool {
        false
    }
    /// The field a stiffness warning points at.
    fn stiffness_field(&self) -> &'static str {
        "strength"
    }
    /// The step-size limit this term imposes.
    fn stiffness(&self) -> Stiffness {
        Stiffness::None
    }
    /// The soft-cored well particles can fall through, if the term has one.
    fn core_well(&self) -> Option<CoreWell> {
        None
    }
    /// The WGSL functions this term's statements call, written once per module however many
    /// terms (or expressions) call them; empty for a term that calls none of its own.
    fn wgsl_helpers(&self) -> Vec<WgslHelpers> {
        Vec::new()
    }
    /// The term as part of the closed form's g − k (v − u); None for a term it cannot hold.
    fn linear(&self) -> Option<Linear> {
        None
    }
    /// The f32 words this term reads on the GPU from the `force_data` binding
    /// (`Role::ForceData`, written once when the effect is made); None for a term that reads
    /// none. One term of an effect at most has data.
    fn gpu_data(&self) -> Option<Vec<f32>> {
        None
    }
    /// WGSL statements that add this term's acceleration to `a`, with `x`, `v` (`vec3<f32>`) and
    /// `t` (f32, seconds mod the noise period) in scope. Locals go in a `{ }` block.
    fn emit_wgsl(&self, w: &mut Writer);
    /// The same acceleration in f64: the CPU reference.
    fn accel(&self, x: DVec3, v: DVec3, t: f64) -> DVec3;
    /// The acceleration of one particle, for terms that read more than x, v and t.
    fn accel_at(&self, x: DVec3, v: DVec3, t: f64, _particle: &ParticleCtx) -> DVec3 {
        self.accel(x, v, t)
    }
}

/// A force term in the IR.
#[derive(Clone, Debug, PartialEq)]
pub enum Term {
    /// Constant acceleration (gravity, noiseless wind; folded into one).
    Constant(constant::ConstantTerm),
    /// Linear drag (merged into one).
    Drag(drag::DragTerm),
    /// Smooth noise acceleration from Wind.
    Noise(noise::NoiseTerm),
    /// Gravity point.
    Attractor(attractor::AttractorTerm),
    /// Vortex.
    Vortex(vortex::VortexTerm),
    /// A custom expression.
    Custom(custom::CustomTerm),
    /// Curl-noise turbulence.
    Turbulence(turbulence::TurbulenceTerm),
    /// An imported vector field.
    VectorField(vector_field::VectorFieldTerm),
}

impl Term {
    /// Learns what the term needs from the lowered emitters (`h` the substep): a custom
    /// term estimates its stiffness over the region they spawn in.
    pub(crate) fn fit_to_emitters(
        &mut self,
        emitters: &[crate::features::emitter::EmitterIr],
        h: f64,
    ) {
        if let Term::Custom(c) = self {
            c.estimate_stiffness(emitters, h);
        }
    }

    /// The term behind the common interface.
    pub fn as_dyn(&self) -> &dyn ForceTerm {
        match self {
            Term::Constant(t) => t,
            Term::Drag(t) => t,
            Term::Noise(t) => t,
            Term::Attractor(t) => t,
            Term::Vortex(t) => t,
            Term::Custom(t) => t,
            Term::Turbulence(t) => t,
            Term::VectorField(t) => t,
        }
    }
}

pub(crate) use crate::base::values::safe_normalize;

/// Constant terms folded into one and drags merged into one, first, so a kernel adds one
/// vector and does one multiply for them; the other terms keep their order after them.
pub(crate) fn fold(terms: Vec<Term>) -> Vec<Term> {
    let mut constant: Option<constant::ConstantTerm> = None;
    let mut drag: Option<drag::DragTerm> = None;
    let mut rest = Vec::new();
    for term in terms {
        match term {
            Term::Constant(c) => {
                constant = Some(match constant {
                    None => c,
                    Some(acc) => {
                        let mut origins = acc.origins;
                        origins.extend(c.origins);
                        constant::ConstantTerm {
                            accel: acc.accel + c.accel,
                            origins,
                        }
                    }
                });
            }
            Term::Drag(d) => {
                drag = Some(match drag {
                    None => d,
                    Some(acc) => acc.merge(&d),
                });
            }
            other => rest.push(other),
        }
    }
    constant
        .map(Term::Constant)
        .into_iter()
        .chain(drag.map(Term::Drag))
        .chain(rest)
        .collect()
}

/// The samples of the effect's vector field, as the `force_data` binding holds them; None
/// without one.
pub fn force_data(terms: &[Term]) -> Option<Vec<f32>> {
    terms.iter().find_map(|t| t.as_dyn().gpu_data())
}

/// Path of the `i`-th force, with its variant named.
pub(crate) fn force_path(i: usize, f: &Force) -> ValuePath {
    ValuePath::root().field("forces").index(i).variant(f.name())
}
