//! The 16-bit float conversions a half-motion layout's loads and stores use, written with
//! integer operations (see each function).

use crate::base::writer::Writer;

/// `half_to_f32(bits)`: the 16-bit float in the low half of `bits` (a half-motion layout's
/// loads). Written with integer operations rather than `unpack2x16float`, which naga admits
/// only with a capability that some adapters lack (llvmpipe's Vulkan without shader-f16).
pub(crate) fn emit_half_unpack(w: &mut Writer) {
    w.block("fn half_to_f32(bits: u32) -> f32", |w| {
        w.line("let sign = (bits & 0x8000u) << 16u;");
        w.line("let exponent = (bits >> 10u) & 0x1fu;");
        w.line("let mantissa = bits & 0x3ffu;");
        w.comment(
            "Normal halves rebias the exponent (15 to 127); subnormals are mantissa · 2^-24.",
        );
        w.line("let normal = bitcast<f32>(sign | ((exponent + 112u) << 23u) | (mantissa << 13u));");
        w.line("let subnormal = bitcast<f32>(sign | bitcast<u32>(f32(mantissa) * 5.9604645e-8));");
        w.line("return select(normal, subnormal, exponent == 0u);");
    });
}

/// `f32_to_half(x)`: `x` as a 16-bit float's bits, rounded to nearest even, its magnitude
/// clamped to f16's largest finite value (65504) so that a store never makes an infinity
/// (a NaN's bits clamp to it too).
pub(super) fn emit_half_pack(w: &mut Writer) {
    w.block("fn f32_to_half(x: f32) -> u32", |w| {
        w.line("let bits = bitcast<u32>(x);");
        w.line("let sign = (bits >> 16u) & 0x8000u;");
        w.line("let magnitude = min(bits & 0x7fffffffu, 0x477fe000u);");
        w.comment("At or above 2^-14 a normal half: rebias (127 to 15) and round off 13 bits.");
        w.line("let rebiased = magnitude - 0x38000000u;");
        w.line("let normal = (rebiased + 0xfffu + ((rebiased >> 13u) & 1u)) >> 13u;");
        w.comment("Below it a subnormal half: x · 2^24 rounded to an integer (exact in f32).");
        w.line("let subnormal = u32(round(bitcast<f32>(magnitude) * 16777216.0));");
        w.line("return sign | select(subnormal, normal, magnitude >= 0x38800000u);");
    });
}
