//! A particle's own colour, its *tint*: the colour its sprite's colour over life is multiplied
//! by. It comes from `render.palette` (one colour of the palette per particle, picked from its
//! id) and, for particles spawned by an event with `inherit_color: true`, from the firing
//! particle's tint (docs/effect-format.md, "Colour from the palette and from the parent").
//!
//! This module owns the palette's check, the pick, the tint a particle stores (8 bits a
//! channel, as WGSL's `pack4x8unorm` packs it), the rule for which groups store one, and the
//! WGSL of all of it; the reference simulator and the reference drawing use the f64 twins.

use glam::DVec3;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::rng::{rand_u32, stream};
use crate::base::values::Vec3;
use crate::base::writer::{f32_lit, Writer};

/// What a group's tint depends on (`EffectIr::tint` gathers it): its palette, its seed and
/// whether its particles store a tint.
#[derive(Clone, Copy, Debug)]
pub struct TintSource<'a> {
    /// `render.palette`, lowered.
    pub palette: Option<&'a [DVec3]>,
    /// The group's `seed_mix`, which the pick's draw is keyed by.
    pub seed_mix: u32,
    /// Whether its particles store their tint: a stateful group fed by an event that passes
    /// the parent's colour on (the GPU cannot derive it from the child's id).
    pub stored: bool,
}

/// The most colours a palette may hold.
pub(crate) const MAX_PALETTE: usize = 256;

/// The packed tint of a particle with no colour of its own: white.
pub const WHITE: u32 = 0xffff_ffff;

/// Checks `render.palette`: 1 to [`MAX_PALETTE`] colours, each component finite in [0, 1].
pub(crate) fn check_palette(c: &mut Checker, path: &ValuePath, palette: &[Vec3]) {
    if palette.is_empty() || palette.len() > MAX_PALETTE {
        c.error(
            path,
            format!(
                "must hold 1 to {MAX_PALETTE} colours, got {}",
                palette.len()
            ),
        );
    }
    for (i, colour) in palette.iter().enumerate() {
        let p = path.index(i);
        for (j, (name, x)) in [("r", colour.0), ("g", colour.1), ("b", colour.2)]
            .into_iter()
            .enumerate()
        {
            c.within(&p.component(j, name), x, 0.0, 1.0);
        }
    }
}

/// The palette colour of particle `id`: entry ⌊u · n⌋ for the 24-bit uniform draw u of stream
/// `PALETTE`, in integers (the same entry on the GPU).
pub fn pick(palette: &[DVec3], seed_mix: u32, id: u32) -> DVec3 {
    let n = palette.len() as u64;
    let u = u64::from(rand_u32(seed_mix, id, stream::PALETTE) >> 8);
    palette[((u * n) >> 24) as usize]
}

/// The tint of particle `id` from its group's palette alone: its pick, or white without one.
pub fn own(tint: TintSource<'_>, id: u32) -> DVec3 {
    tint.palette
        .map_or(DVec3::ONE, |p| pick(p, tint.seed_mix, id))
}

/// The tint of a particle of the group spawned as `id` that inherits `inherited` (white from an
/// emitter or an event that passes no colour on): its own times the inherited one, at 8 bits a
/// channel where the group stores it.
pub(crate) fn spawned(tint: TintSource<'_>, id: u32, inherited: DVec3) -> DVec3 {
    let c = own(tint, id) * inherited;
    if tint.stored {
        stored(c)
    } else {
        c
    }
}

/// `c` packed as `pack4x8unorm(vec4(c, 1))`: each channel ⌊0.5 + 255 · clamp(c, 0, 1)⌋.
pub fn pack(c: DVec3) -> u32 {
    let byte = |x: f64| (0.5 + 255.0 * x.clamp(0.0, 1.0)).floor() as u32;
    byte(c.x) | (byte(c.y) << 8) | (byte(c.z) << 16) | (255 << 24)
}

/// The colour of a packed tint, as `unpack4x8unorm(bits).rgb`.
pub fn unpack(bits: u32) -> DVec3 {
    let channel = |k: u32| f64::from((bits >> (8 * k)) & 0xff) / 255.0;
    DVec3::new(channel(0), channel(1), channel(2))
}

/// What a stored tint holds for `c`: `c` at 8 bits a channel.
pub fn stored(c: DVec3) -> DVec3 {
    unpack(pack(c))
}

/// Emits `palette_tint(id) -> vec3<f32>` (the f32 twin of [`pick`]) when the group has a
/// palette; it needs the rng functions and `SEED_MIX`.
pub(crate) fn emit_palette_fn(w: &mut Writer, tint: TintSource<'_>) {
    let Some(palette) = tint.palette else {
        return;
    };
    let colours: Vec<String> = palette
        .iter()
        .map(|c| {
            format!(
                "vec3<f32>({}, {}, {})",
                f32_lit(c.x),
                f32_lit(c.y),
                f32_lit(c.z)
            )
        })
        .collect();
    w.line(format!(
        "const PALETTE = array<vec3<f32>, {}>({});",
        palette.len(),
        colours.join(", ")
    ));
    w.comment("The palette's colour for particle `id` (tint.rs: `pick`).");
    w.block("fn palette_tint(id: u32) -> vec3<f32>", |w| {
        w.line(format!(
            "let at = ((rand_u32(id, {}u) >> 8u) * {}u) >> 24u;",
            stream::PALETTE,
            palette.len()
        ));
        w.line("return PALETTE[at];");
    });
}

/// The WGSL of the group's own tint (vec3<f32>) for a particle of id `id`: its palette pick,
/// or white.
pub(crate) fn own_wgsl(tint: TintSource<'_>, id: &str) -> String {
    if tint.palette.is_some() {
        format!("palette_tint({id})")
    } else {
        "vec3<f32>(1.0)".to_string()
    }
}

/// The WGSL of particle `p`'s tint (vec3<f32>) as the draw applies it, or None when the group
/// has no colour of its own (its sprites keep their colour over life). `id` names its id.
pub(crate) fn particle_wgsl(tint: TintSource<'_>, p: &str, id: &str) -> Option<String> {
    if tint.stored {
        Some(format!("unpack4x8unorm({p}.tint).rgb"))
    } else if tint.palette.is_some() {
        Some(format!("palette_tint({id})"))
    } else {
        None
    }
}

/// The WGSL of a stateless particle's tint packed for an event record (u32), from its `id`: a
/// stateless group stores no tint (nothing feeds it).
pub(crate) fn packed_wgsl_of_id(tint: TintSource<'_>, id: &str) -> String {
    if tint.palette.is_some() {
        format!("pack4x8unorm(vec4<f32>(palette_tint({id}), 1.0))")
    } else {
        format!("{WHITE}u")
    }
}

/// The WGSL of particle `p`'s tint packed for an event record (u32): what its children inherit.
pub(crate) fn packed_wgsl(tint: TintSource<'_>, p: &str) -> String {
    if tint.stored {
        format!("{p}.tint")
    } else if tint.palette.is_some() {
        format!("pack4x8unorm(vec4<f32>(palette_tint({p}.id), 1.0))")
    } else {
        format!("{WHITE}u")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packing_rounds_to_the_nearest_step_and_clamps() {
        assert_eq!(pack(DVec3::ONE), WHITE);
        assert_eq!(
            pack(DVec3::new(0.0, 0.5, 2.0)) & 0x00ff_ffff,
            (128 << 8) | (255 << 16)
        );
        assert_eq!(
            pack(DVec3::new(-1.0, 1.0 / 255.0, 0.499 / 255.0)) & 0xffff,
            1 << 8
        );
        let c = DVec3::new(0.2, 0.6, 0.9);
        assert!((stored(c) - c).abs().max_element() <= 0.5 / 255.0);
    }

    #[test]
    fn picks_spread_over_the_whole_palette() {
        let palette = [DVec3::X, DVec3::Y, DVec3::Z];
        let mut seen = [0u32; 3];
        for id in 0..3000 {
            let c = pick(&palette, 12345, id);
            seen[palette.iter().position(|p| *p == c).unwrap()] += 1;
        }
        assert!(seen.iter().all(|&n| (850..1150).contains(&n)), "{seen:?}");
    }
}
