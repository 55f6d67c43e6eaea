//! A world-space effect's steps along its entity's motion: when a frame holds several steps
//! (a frame longer than the effect's `dt`, or a warm-up), they are recorded in up to
//! [`MAX_PARTS`] parts, each placed where the entity was at that part's end, interpolated
//! between the last frame's transform and this one's. A fast emitter then leaves a line of
//! particles, not a clump per frame.

use bevy::prelude::*;

/// At most this many parts per frame (each is one `Effect::advance`, with its own upload).
pub(crate) const MAX_PARTS: u64 = 8;

/// Splits `steps` into parts: (steps in the part, the transform its spawns use), in order.
/// The parts' steps add up to `steps`; the last part is at `to`; a part ending at fraction f
/// of the frame is at the interpolation from `from` to `to` at f (translation and scale
/// linearly, rotation along the shortest arc).
pub(crate) fn parts(steps: u64, from: Mat4, to: Mat4) -> Vec<(u64, Mat4)> {
    let count = steps.min(MAX_PARTS);
    let (s0, r0, t0) = from.to_scale_rotation_translation();
    let (s1, r1, t1) = to.to_scale_rotation_translation();
    let mut out = Vec::with_capacity(count as usize);
    let mut done = 0;
    for p in 1..=count {
        let end = steps * p / count;
        let f = end as f32 / steps as f32;
        let at = match p == count {
            true => to,
            false => Mat4::from_scale_rotation_translation(
                s0.lerp(s1, f),
                r0.slerp(r1, f),
                t0.lerp(t1, f),
            ),
        };
        out.push((end - done, at));
        done = end;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_of_steps_is_split_along_the_motion() {
        let from = Mat4::from_translation(Vec3::ZERO);
        let to = Mat4::from_rotation_y(1.0) * Mat4::from_translation(Vec3::new(8.0, 0.0, 0.0));
        for steps in [1, 2, 4, 7, 8, 9, 100] {
            let parts = parts(steps, from, to);
            assert_eq!(
                parts.iter().map(|p| p.0).sum::<u64>(),
                steps,
                "{steps} steps"
            );
            assert!(
                parts.iter().all(|p| p.0 > 0),
                "an empty part at {steps} steps"
            );
            assert_eq!(parts.len() as u64, steps.min(MAX_PARTS));
            assert_eq!(parts.last().unwrap().1, to);
        }
        // Four steps: the parts end at 1/4, 1/2, 3/4 and all of the way.
        let slide = Mat4::from_translation(Vec3::new(8.0, 0.0, 0.0));
        let xs: Vec<f32> = parts(4, from, slide).iter().map(|p| p.1.w_axis.x).collect();
        assert_eq!(xs, [2.0, 4.0, 6.0, 8.0]);
        assert!(parts(0, from, to).is_empty());
    }
}
