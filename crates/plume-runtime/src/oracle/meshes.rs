//! The reference drawing of mesh particles (`render.mesh`), beside [`crate::oracle::sprites`]:
//! each sprite's mesh placed on the CPU in f64 by `MeshIr::placed`, its back faces dropped, each
//! vertex coloured as the sprite and, for a lit look, lit there by its triangle's normal (the
//! effect's lights, `Lights::received`, `Lit::shade`), drawn as triangles by the strip shader.

use glam::DVec3;
use plume_compiler::ir::EffectIr;

use crate::draw::camera::Camera;
use crate::oracle::sprites::Sprite;
use crate::oracle::strips::StripVertex;

/// The triangles of `sprites`' meshes (in their order, each mesh's in the file's) as seen by
/// `camera`: the faces turned toward the viewer, lit as the look says. Empty without a mesh.
pub fn mesh_triangles(sprites: &[Sprite], ir: &EffectIr, camera: &Camera) -> Vec<StripVertex> {
    let Some(mesh) = &ir.render.mesh else {
        return Vec::new();
    };
    let view = camera.view.as_dmat4();
    let inverse = view.inverse();
    let eye = inverse.transform_point3(DVec3::ZERO);
    // An orthographic projection looks along the view's -z everywhere.
    let orthographic = camera.proj.w_axis.w == 1.0;
    let toward_viewer = inverse.transform_vector3(DVec3::Z);
    let d = |v: [f32; 3]| DVec3::new(v[0].into(), v[1].into(), v[2].into());
    let mut out = Vec::new();
    for s in sprites {
        // What the draw hides: no opacity, or for premultiplied colour nothing at all.
        if ir.render.blend.hides(s.color.map(f64::from)) {
            continue;
        }
        let rgb = d([s.color[0], s.color[1], s.color[2]]);
        for (corners, normal) in mesh.placed(d(s.center), (d(s.half_x), d(s.half_y))) {
            let winding = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
            let viewer = match orthographic {
                true => toward_viewer,
                false => eye - corners[0],
            };
            // The raster pipeline culls back faces (and those edge-on).
            if winding.dot(viewer) <= 0.0 {
                continue;
            }
            for p in corners {
                let c = match &ir.render.lit {
                    Some(lit) => lit.shade(rgb, ir.lights.received(normal, p, lit.wrap)),
                    None => rgb,
                };
                out.push(StripVertex {
                    position: [p.x as f32, p.y as f32, p.z as f32],
                    across: 0.0,
                    color: [c.x as f32, c.y as f32, c.z as f32, s.color[3]],
                });
            }
        }
    }
    out
}
