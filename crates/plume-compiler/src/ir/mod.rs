//! The typed IR: an effect after checking, with vectors in f64, directions normalised, spawn
//! bases precomputed and forces lowered to terms. Passes rewrite it; the WGSL writer and the
//! CPU reference both read it.

use glam::DVec3;

use crate::features::forces::Term;
mod display;
pub mod stateless;

use crate::base::values::{interpolate, scalar_at, Integrator, State};
pub(crate) use crate::features::emitter::{EmitterIr, ShapeIr};
use crate::features::looks::glow::Glow;
use crate::features::looks::tint::TintSource;
use crate::features::looks::Blend;

/// An effect in the IR.
#[derive(Clone, Debug, PartialEq)]
pub struct EffectIr {
    /// The effect's name.
    pub name: String,
    /// Most live particles at once.
    pub capacity: u32,
    /// The file's seed.
    pub seed: u32,
    /// `rng::seed_mix(seed)`, baked into the kernels.
    pub seed_mix: u32,
    /// Seconds per step.
    pub dt: f64,
    /// Substeps per step.
    pub substeps: u32,
    /// Particle sources, in id order.
    pub emitters: Vec<EmitterIr>,
    /// Force terms (after the passes: folded, merged, pruned).
    pub terms: Vec<Term>,
    /// The baked force field, when the effect bakes one.
    pub field: Option<crate::features::field::FieldIr>,
    /// Flocking, when the effect has a Flock force.
    pub flock: Option<crate::features::forces::flock::FlockIr>,
    /// The attributes its particles carry (`features::attributes`), kept or not: which are
    /// kept is [`EffectIr::kept_attributes`].
    pub attributes: crate::features::attributes::AttributesIr,
    /// Speed limit after every velocity update.
    pub max_speed: Option<f64>,
    /// The integrator; concrete (never Auto) after the integrator pass.
    pub integrator: Integrator,
    /// Why this integrator: the file chose it, or what Auto decided and why.
    pub integrator_reason: String,
    /// The accuracy budget and what was chosen to meet it (`features::accuracy`).
    pub accuracy: Option<crate::features::accuracy::AccuracyIr>,
    /// Colliders, in file order.
    pub colliders: Vec<crate::features::colliders::ColliderIr>,
    /// Meshes drawn and not simulated (the file's `scene`; the first group's only).
    pub(crate) scene: Vec<crate::features::scene::SceneMeshIr>,
    /// The lights the file names (the default ones when it names none): what a lit look is
    /// drawn with unless a host passes its own.
    pub lights: crate::features::lights::Lights,
    /// Whether the file names its `lights` (else `lights` are the default ones): then they
    /// light the scene's meshes in `plume render` even when the look is unlit.
    pub lights_named: bool,
    /// Kill volumes.
    pub(crate) kills: Vec<KillIr>,
    /// Whether a depth sort is requested.
    pub sort: bool,
    /// The state the file asks for (Auto, Stateful or Stateless).
    pub state: State,
    /// The stateless plan, when particles are computed from (id, age) with no state kept.
    pub stateless: Option<stateless::StatelessIr>,
    /// Why the effect is stateless or stateful (what the state pass decided).
    pub state_reason: String,
    /// Whether a transform set at run time places its emitters (`features::placement`).
    pub placed: bool,
    /// Whether the step parameters carry bursts fired from code (`features::bursts`).
    pub bursts: bool,
    /// With `CompileOptions::live_params`: every param's name and value in name order, as the
    /// step parameters carry them (read by custom forces at run time); empty otherwise.
    pub live_params: Vec<(String, f64)>,
    /// The camera.
    pub camera: CameraIr,
    /// The author's box for every live particle, in the effect's space, for a host's culling:
    /// (min, max).
    pub bounds: Option<(DVec3, DVec3)>,
    /// How particles look when rendered.
    pub render: RenderIr,
    /// The events this group fires (empty outside an effect with groups).
    pub events: Vec<crate::features::events::EventIr>,
    /// The events this group is fed by; each one's spawn rule is one of `emitters`.
    pub event_inputs: Vec<crate::features::events::EventInputIr>,
}

/// The render section in the IR, with gradients ready to evaluate.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderIr {
    /// Colour stops (t, rgba), t increasing.
    pub color: Vec<(f64, [f64; 4])>,
    /// Size stops (t, diameter in m), t increasing.
    pub size: Vec<(f64, f64)>,
    /// Height stops (t, m), when the sprite's height has a curve of its own (`size` is then
    /// its width).
    pub size_y: Option<Vec<(f64, f64)>>,
    /// Alpha stops (t, alpha), when opacity has a curve of its own.
    pub alpha: Option<Vec<(f64, f64)>>,
    /// Blending.
    pub blend: Blend,
    /// Background colour.
    pub background: DVec3,
    /// Which way sprites face.
    pub orient: crate::features::looks::orient::OrientIr,
    /// What the size stops measure (metres, or fractions of the image's height).
    pub size_in: crate::features::looks::screen_size::SizeIn,
    /// The sprite texture, loaded; None draws the soft round dot.
    pub texture: Option<crate::features::looks::texture::TextureIr>,
    /// Each sprite's turn in its plane, when the effect asks for one.
    pub rotation: Option<crate::features::looks::rotation::RotationIr>,
    /// The soft-particle fade distance (m), used where a host's depth buffer is bound.
    pub soft: Option<f64>,
    /// Bloom in `plume render`'s images.
    pub glow: Option<Glow>,
    /// Ribbons through each particle's recent positions, when the effect asks for them.
    pub trail: Option<crate::features::looks::trail::TrailIr>,
    /// The colours particles pick their tint from (`tint.rs`).
    pub palette: Option<Vec<DVec3>>,
    /// What each particle's colour and size are multiplied by (`by_expression.rs`).
    pub by: crate::features::looks::by_expression::LookBy,
    /// Shading by the lights, when the sprites are lit (`lit.rs`).
    pub lit: Option<crate::features::looks::lit::Lit>,
    /// A lit look's maps (its normal map, or its six-way lightmaps), loaded: laid out as
    /// `texture`, whose frames they follow.
    pub lit_maps: Vec<crate::features::looks::texture::TextureIr>,
    /// The light the brightest particles give off, when they do (`particle_light.rs`).
    pub light: Option<crate::features::looks::particle_light::ParticleLight>,
    /// Ribbons joining the particles, drawn instead of sprites (`ribbon.rs`).
    pub ribbon: Option<crate::features::looks::ribbon::Ribbon>,
    /// The mesh each particle is drawn as, instead of a sprite (`particle_mesh.rs`).
    pub mesh: Option<crate::features::looks::particle_mesh::MeshIr>,
}

impl RenderIr {
    /// The colour at life fraction `t` (its alpha from `alpha` when there is one).
    pub fn color_at(&self, t: f64) -> [f64; 4] {
        let mut c = interpolate(&self.color, t);
        if let Some(alpha) = &self.alpha {
            c[3] = scalar_at(alpha, t);
        }
        c
    }

    /// The sprite diameter (m) at life fraction `t`: its width when it has a height curve.
    pub fn size_at(&self, t: f64) -> f64 {
        scalar_at(&self.size, t)
    }

    /// The sprite's height (m) at life fraction `t`: `size_y`'s, else the size.
    pub fn height_at(&self, t: f64) -> f64 {
        scalar_at(self.size_y.as_ref().unwrap_or(&self.size), t)
    }

    /// Whether the quad's half axes are computed (oriented or rotated) rather than the upright
    /// camera-facing square.
    pub(crate) fn turns_quad(&self) -> bool {
        self.orient != crate::features::looks::orient::OrientIr::Camera
            || self.rotation.is_some()
            || self.size_y.is_some()
    }

    /// Whether colour or size change over a particle's life (some stop differs from the first);
    /// if not, the draw needs no life fraction at all.
    pub(crate) fn varies_over_life(&self) -> bool {
        let colour = self.color.iter().any(|(_, c)| *c != self.color[0].1);
        let varies = |stops: &[(f64, f64)]| stops.iter().any(|(_, s)| *s != stops[0].1);
        let size = varies(&self.size);
        let height = self.size_y.as_deref().is_some_and(varies);
        let alpha = self.alpha.as_deref().is_some_and(varies);
        colour || size || height || alpha
    }
}

impl EffectIr {
    /// What the group's tint depends on ([`crate::features::looks::tint`]).
    pub fn tint(&self) -> TintSource<'_> {
        TintSource {
            palette: self.render.palette.as_deref(),
            seed_mix: self.seed_mix,
            stored: self.stores_tint(),
        }
    }

    /// Whether the group's particles store their tint: a stateful group fed by an event that
    /// passes the parent's colour on (the GPU cannot derive it from the child's id).
    pub(crate) fn stores_tint(&self) -> bool {
        self.stateless.is_none() && self.event_inputs.iter().any(|e| e.inherit_color)
    }

    /// Integration step: `dt / substeps`.
    pub fn h(&self) -> f64 {
        self.dt / f64::from(self.substeps)
    }

    /// True when any emitter gives its particles a lifetime.
    pub(crate) fn has_lifetimes(&self) -> bool {
        self.emitters.iter().any(|e| e.lifetime.is_some())
    }

    /// About how many particles the emitters keep alive at once: per emitter its burst (the
    /// largest of a drawn range) plus its steady rate (a burst repeating for ever counts as
    /// burst / every) times its longest lifetime; the capacity where that is more, where a
    /// particle may live for ever, or where events feed the group. An estimate for a host
    /// that shares a particle budget among effects, not a bound.
    pub fn expected_alive(&self) -> u64 {
        if !self.event_inputs.is_empty() {
            return u64::from(self.capacity);
        }
        let alive: f64 = self
            .emitters
            .iter()
            .map(|e| {
                let burst = f64::from(e.burst_range.map_or(e.burst, |r| r.1));
                let repeating = match (e.timing.every, e.timing.cycles, e.timing.end_step) {
                    (Some(every), None, None) if every > 0.0 => burst / every,
                    _ => 0.0,
                };
                let rate = e.rate + repeating;
                match e.lifetime {
                    Some((_, longest)) => burst + rate * longest,
                    None if rate > 0.0 => f64::INFINITY,
                    None => burst,
                }
            })
            .sum();
        alive.min(f64::from(self.capacity)) as u64
    }

    /// True when an emitter gives its particles a random starting age (`Emitter::age`): their
    /// spawn step is then stored, as the step their age counts from.
    pub(crate) fn has_start_ages(&self) -> bool {
        self.emitters.iter().any(|e| e.age_steps.is_some())
    }

    /// The attributes kept (a bit set of their indices): those that custom forces or the
    /// draw read, and what their changes read in turn. An effect that keeps any is stateful (the
    /// state pass: `stages::passes::stateless`).
    pub fn kept_attributes(&self) -> u64 {
        let read = self
            .custom_terms()
            .fold(self.render.by.attrs_read(), |set, c| {
                set | c.expr.attrs_read()
            });
        let moved = crate::features::inherit::kept(&self.events, &self.event_inputs);
        self.attributes.kept(read | moved)
    }

    /// Whether an expression of the compute module (a custom force, a kept attribute, a spawn
    /// expression) reads the gradient noise through `op` (`noise` or `curl`).
    pub(crate) fn compute_uses(&self, op: crate::expr::typed::Op1) -> bool {
        self.custom_terms().any(|c| c.expr.uses(op))
            || self.attributes.uses(self.kept_attributes(), op)
            || self.emitters.iter().any(|e| e.uses(op))
    }

    /// The attributes custom forces read (a bit set): their context holds them.
    pub(crate) fn attributes_forces_read(&self) -> u64 {
        self.custom_terms()
            .fold(0, |set, c| set | c.expr.attrs_read())
    }

    /// Sets live param `index` to `value` in every custom term (the reference's twin of the
    /// host changing it on the GPU; the value is the f32 the GPU reads).
    pub(crate) fn set_live_param(&mut self, index: usize, value: f32) {
        if let Some(p) = self.live_params.get_mut(index) {
            p.1 = f64::from(value);
        }
        for t in &mut self.terms {
            if let crate::features::forces::Term::Custom(c) = t {
                c.expr.set_param(index as u32, f64::from(value));
            }
        }
        for e in &mut self.emitters {
            e.set_param(index as u32, f64::from(value));
        }
        self.attributes.set_param(index as u32, f64::from(value));
    }

    /// The custom expression terms.
    pub fn custom_terms(
        &self,
    ) -> impl Iterator<Item = &crate::features::forces::custom::CustomTerm> {
        self.terms.iter().filter_map(|t| match t {
            crate::features::forces::Term::Custom(c) => Some(c),
            _ => None,
        })
    }

    /// The normal speed below which a contact does not bounce: twice what the effect's constant
    /// acceleration adds in one substep, so a particle resting on a collider stays at rest.
    pub(crate) fn rest_speed(&self) -> f64 {
        let g: glam::DVec3 = self
            .terms
            .iter()
            .filter_map(|t| t.as_dyn().linear())
            .map(|linear| linear.accel)
            .sum();
        2.0 * g.length() * self.h()
    }

    /// The triangles of every mesh the effect names (its mesh colliders', then its mesh
    /// emitters', then its scene's), placed in the world: the scene a preview draws around the particles.
    pub fn scene_triangles(&self) -> Vec<[glam::DVec3; 3]> {
        let mut out = Vec::new();
        for c in &self.colliders {
            if let crate::features::colliders::Surface::Mesh(m) = &c.surface {
                out.extend(m.world_triangles());
            }
        }
        for e in &self.emitters {
            if let ShapeIr::Mesh(m) = &e.shape {
                out.extend(m.world_triangles());
            }
        }
        for m in &self.scene {
            out.extend(m.world_triangles());
        }
        out
    }

    /// Whether the effect collides with the view's depth image (a `SceneDepth` collider): its
    /// kernels then read the `scene_depth` and `scene_camera` bindings, which the host fills.
    pub fn collides_with_scene_depth(&self) -> bool {
        self.colliders.iter().any(|c| {
            matches!(
                c.surface,
                crate::features::colliders::Surface::SceneDepth(_)
            )
        })
    }

    /// Gives every `SceneDepth` collider the image it collides with (the reference's copy of
    /// what the host gives the GPU).
    pub fn set_scene_depth(
        &mut self,
        image: &std::sync::Arc<crate::features::colliders::scene_depth::DepthImage>,
    ) {
        for c in &mut self.colliders {
            if let crate::features::colliders::Surface::SceneDepth(s) = &mut c.surface {
                s.image = Some(image.clone());
            }
        }
    }

    /// Whether any collider needs the `collider_data` binding (a height field's samples, a
    /// mesh's field).
    pub(crate) fn has_collider_data(&self) -> bool {
        self.colliders.iter().any(|c| c.surface.data_len() > 0)
    }

    /// Whether kernels get the time modulo the noise period (the default: noise repeats
    /// then, and f32 keeps its sub-millisecond precision) or the whole simulation time, which a
    /// custom expression reading `t` or evolving turbulence needs (f32 then, so 1 ms steps at
    /// 2.3 hours).
    pub fn wraps_kernel_time(&self) -> bool {
        !self.terms.iter().any(|t| t.as_dyn().reads_whole_time())
            && !self.attributes.reads_time(self.kept_attributes())
    }
}

/// A kill volume.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum KillIr {
    /// Inside an axis-aligned box.
    InsideBox(DVec3, DVec3),
    /// Outside an axis-aligned box.
    OutsideBox(DVec3, DVec3),
    /// Inside a ball (centre, radius).
    InsideSphere(DVec3, f64),
    /// Outside a ball (centre, radius).
    OutsideSphere(DVec3, f64),
}

impl KillIr {
    /// Whether a particle at `x` dies (the f64 twin of the WGSL test).
    pub(crate) fn kills(&self, x: DVec3) -> bool {
        match *self {
            KillIr::InsideBox(min, max) => x.cmpge(min).all() && x.cmple(max).all(),
            KillIr::OutsideBox(min, max) => !(x.cmpge(min).all() && x.cmple(max).all()),
            KillIr::InsideSphere(c, r) => (x - c).length_squared() < r * r,
            KillIr::OutsideSphere(c, r) => (x - c).length_squared() > r * r,
        }
    }

    /// The thinnest a particle must cross to pass through an Inside volume (None for Outside).
    pub(crate) fn thickness(&self) -> Option<f64> {
        match *self {
            KillIr::InsideBox(min, max) => Some((max - min).min_element()),
            KillIr::InsideSphere(_, r) => Some(2.0 * r),
            _ => None,
        }
    }
}

/// The camera, for sorting and rendering.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraIr {
    /// Eye position.
    pub eye: DVec3,
    /// Look-at point.
    pub target: DVec3,
    /// Vertical field of view, degrees.
    pub fov_y: f64,
}
