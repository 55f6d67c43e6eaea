//! Reading trails back (`render.trail`): each live particle's ribbon points as the GPU's ring
//! holds them, decoded with the same window and ownership test the trail draw uses. Tests
//! compare them with the f64 reference's (`ReferenceSim::trails`); drawing never reads back.

use glam::DVec3;

use crate::error::RuntimeError;
use crate::instance::EffectInstance;
use crate::readback::read_buffer;

/// Each live particle's trail in id order: its id and the ribbon's points, its position now
/// and then the samples the ring holds for it, newest first. Empty for an effect without a
/// trail.
pub fn read_trails(instance: &EffectInstance) -> Result<Vec<(u32, Vec<DVec3>)>, RuntimeError> {
    let effect = instance.effect();
    let Some(trail) = &effect.ir.render.trail else {
        return Ok(Vec::new());
    };
    let slots = instance.records_by_slot()?;
    let window: Vec<(u64, u64)> = trail.window(instance.steps_done()).collect();
    let mut out = Vec::new();
    for chunk in instance.resources().chunks(effect)? {
        let ring = chunk
            .trail
            .as_ref()
            .expect("the chunks of an effect with a trail hold rings");
        let bytes = read_buffer(instance.gpu(), ring)?;
        let word = |at: usize| {
            u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]])
        };
        for i in 0..chunk.len {
            let Some(record) = &slots[(chunk.base + i) as usize] else {
                continue;
            };
            let mut points = vec![record.position];
            // The particle's samples are the newest ones: stop at the first it does not own.
            for &(_, entry) in &window {
                let at = ((i * u64::from(trail.ring()) + entry) * 16) as usize;
                if word(at + 12) != record.id.wrapping_add(1) {
                    break;
                }
                let x = [0, 4, 8].map(|o| f64::from(f32::from_bits(word(at + o))));
                points.push(DVec3::from_array(x));
            }
            out.push((record.id, points));
        }
    }
    out.sort_by_key(|(id, _)| *id);
    Ok(out)
}
