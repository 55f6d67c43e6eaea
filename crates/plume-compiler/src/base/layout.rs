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
    /// The step the particle's age counts from (its spawn step, less a starting age): `born`.
    /// Only where something needs a particle's age that its id and death step cannot give:
    /// a custom force or attribute change reading `age` or `life`, a draw needing a life
    /// fraction or an age (gradients, flipbooks, a spin, expressions) when the lifetimes do not
    /// come from one shared range, events, or starting ages (`stages::passes::layout::decide`).
    SpawnStep,
    /// The particle's tint, packed 8 bits a channel: `tint`. Only in a group fed by an event
    /// that passes the parent's colour on (`EffectIr::stores_tint`).
    Tint,
    /// An attribute the effect declares (`features::attributes`), kept because something
    /// reads it: `uN` for a number, `uN, uN+1, uN+2` for a vec3, N its first word among the
    /// declared attributes' words.
    User {
        /// Its index among the effect's attributes (name order).
        index: u8,
        /// Its first word among the declared attributes' words (the field `u{first}`).
        first: u8,
        /// Its words: 1 for a number, 3 for a vec3.
        width: u8,
        /// Whether it changes after spawn (the update then stores it).
        changes: bool,
    },
}

/// The field names of the declared attributes' words, `u0` to `u15`.
const USER_FIELDS: [&str; 16] = [
    "u0", "u1", "u2", "u3", "u4", "u5", "u6", "u7", "u8", "u9", "u10", "u11", "u12", "u13", "u14",
    "u15",
];

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
            Attribute::User { first, width, .. } => {
                let first = usize::from(first);
                (&USER_FIELDS[first..first + usize::from(width)], "f32")
            }
        }
    }

    /// Whether the update changes it (the rest the spawn alone writes): position, motion, and
    /// declared attributes with a rate or an update.
    pub fn changes(self) -> bool {
        match self {
            Attribute::Position | Attribute::Velocity | Attribute::Displacement => true,
            Attribute::User { changes, .. } => changes,
            _ => false,
        }
    }

    /// Whether the attribute is the particle's motion (velocity, or Verlet's displacement):
    /// the one an accuracy budget may store in 16-bit floats (`Layout::half_motion`).
    pub(crate) fn is_motion(self) -> bool {
        matches!(self, Attribute::Velocity | Attribute::Displacement)
    }

    /// The 4-byte words it is stored in, as (name, kind): the struct's fields themselves, or
    /// for motion in 16-bit floats two words, `HALF2` holding x and y and `HALF1` holding z in
    /// its low half (the struct's fields stay f32: loads unpack, stores pack).
    pub fn words(self, half_motion: bool) -> Vec<(&'static str, &'static str)> {
        match self {
            Attribute::Velocity if half_motion => vec![("vxy", HALF2), ("vz", HALF1)],
            Attribute::Displacement if half_motion => vec![("dxy", HALF2), ("dz", HALF1)],
            _ => {
                let (names, ty) = self.fields();
                names.iter().map(|n| (*n, ty)).collect()
            }
        }
    }

    /// Bytes this attribute takes per particle, stored.
    pub fn bytes(self, half_motion: bool) -> u32 {
        4 * self.words(half_motion).len() as u32
    }

    /// What it holds, for `--emit layout`.
    pub(crate) fn meaning(self) -> &'static str {
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
            Attribute::User { changes: true, .. } => {
                "a declared attribute, changed each step (its name: --emit ir)"
            }
            Attribute::User { changes: false, .. } => {
                "a declared attribute, set at spawn (its name: --emit ir)"
            }
        }
    }
}

/// A stored word holding two 16-bit floats (fields x and y of its attribute).
pub(crate) const HALF2: &str = "f16x2";
/// A stored word holding one 16-bit float in its low half (field z of its attribute).
pub(crate) const HALF1: &str = "f16";

/// One resource binding of the compiled module (group 0).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Binding {
    /// Binding index.
    pub binding: u32,
    /// What it holds: the runtime makes, fills and binds its buffer by this.
    pub role: Role,
    /// Address space and access, as the module declares it.
    pub space: Space,
    /// Size in bytes for this effect's capacity.
    pub bytes: u64,
    /// What it holds, in words (`plume compile --emit layout`).
    pub meaning: &'static str,
}

impl Binding {
    /// Its WGSL variable's name.
    pub fn name(&self) -> &'static str {
        self.role.name()
    }
}

/// What a binding of the compute module holds: the contract between the layout the compiler
/// writes and the buffers the runtime makes, fills and binds, so neither side matches a
/// binding by its name or number. Each role has one WGSL name ([`Role::name`]); the roles of
/// events and inherited attributes carry the event's slot (0 to 3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Role {
    /// The particle records (a stateless effect's view of them).
    Particles,
    /// A stateless effect's spawn bookkeeping, written by the CPU each frame.
    Frame,
    /// The stack of free slots.
    FreeList,
    /// The free count, spawn base and totals.
    Counters,
    /// The step parameters (a row per step; per instance too when batched).
    Params,
    /// The slots one dispatch's particle buffer holds.
    Chunk,
    /// The trail history ring.
    Trail,
    /// The ribbons' slot table by id.
    RibbonTable,
    /// A baked vector field's cells.
    Field,
    /// The vector-field forces' samples, written once.
    ForceData,
    /// The mesh emitters' surfaces, written once.
    SpawnData,
    /// The height fields' samples and mesh colliders' distance fields, written once.
    ColliderData,
    /// The host's depth image that a `SceneDepth` collider meets.
    SceneDepth,
    /// That depth image's camera, written by the host.
    SceneCamera,
    /// Flocking: the boids' positions and velocities.
    Boids,
    /// Flocking: each boid's steering.
    FlockOut,
    /// Flocking: the neighbour sums.
    FlockSums,
    /// Flocking's grid: cell keys.
    GridKeys,
    /// Flocking's grid: slot values.
    GridVals,
    /// Flocking's grid: slots in cell order.
    GridPlaced,
    /// Flocking's grid: boids per cell.
    CellCounts,
    /// Flocking's grid: each cell's first boid.
    CellStart,
    /// The depth sort's keys.
    SortKeys,
    /// The depth sort's values.
    SortVals,
    /// The axis the depth sort measures along.
    DepthAxis,
    /// A stateless group's bookkeeping for the steps whose events fire.
    FireFrame,
    /// The step a stateless group's firing kernel fires for.
    FireState,
    /// A batch's per-instance transforms.
    InstanceModels,
    /// An event's firing keys (to order the firings).
    EventKeys(u8),
    /// An event's firing values.
    EventVals(u8),
    /// An event's firing records, as its parent writes them.
    EventOut(u8),
    /// The order a child group takes an event's firings in.
    EventOrder(u8),
    /// An event's firing records, as the child group reads them.
    EventIn(u8),
    /// The attributes an event's firings pass on, as the parent writes them.
    AttrsOut(u8),
    /// Those attributes, as the child group reads them.
    AttrsIn(u8),
}

impl Role {
    /// The WGSL variable's name.
    pub fn name(self) -> &'static str {
        let slot = |names: [&'static str; 4], j: u8| names[usize::from(j).min(3)];
        match self {
            Role::Particles => "particles",
            Role::Frame => "frame",
            Role::FreeList => "free_list",
            Role::Counters => "counters",
            Role::Params => "params",
            Role::Chunk => "chunk",
            Role::Trail => "trail",
            Role::RibbonTable => "ribbon_table",
            Role::Field => "field",
            Role::ForceData => "force_data",
            Role::SpawnData => "spawn_data",
            Role::ColliderData => "collider_data",
            Role::SceneDepth => "scene_depth",
            Role::SceneCamera => "scene_camera",
            Role::Boids => "boids",
            Role::FlockOut => "flock_out",
            Role::FlockSums => "flock_sums",
            Role::GridKeys => "grid_keys",
            Role::GridVals => "grid_vals",
            Role::GridPlaced => "grid_placed",
            Role::CellCounts => "cell_counts",
            Role::CellStart => "cell_start",
            Role::SortKeys => "sort_keys",
            Role::SortVals => "sort_vals",
            Role::DepthAxis => "depth_axis",
            Role::FireFrame => "fire_frame",
            Role::FireState => "fire_state",
            Role::InstanceModels => "instance_models",
            Role::EventKeys(j) => slot(
                [
                    "event_keys_0",
                    "event_keys_1",
                    "event_keys_2",
                    "event_keys_3",
                ],
                j,
            ),
            Role::EventVals(j) => slot(
                [
                    "event_vals_0",
                    "event_vals_1",
                    "event_vals_2",
                    "event_vals_3",
                ],
                j,
            ),
            Role::EventOut(j) => slot(
                ["event_out_0", "event_out_1", "event_out_2", "event_out_3"],
                j,
            ),
            Role::EventOrder(j) => slot(
                [
                    "event_order_0",
                    "event_order_1",
                    "event_order_2",
                    "event_order_3",
                ],
                j,
            ),
            Role::EventIn(j) => slot(["event_in_0", "event_in_1", "event_in_2", "event_in_3"], j),
            Role::AttrsOut(j) => slot(
                [
                    "event_attrs_out_0",
                    "event_attrs_out_1",
                    "event_attrs_out_2",
                    "event_attrs_out_3",
                ],
                j,
            ),
            Role::AttrsIn(j) => slot(
                [
                    "event_attrs_in_0",
                    "event_attrs_in_1",
                    "event_attrs_in_2",
                    "event_attrs_in_3",
                ],
                j,
            ),
        }
    }
}

/// A binding's address space and access.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Space {
    /// `var<uniform>`.
    Uniform,
    /// `var<storage, read>`.
    Read,
    /// `var<storage, read_write>`.
    ReadWrite,
}

impl Space {
    /// As WGSL writes it between `var<` and `>`.
    pub fn wgsl(self) -> &'static str {
        match self {
            Space::Uniform => "uniform",
            Space::Read => "storage, read",
            Space::ReadWrite => "storage, read_write",
        }
    }
}

/// The particle struct and the bindings of an effect.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Attributes in struct order.
    pub attributes: Vec<Attribute>,
    /// Whether the motion attribute is stored in 16-bit floats (an accuracy budget that
    /// allows it: `calibration::accuracy`). Such a layout keeps its words unpadded: whole
    /// 16-byte planes, then a plane of 8-byte and one of 4-byte words for the rest
    /// ([`Layout::planes`]).
    pub half_motion: bool,
    /// Bytes per particle: the attributes' stored 4-byte words, padded to a multiple of 16
    /// unless the motion is stored in halves.
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
    /// Compiled for batched instances (`crate::batch`): `CAPACITY` slots per instance, every
    /// instance's counters, free list segment and step parameters side by side, the instance
    /// read from the dispatch's z.
    pub batched: bool,
    /// A batched layout's slots per instance (`CAPACITY` of its compute module; 0 otherwise).
    pub(crate) instance_slots: u32,
}

impl Layout {
    /// The stored fields of declared attribute `index`, when it is kept.
    pub(crate) fn user_fields(&self, index: usize) -> Option<&'static [&'static str]> {
        self.attributes.iter().find_map(|a| match *a {
            Attribute::User { index: i, .. } if usize::from(i) == index => Some(a.fields().0),
            _ => None,
        })
    }

    /// Offset of attribute `a` in the stored particle, in 4-byte words.
    pub fn word_offset(&self, a: Attribute) -> Option<usize> {
        let mut word = 0;
        for &b in &self.attributes {
            if a == b {
                return Some(word);
            }
            word += b.words(self.half_motion).len();
        }
        None
    }

    /// The stored 4-byte words in order, as (name, kind: `f32`, `u32`, `HALF2` or
    /// `HALF1`), without padding.
    pub fn words(&self) -> Vec<(&'static str, &'static str)> {
        self.attributes
            .iter()
            .flat_map(|a| a.words(self.half_motion))
            .collect()
    }

    /// Whole 16-byte words per particle (planes of vec4s).
    pub fn vec4s(&self) -> u32 {
        self.planes().full
    }

    /// How a buffer's slots are stored: word-major planes, each holding one word group of
    /// every slot. A padded layout is whole 16-byte planes; a half-motion layout's last one to
    /// three words go to an 8-byte plane (two slots a vec4) and a 4-byte plane (four slots a
    /// vec4), so no slot carries padding.
    pub fn planes(&self) -> Planes {
        let words = self.words().len() as u32;
        if !self.half_motion {
            return Planes {
                full: self.bytes_per_particle / 16,
                pair: false,
                single: false,
            };
        }
        Planes {
            full: words / 4,
            pair: words % 4 >= 2,
            single: words % 2 == 1,
        }
    }

    /// Bytes of a particle buffer of `slots` slots: its planes, each a whole number of vec4s.
    pub fn buffer_bytes(&self, slots: u64) -> u64 {
        let p = self.planes();
        let pair = if p.pair { slots.div_ceil(2) } else { 0 };
        let single = if p.single { slots.div_ceil(4) } else { 0 };
        16 * (u64::from(p.full) * slots + pair + single)
    }

    /// The slots of a particle buffer of `bytes` bytes (the inverse of [`Layout::buffer_bytes`]).
    pub fn slots_in(&self, bytes: u64) -> u64 {
        let bpp = u64::from(self.bytes_per_particle.max(1));
        let mut slots = bytes / bpp;
        while slots > 0 && self.buffer_bytes(slots) > bytes {
            slots -= 1;
        }
        slots
    }

    /// Byte offset, in a buffer of `slots` slots, of stored word `word` of slot `i`.
    pub fn word_byte(&self, word: usize, i: u64, slots: u64) -> u64 {
        let p = self.planes();
        let full = 4 * p.full as usize;
        let pairs_at = 16 * u64::from(p.full) * slots;
        if word < full {
            16 * ((word as u64 / 4) * slots + i) + 4 * (word as u64 % 4)
        } else if p.pair && word < full + 2 {
            pairs_at + 8 * i + 4 * (word - full) as u64
        } else {
            let singles_at = pairs_at + if p.pair { 16 * slots.div_ceil(2) } else { 0 };
            singles_at + 4 * i
        }
    }

    /// Whether the layout has a binding of `role`.
    pub fn binds(&self, role: Role) -> bool {
        self.bindings.iter().any(|b| b.role == role)
    }

    /// The binding of `role`, if the layout has one.
    pub fn binding_of(&self, role: Role) -> Option<&Binding> {
        self.bindings.iter().find(|b| b.role == role)
    }

    /// Whether the effect is stateless: one `evaluate` kernel, no state kept between steps.
    pub fn stateless(&self) -> bool {
        self.binds(Role::Frame)
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
        self.binds(Role::SortKeys)
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
        // A batched instance's row ends with (active, 0, 0, 0).
        let batch = if self.batched { 16 } else { 0 };
        16 + placement
            + 16 * u64::from(self.emitter_slots)
            + bursts
            + 16 * self.user_vec4s()
            + batch
    }

    /// The vec4s the live params take in the step parameters.
    pub fn user_vec4s(&self) -> u64 {
        u64::from(self.live_params).div_ceil(4)
    }
}

/// The planes a particle buffer stores its slots in ([`Layout::planes`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Planes {
    /// Planes of 16-byte words (word k of slot i at vec4 k · slots + i).
    pub full: u32,
    /// Whether an 8-byte plane follows (slot i's pair in half i % 2 of vec4
    /// full · slots + i / 2).
    pub pair: bool,
    /// Whether a 4-byte plane ends the buffer (slot i's word in lane i % 4 of the vec4
    /// i / 4 after the pair plane).
    pub single: bool,
}

/// Bytes of the counters struct (free count, spawn base, spawn count, spawned, dropped, died).
/// A group fed by events adds two words (its next id, the first id of the current event
/// spawn), which the buffer's padding to 32 bytes already holds.
pub const COUNTERS_BYTES: u64 = 24;
