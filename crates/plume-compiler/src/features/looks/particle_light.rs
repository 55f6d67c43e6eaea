//! Light from particles (`render.light`): a group's brightest particles give off light, as
//! point lights at their positions of their colour: what sparks throw on the ground. The
//! particles are split into `count` buckets by slot (slot mod count) and each bucket gives
//! its brightest visible particle (by the luminance of its drawn colour times its opacity),
//! so the lights are bright and spread over the whole group rather than bunched. Two small
//! kernels of the draw module find them on the GPU (`ParticleLight::emit_kernels`: a
//! maximum per bucket, then the particle that holds it), and [`ParticleLight::pick`] is the
//! f64 twin over the particles' drawn colours. The runtime reads the few lights back;
//! `plume render` and `plume preview` light the scene's meshes with them, and the Bevy plugin
//! turns them into Bevy point lights.

use glam::DVec3;
use serde::Deserialize;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::writer::{f32_lit, Writer};
use crate::features::lights::LIGHTS_MOST;

/// `render.light`: the group's brightest particles give off light.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticleLight {
    /// Most lights given off (1 to [`LIGHTS_MOST`]): the buckets the particles are split into.
    #[serde(default = "default_count")]
    pub count: u32,
    /// A light's strength: colour (times opacity) times this, 1 m away.
    #[serde(default = "default_intensity")]
    pub intensity: f64,
    /// Where a light has faded to nothing (m).
    #[serde(default = "default_range")]
    pub range: f64,
}

fn default_count() -> u32 {
    LIGHTS_MOST as u32
}

fn default_intensity() -> f64 {
    1.0
}

fn default_range() -> f64 {
    5.0
}

/// Binding of the buckets' brightest keys in a draw module with the light kernels.
pub const LIGHT_KEYS_BINDING: u32 = 50;

/// Binding of the lights the kernels pick: two vec4s each, (position, key) and (colour times
/// opacity, 0), in the draw's space (the runtime draws them with an identity view).
pub const LIGHT_LIST_BINDING: u32 = 51;

/// Bytes of one picked light.
pub const LIGHT_ENTRY_BYTES: u64 = 32;

/// Threads of a light kernel's workgroup, a slot each.
pub const LIGHT_WORKGROUP: u32 = 256;

impl ParticleLight {
    /// Checks `count` (1 to [`LIGHTS_MOST`]), `intensity` (>= 0) and `range` (> 0).
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        if self.count == 0 || self.count as usize > LIGHTS_MOST {
            c.error(
                &path.field("count"),
                format!(
                    "must be 1 to {LIGHTS_MOST} (the lights a draw reads), got {}",
                    self.count
                ),
            );
        }
        c.non_negative(&path.field("intensity"), self.intensity);
        c.positive(&path.field("range"), self.range);
    }

    /// A particle's brightness: the luminance of its drawn colour (Rec. 709 weights) times its
    /// opacity, never below 0. The f64 twin of the kernels' key.
    pub fn brightness(rgba: [f64; 4]) -> f64 {
        ((0.2126 * rgba[0] + 0.7152 * rgba[1] + 0.0722 * rgba[2]) * rgba[3]).max(0.0)
    }

    /// The lights of particles in slots (`Some((position, drawn colour RGBA))` for a visible
    /// one): for each bucket (slot mod `count`) its brightest particle (the lowest slot of
    /// equals), as (position, colour times opacity), brightest bucket first.
    pub fn pick(&self, slots: &[Option<(DVec3, [f64; 4])>]) -> Vec<(DVec3, DVec3)> {
        let n = self.count.max(1) as usize;
        let mut best: Vec<Option<(f64, DVec3, [f64; 4])>> = vec![None; n];
        for (slot, particle) in slots.iter().enumerate() {
            let Some((x, rgba)) = *particle else { continue };
            let b = Self::brightness(rgba);
            let bucket = &mut best[slot % n];
            if bucket.is_none_or(|(held, _, _)| b > held) {
                *bucket = Some((b, x, rgba));
            }
        }
        let mut lights: Vec<(f64, DVec3, DVec3)> = best
            .into_iter()
            .flatten()
            .map(|(b, x, c)| (b, x, DVec3::new(c[0], c[1], c[2]) * c[3]))
            .collect();
        lights.sort_by(|a, b| b.0.total_cmp(&a.0));
        lights.into_iter().map(|(_, x, c)| (x, c)).collect()
    }

    /// Emits the buffers and the two kernels of the draw module (which holds `sprite_at`):
    /// `light_keys_pass`, a thread per slot, keeps each bucket's greatest key (the
    /// brightness's bits plus one: 0 is an empty bucket) with atomic maxima, in its workgroup
    /// and then once per workgroup in the buffer; `light_pick_pass` writes the particle that
    /// holds its bucket's key into the list (equal keys: any of them).
    pub(crate) fn emit_kernels(&self, w: &mut Writer, capacity: u32) {
        w.comment(
            "render.light: each bucket's brightest particle (slot mod count), and its light.",
        );
        w.line(format!(
            "@group(0) @binding({LIGHT_KEYS_BINDING}) var<storage, read_write> light_keys: array<atomic<u32>>;"
        ));
        w.line(format!(
            "@group(0) @binding({LIGHT_LIST_BINDING}) var<storage, read_write> light_list: array<vec4<f32>>;"
        ));
        w.line(format!("const LIGHT_BUCKETS: u32 = {}u;", self.count));
        w.line(format!("const LIGHT_SLOTS: u32 = {capacity}u;"));
        w.blank();
        w.comment("A visible sprite's key: its brightness's bits plus one (non-negative floats order as their bits); 0 for none.");
        w.block("fn light_key(s: SpriteAt) -> u32", |w| {
            w.block("if (!s.visible)", |w| w.line("return 0u;"));
            w.line(format!(
                "let luminance = dot(s.color.rgb, vec3<f32>({}, {}, {}));",
                f32_lit(0.2126),
                f32_lit(0.7152),
                f32_lit(0.0722)
            ));
            w.line("return bitcast<u32>(max(luminance * s.color.a, 0.0)) + 1u;");
        });
        w.blank();
        w.comment("Each bucket's greatest key in the workgroup first, then one global atomic per bucket and workgroup: 8 words that every slot would hit otherwise.");
        w.line("var<workgroup> group_keys: array<atomic<u32>, LIGHT_BUCKETS>;");
        w.blank();
        w.line(format!("@compute @workgroup_size({LIGHT_WORKGROUP})"));
        w.block(
            "fn light_keys_pass(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) local: u32, @builtin(num_workgroups) groups: vec3<u32>)",
            |w| {
                w.comment(format!("A 2D grid past the dispatch limit: rows of groups.x workgroups of {LIGHT_WORKGROUP}."));
                w.line(format!("let slot = gid.y * groups.x * {LIGHT_WORKGROUP}u + gid.x;"));
                w.block("if (local < LIGHT_BUCKETS)", |w| {
                    w.line("atomicStore(&group_keys[local], 0u);");
                });
                w.line("workgroupBarrier();");
                w.block("if (slot < LIGHT_SLOTS)", |w| {
                    w.line("let key = light_key(sprite_at(slot));");
                    w.block("if (key > 0u)", |w| {
                        w.line("atomicMax(&group_keys[slot % LIGHT_BUCKETS], key);");
                    });
                });
                w.line("workgroupBarrier();");
                w.block("if (local < LIGHT_BUCKETS)", |w| {
                    w.line("let key = atomicLoad(&group_keys[local]);");
                    w.block("if (key > 0u)", |w| {
                        w.line("atomicMax(&light_keys[local], key);");
                    });
                });
            },
        );
        w.blank();
        w.line(format!("@compute @workgroup_size({LIGHT_WORKGROUP})"));
        w.block(
            "fn light_pick_pass(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
            |w| {
                w.line(format!("let slot = gid.y * groups.x * {LIGHT_WORKGROUP}u + gid.x;"));
                w.block("if (slot >= LIGHT_SLOTS)", |w| w.line("return;"));
                w.line("let s = sprite_at(slot);");
                w.line("let key = light_key(s);");
                w.line("let bucket = slot % LIGHT_BUCKETS;");
                w.block(
                    "if (key > 0u && key == atomicLoad(&light_keys[bucket]))",
                    |w| {
                        w.comment("The view is the identity: the centre is the particle's position.");
                        w.line("light_list[2u * bucket] = vec4<f32>(s.center.xyz, bitcast<f32>(key));");
                        w.line("light_list[2u * bucket + 1u] = vec4<f32>(s.color.rgb * s.color.a, 0.0);");
                    },
                );
            },
        );
    }
}
