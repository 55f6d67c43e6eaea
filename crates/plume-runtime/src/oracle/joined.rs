//! The reference drawing of ribbons that join particles (`render.ribbon`), beside
//! [`crate::oracle::strips`]' trails: the chains the table joins
//! ([`plume_compiler::ribbon::Ribbon::chains`], f64), each point where its particle's sprite
//! would be, as wide and of the colour the sprite would have ([`crate::oracle::sprites`]), its
//! vertices placed on the CPU in f64, drawn by the reference ribbon shader. And the GPU's table
//! read back, to compare with the reference simulator's.

use plume_compiler::passes::layout::Role;
use std::collections::HashMap;

use glam::{DVec3, Vec3};
use plume_compiler::ir::EffectIr;
use plume_compiler::reference::ParticleRecord;
use plume_compiler::ribbon::{Link, Table};

use crate::draw::camera::Camera;
use crate::error::RuntimeError;
use crate::oracle::strips::{push_triangles, strip_color, StripVertex};
use crate::sim::effect::Effect;

/// One entry of the GPU's ribbon table: the id and link of the particle that wrote it last,
/// and the slot it was given.
pub(crate) type GpuEntry = Option<(u32, Link, u32)>;

/// Group `g`'s ribbon table as the GPU holds it, per entry (None where no spawn has written).
/// An error for a group without ribbons.
///
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use plume_compiler::reference::ReferenceSim;
/// use plume_runtime::{oracle::read_ribbon_table, Effect, Gpu};
/// let source = r#"Effect(name: "stream", capacity: 16,
///     emitters: [Emitter(rate: 60.0, shape: Custom("vec3(t, 0.0, 0.0)"),
///                        velocity: Constant((0.0, 0.0, 0.0)), lifetime: Some((0.1, 0.1)))],
///     render: Render(ribbon: Some(Ribbon(points: 8))))"#;
/// let effect = plume_compiler::compile_str(source, &Default::default())?;
/// let gpu = Gpu::new(&Default::default())?;
/// let mut stream = Effect::new(&gpu, effect.clone())?;
/// stream.run(5, |_| {})?;
/// let mut reference = ReferenceSim::new(&effect.ir);
/// reference.run(5);
/// // The same ids and links in every entry, the GPU's slots aside.
/// let on_gpu: Vec<_> = read_ribbon_table(&stream, 0)?
///     .into_iter()
///     .map(|e| e.map(|(id, link, _slot)| (id, link)))
///     .collect();
/// assert_eq!(&on_gpu, reference.ribbon_table());
/// assert_eq!(on_gpu.iter().flatten().count(), 5);
/// # Ok(())
/// # }
/// ```
pub fn read_ribbon_table(effect: &Effect, g: usize) -> Result<Vec<GpuEntry>, RuntimeError> {
    let bytes = effect.group(g)?.read_extra_buffer(Role::RibbonTable)?;
    let word =
        |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    Ok((0..bytes.len() / 16)
        .map(|e| {
            let [slot, id_1, key, ordinal] = std::array::from_fn(|j| word(16 * e + 4 * j));
            // The id is stored plus one: 0 was never written.
            (id_1 != 0).then_some((id_1.wrapping_sub(1), Link { key, ordinal }, slot))
        })
        .collect())
}

/// The joined ribbons of the particles `records` (all of one group, live), whose spawns wrote
/// `table`, as the GPU's `vs_ribbon` draws them for `camera` at simulation time `time`: a triangle list, two triangles a
/// segment. A point's half width is its sprite's half size, its colour the sprite's; its
/// direction runs from the point before it to the point after it in its chain (itself at an
/// end), and its vertices lie half a width to either side across that direction and the line
/// of sight.
pub fn ribbon_strips(
    records: &[ParticleRecord],
    table: &Table,
    ir: &EffectIr,
    (camera, time): (&Camera, f64),
) -> Vec<StripVertex> {
    let Some(ribbon) = &ir.render.ribbon else {
        return Vec::new();
    };
    // Each live particle's sprite: centre, half width, colour; None when it would not show.
    let shown: HashMap<u32, (DVec3, f64, [f32; 4])> = records
        .iter()
        .filter_map(|r| {
            let s = crate::oracle::sprites_at(std::slice::from_ref(r), ir, camera, false, time)
                .pop()?;
            let half = f64::from(Vec3::from(s.half_x).length());
            (s.color[3] > 0.0 && half > 0.0).then_some((r.id, (r.position, half, s.color)))
        })
        .collect();
    let eye = camera
        .view
        .as_dmat4()
        .inverse()
        .transform_point3(DVec3::ZERO);
    let mut out = Vec::new();
    for chain in ribbon.chains(table, &|id| shown.contains_key(&id)) {
        let points: Vec<(DVec3, f64, [f32; 4])> = chain.iter().map(|id| shown[id]).collect();
        let centres: Vec<DVec3> = points.iter().map(|p| p.0).collect();
        let sides = plume_compiler::trail::strip_sides(&centres, eye, &|j| points[j].1);
        let normals = plume_compiler::trail::strip_normals(&centres, eye);
        push_triangles(&mut out, &sides, &|j| {
            let c = points[j].2.map(f64::from);
            strip_color(ir, c, normals[j], centres[j])
        });
    }
    out
}
