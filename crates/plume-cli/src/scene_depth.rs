//! The depth a `SceneDepth` collider meets where the command draws no scene of its own
//! (`plume run`, `plume bench`, `plume render --draw compute`): the effect's scene meshes drawn
//! once from the effect's camera.

use plume_runtime::outputs::Scene;
use plume_runtime::{Camera, Effect, Gpu, RuntimeError};

/// For an effect with a `SceneDepth` collider, its scene drawn from `camera` at `size` and
/// bound to it; returns the scene, to keep alive while the effect runs. Says so on stderr when
/// there is nothing to meet.
pub fn bind_effect_scene(
    gpu: &Gpu,
    sim: &mut Effect,
    camera: &Camera,
    size: (u32, u32),
) -> Result<Option<Scene>, RuntimeError> {
    if !sim.collides_with_scene_depth() {
        return Ok(None);
    }
    let triangles: Vec<_> = (0..sim.group_names().len())
        .filter_map(|g| sim.group_compiled(g).ok())
        .flat_map(|c| c.ir.scene_triangles())
        .collect();
    let Some(scene) = Scene::depth_only(gpu, &triangles, camera, size)? else {
        eprintln!(
            "note: SceneDepth: the effect names no meshes, so its particles meet nothing here (give it `scene: [Mesh(file: ..)]`, or give a host's depth to Effect::set_scene_depth)"
        );
        return Ok(None);
    };
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    sim.set_scene_depth(
        &mut encoder,
        scene.depth_texture(),
        camera.view,
        camera.proj,
    )?;
    gpu.queue.submit([encoder.finish()]);
    eprintln!(
        "scene depth: {} triangles drawn from the effect's camera at {} x {}",
        triangles.len(),
        size.0,
        size.1
    );
    Ok(Some(scene))
}
