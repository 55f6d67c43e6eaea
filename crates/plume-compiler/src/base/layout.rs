//! The particle layout's types: the particle struct holds only the attributes an effect needs,
//! as scalar f32/u32 fields (no vec3 padding), so bytes per particle are the fewest the kernels
//! read and write. The layout pass (`stages::passes::layout`) decides them; they sit here,
//! below the features, because features that emit kernels (events, the flock) read them.

/// What an attribute of the particle struct holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Attribute {
    /// Position (m): `px, py, pz`.
    Position,
    /// Velocity (m/s): `vx, vy, vz`.
    Velocity,
    /// Verlet's displacement `x - x_prev` over one substep (m): `dx, dy, dz`.
    Displacement,
    /// Index of the step whose update kills the particle (`0xffffffff`: never): `die_at`.
    /// Only when some emitter sets a lifetime; age itself is derived on the CPU from the id.
    DeathStep,
    /// Global spawn index, or `0xffffffff` for a free slot: `id`.
    Id,
    /// The step the particle spawned at: `born`. Only when a custom force reads `age` or
    /// `life`, or when the draw needs a life fraction (colour or size change over life) and
    /// the emitters with lifetimes draw them from different ranges, so that the draw cannot
    /// re-derive a particle's lifetime from its id alone (see `stages::passes::layout::needs_spawn_step`).
    SpawnStep,
    /// The particle's tint, packed 8 bits a channel: `tint`. Only in a group fed by an event
    /// that passes the parent's colour on (`EffectIr::stores_tint`).
    Tint,
}

impl Attribute {
    /// The WGSL field names and their scalar type.
    pub fn fields(self) -> (&'static [&'static str], &'static str) {
        match self {
            Attribute::Position => (&["px", "py", "pz"], "f32"),
            Attribute::Velocity => (&["vx", "vy", "vz"], "f32"),
            Attribute::Displacement => (&["dx", "dy", "dz"], "f32"),
            Attribute::DeathStep => (&["die_at"], "u32"),
            Attribute::Id => (&["id"], "u32"),
            Attribute::SpawnStep => (&["born"], "u32"),
            Attribute::Tint => (&["tint"], "u32"),
        }
    }

    /// Bytes this attribute takes per particle.
    pub fn bytes(self) -> u32 {
        4 * self.fields().0.len() as u32
    }

    /// What it holds, for `--emit layout`.
    pub fn meaning(self) -> &'static str {
        match self {
            Attribute::Position => "position (m)",
            Attribute::Velocity => "velocity (m/s)",
            Attribute::Displacement => "Verlet displacement x - x_prev per substep (m)",
            Attribute::DeathStep => "step whose update kills it (0xffffffff: never)",
            Attribute::Id => "global spawn index; 0xffffffff marks a free slot",
            Attribute::SpawnStep => {
                "spawn step, for a custom force's age, the draw's life fraction, a flipbook's frame or events"
            }
            Attribute::Tint => {
                "colour (8 bits a channel) multiplying the colour over life: the parent's tint times the palette's"
            }
        }
    }
}

/// One resource binding of the compiled module (group 0).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Binding {
    /// Binding index.
    pub binding: u32,
    /// WGSL variable name.
    pub name: &'static str,
    /// Address space and access, as in WGSL.
    pub space: &'static str,
    /// Size in bytes for this effect's capacity.
    pub bytes: u64,
    /// What it holds.
    pub meaning: &'static str,
}

/// The particle struct and the bindings of an effect.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Attributes in struct order.
    pub attributes: Vec<Attribute>,
    /// Bytes per particle: the attributes' 4-byte fields, padded to a multiple of 16.
    pub bytes_per_particle: u32,
    /// Bindings, in binding order.
    pub bindings: Vec<Binding>,
    /// Number of emitter entries in the step parameters (at least 1).
    pub emitter_slots: u32,
    /// Whether the step parameters carry the placement's rows after their header
    /// (`features::placement`).
    pub placed: bool,
    /// Whether the step parameters carry the bursts' slots after the emitters'
    /// (`features::bursts`).
    pub bursts: bool,
    /// Params read at run time (`CompileOptions::live_params`): the step parameters end with
    /// them, four to a vec4, in name order.
    pub live_params: u32,
    /// Bytes of trail history per particle (`render.trail`; 0 without one), held in the
    /// `trail` binding beside the particle struct.
    pub trail_bytes_per_particle: u32,
}

impl Layout {
    /// Offset of attribute `a` in the particle struct, in 4-byte words.
    pub fn word_offset(&self, a: Attribute) -> Option<usize> {
        let mut word = 0;
        for &b in &self.attributes {
            if a == b {
                return Some(word);
            }
            word += b.fields().0.len();
        }
        None
    }

    /// The struct's 4-byte words in order, as (field name, WGSL scalar type), without padding.
    pub fn words(&self) -> Vec<(&'static str, &'static str)> {
        self.attributes
            .iter()
            .flat_map(|a| {
                let (names, ty) = a.fields();
                names.iter().map(move |n| (*n, ty))
            })
            .collect()
    }

    /// 16-byte words per particle.
    pub fn vec4s(&self) -> u32 {
        self.bytes_per_particle / 16
    }

    /// Whether the layout has a binding called `name`.
    pub fn binds(&self, name: &str) -> bool {
        self.bindings.iter().any(|b| b.name == name)
    }

    /// Whether the effect is stateless: one `evaluate` kernel, no state kept between steps.
    pub fn stateless(&self) -> bool {
        self.binds("frame")
    }

    /// Bytes per particle carried from step to step: `bytes_per_particle`, or 0 when the
    /// effect is stateless (its `particles` buffer is then a view `evaluate` writes afresh).
    pub fn state_bytes_per_particle(&self) -> u32 {
        if self.stateless() {
            0
        } else {
            self.bytes_per_particle
        }
    }

    /// Whether the effect has a sort stage (bindings 5 and 6).
    pub fn sorts(&self) -> bool {
        self.bindings.iter().any(|b| b.name == "sort_keys")
    }

    /// Whether the layout has `a`.
    pub fn has(&self, a: Attribute) -> bool {
        self.attributes.contains(&a)
    }

    /// Bytes of the uniform step parameters: 16 of header, 48 of placement when placed, 16 per
    /// emitter slot, the bursts' slots when it takes bursts (384), then 16 per four live
    /// params.
    pub fn params_bytes(&self) -> u64 {
        let placement = if self.placed { 48 } else { 0 };
        let bursts = if self.bursts { 384 } else { 0 };
        16 + placement + 16 * u64::from(self.emitter_slots) + bursts + 16 * self.user_vec4s()
    }

    /// The vec4s the live params take in the step parameters.
    pub fn user_vec4s(&self) -> u64 {
        u64::from(self.live_params).div_ceil(4)
    }
}

/// Bytes of the counters struct (free count, spawn base, spawn count, spawned, dropped, died).
/// A group fed by events adds two words (its next id, the first id of the current event
/// spawn), which the buffer's padding to 32 bytes already holds.
pub const COUNTERS_BYTES: u64 = 24;
