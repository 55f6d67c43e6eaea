//! Reading trails back (`render.trail`): each live particle's ribbon points as the GPU's ring
//! holds them, decoded with the same window and ownership test the trail draw uses. Tests
//! compare them with the f64 reference's (`ReferenceSim::trails`); drawing never reads back.

use glam::DVec3;

use crate::device::readback::read_buffer;
use crate::error::RuntimeError;
use crate::sim::effect::Effect;

/// Each live particle's trail in id order (of the top-level group): its id and the ribbon's points, its position now
/// and then the samples the ring holds for it, newest first. Empty for an effect without a
/// trail.
///
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use plume_compiler::reference::ReferenceSim;
/// use plume_runtime::{oracle::read_trails, Effect, Gpu};
/// let source = r#"Effect(name: "comet", capacity: 1,
///     emitters: [Emitter(burst: 1, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((1.0, 0.0, 0.0)))],
///     render: Render(trail: Some(Trail(points: 4))))"#;
/// let effect = plume_compiler::compile_str(source, &Default::default())?;
/// let gpu = Gpu::new(&Default::default())?;
/// let mut comet = Effect::new(&gpu, effect.clone())?;
/// comet.run(10, |_| {})?;
/// let mut reference = ReferenceSim::new(&effect.ir);
/// reference.run(10);
/// let (gpu_trail, cpu_trail) = (read_trails(&comet)?, reference.trails());
/// // Now, and the positions 1, 2 and 3 steps ago.
/// assert_eq!(gpu_trail[0].1.len(), 4);
/// for (g, c) in gpu_trail[0].1.iter().zip(&cpu_trail[0].1) {
///     assert!((*g - *c).length() < 1e-5);
/// }
/// # Ok(())
/// # }
/// ```
pub fn read_trails(effect: &Effect) -> Result<Vec<(u32, Vec<DVec3>)>, RuntimeError> {
    let group = &effect.groups()[0];
    let effect = &group.effect;
    let Some(trail) = &effect.ir.render.trail else {
        return Ok(Vec::new());
    };
    let slots = group.records_by_slot()?;
    let window: Vec<(u64, u64)> = trail.window(group.steps_done()).collect();
    let mut out = Vec::new();
    for chunk in group.chunks()? {
        let ring = chunk
            .trail
            .as_ref()
            .expect("the chunks of an effect with a trail hold rings");
        let bytes = read_buffer(&group.gpu, ring)?;
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
