//! Additive light summed in fixed point. A tile's list of additive records is built without a
//! sort (the runtime places each entry with an atomic, in no fixed order), so the composite
//! must reach the same sum in any order: each fragment's light is rounded to a whole number of
//! [`LIGHT_UNITS`] and added as an integer, which is exact and so independent of the order.
//! A fragment takes eight instructions where an f32 sum took three, which costs the composite
//! less than the lists save by losing their sort (docs/performance.md, "What bounds sparks and
//! orbit"). Images move by at most one 8-bit step, in a few hundred of 2.8M channels.

use crate::base::writer::Writer;

/// Units of fixed-point light in 1.0: 2^15, a 128th of an 8-bit step. A u32 then holds up to
/// 131,072, past f16's largest finite value (65,504), which an HDR image keeps.
pub(crate) const LIGHT_UNITS: u32 = 1 << 15;

/// The most units one fragment adds (`features::looks::COLOR_MOST` of light, 128): below
/// 2^22, where adding [`ROUNDING`] rounds an f32 to a whole number exactly.
const FRAGMENT_MOST: u32 = (1 << 22) - 1;

/// 1.5 * 2^23: f32 values from 2^23 to 2^24 are whole numbers, so `ROUNDING + x` (x from 0
/// to 2^22) rounds x to the nearest one (ties to even), and its bits are [`ROUNDING_BITS`]
/// plus that number: a multiply-add instead of a float-to-integer conversion, which the H100
/// issues at an eighth of the rate.
const ROUNDING: &str = "12582912.0";
/// The bits of [`ROUNDING`] (0x4b400000).
const ROUNDING_BITS: &str = "0x4b400000u";

/// The sum a pixel may hold when a batch starts: a batch of `batch` records adds at most
/// [`FRAGMENT_MOST`] each, so clamping to this after each batch keeps the u32 sums from
/// wrapping (far past f16's range: the image clamps there anyway).
fn ceiling(batch: u32) -> u32 {
    u32::MAX - batch * (FRAGMENT_MOST + 1)
}

/// The fixed point's constants as WGSL declarations (`LIGHT_UNITS`, an f32; `ROUNDING` and its
/// bits `ROUNDING_BITS`), for the runtime's disc kernel (`splat.wgsl`'s raster), which sums
/// additive discs' light as the generated composites do.
pub fn splat_light_constants() -> String {
    let mut w = Writer::new();
    w.comment(format!(
        "Additive light in fixed point (the compiler's splat `light`): {LIGHT_UNITS} units a 1.0, each fragment rounded to whole units by adding ROUNDING (1.5 * 2^23) and summed as integers."
    ));
    w.line(format!("const LIGHT_UNITS: f32 = {LIGHT_UNITS}.0;"));
    w.line(format!("const ROUNDING: f32 = {ROUNDING};"));
    w.line(format!("const ROUNDING_BITS: u32 = {ROUNDING_BITS};"));
    w.finish()
}

/// Declares the pixel's light: `var light`, the bits of each fragment's rounded light summed
/// (three u32s, wrapping), and `var layers`, the fragments summed since the last batch, whose
/// [`ROUNDING_BITS`] each come off once a batch instead of once a fragment.
pub(crate) fn emit_declare(w: &mut Writer) {
    w.comment(format!(
        "Additive light in fixed point ({LIGHT_UNITS} units a 1.0): integer sums do not depend on the order of the tile's list."
    ));
    w.line("var light = vec3<u32>(0u);");
    w.line("var layers = 0u;");
}

/// Adds fragment `f` (its RGB times its alpha) to `light`. Colours are at most `COLOR_MOST`
/// and alphas, palettes and textures at most 1, so a fragment's light is within
/// [`FRAGMENT_MOST`] and needs no clamp (one past it would only add the wrong light, never a
/// NaN or an infinity: the sums are integers); an 8-bit target clamps `f` to 1 before.
pub(crate) fn emit_add(w: &mut Writer) {
    w.line(format!(
        "light += bitcast<vec3<u32>>(fma(f.rgb, vec3<f32>(f.a * {LIGHT_UNITS}.0), vec3<f32>({ROUNDING})));"
    ));
    w.line("layers += 1u;");
}

/// The pixel's light in units (a WGSL expression): the bits summed less the rounding's.
fn units() -> String {
    format!("(light - vec3<u32>(layers * {ROUNDING_BITS}))")
}

/// Whether every channel of `light` is full (1.0 or more: an 8-bit target's pixel is done).
pub(crate) fn full() -> String {
    format!("all({} >= vec3<u32>({LIGHT_UNITS}u))", units())
}

/// The light at which an HDR image's pixel is finished, in units (the tile kernels'
/// `splat_tiles.light_ceiling`): the glow's clamp (`clamp`, at most f16's largest finite
/// value; validation keeps it in [1, 65504]), past which light blooms as the clamp does and
/// the image shows 1, so any more light into the pixel changes nothing; or f16's largest
/// finite value, which the HDR image holds at most (`None`: an image without a glow, such as a
/// host's, which takes the light as it is).
pub fn splat_light_ceiling(clamp: Option<f64>) -> u32 {
    let most = crate::features::looks::glow::GLOW_CLAMP_MOST;
    let level = clamp.unwrap_or(most).clamp(1.0, most);
    (level * f64::from(LIGHT_UNITS)).round() as u32
}

/// Sets `done` when every channel of the pixel's light has reached `splat_tiles.light_ceiling`
/// ([`splat_light_ceiling`]). Light is never negative, so the pixel's sum over every slice
/// is past the ceiling too, and the merge's clamp leaves the same pixel whatever the other
/// records add: the sum stays exact and independent of the order.
pub(crate) fn emit_ceiling_test(w: &mut Writer) {
    w.line(format!(
        "done = all({} >= vec3<u32>(splat_tiles.light_ceiling));",
        units()
    ));
}

/// `splat_tiles.light_ceiling` as f32 light (a WGSL expression). f32 rounding is monotonic, so
/// a sum of units at or past the ceiling converts to at least this.
pub(crate) fn ceiling_as_f32() -> String {
    format!("f32(splat_tiles.light_ceiling) / {LIGHT_UNITS}.0")
}

/// Clamps `light` after a batch of `batch` records, so that the next batch cannot wrap it.
pub(crate) fn emit_batch_clamp(w: &mut Writer, batch: u32) {
    w.line(format!(
        "light = min({}, vec3<u32>({}u));",
        units(),
        ceiling(batch)
    ));
    w.line("layers = 0u;");
}

/// `light` as f32 light (a WGSL expression).
pub(crate) fn as_f32() -> String {
    format!("vec3<f32>({}) / {LIGHT_UNITS}.0", units())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rounding trick and the ceiling, checked in f32 and u32 on the CPU as the GPU does
    /// them: every whole number up to the fragment's most comes back exactly, halves round to
    /// even, and a batch of the most from the ceiling does not wrap.
    #[test]
    fn rounding_is_exact_and_sums_do_not_wrap() {
        let rounding: f32 = ROUNDING.parse().unwrap();
        let bits = u32::from_str_radix(
            ROUNDING_BITS.trim_start_matches("0x").trim_end_matches('u'),
            16,
        )
        .unwrap();
        assert_eq!(rounding.to_bits(), bits);
        let round = |x: f32| (x + rounding).to_bits().wrapping_sub(bits);
        for n in [0u32, 1, 2, 1000, 32768, FRAGMENT_MOST - 1, FRAGMENT_MOST] {
            assert_eq!(round(n as f32), n);
        }
        assert_eq!(round(2.5), 2);
        assert_eq!(round(3.5), 4);
        assert_eq!(round(0.49), 0);
        assert_eq!(round(0.51), 1);
        for batch in [64u32, 128] {
            let most = u64::from(ceiling(batch)) + u64::from(batch) * u64::from(FRAGMENT_MOST);
            assert!(most <= u64::from(u32::MAX));
            // The ceiling is far past f16's largest finite value.
            assert!(ceiling(batch) / LIGHT_UNITS > 65504);
            // The light's ceiling stays below the batch clamp: a pixel can reach it.
            assert!(splat_light_ceiling(None) < ceiling(batch));
        }
        assert_eq!(splat_light_ceiling(Some(64.0)), 64 * LIGHT_UNITS);
        assert_eq!(splat_light_ceiling(None), 65504 * LIGHT_UNITS);
        // Out of range (validation refuses it) is held to [1, 65504], never wraps.
        assert_eq!(splat_light_ceiling(Some(1e9)), 65504 * LIGHT_UNITS);
        assert_eq!(splat_light_ceiling(Some(0.0)), LIGHT_UNITS);
    }
}
