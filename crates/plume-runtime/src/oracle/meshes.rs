//! The reference drawing of mesh particles (`render.mesh`), beside [`crate::oracle::sprites`]:
//! each sprite's mesh placed on the CPU in f64 by `MeshIr::placed`, its back faces dropped, each
//! vertex coloured as the sprite, drawn as triangles by the strip shader. The GPU lights a lit
//! mesh per pixel; here each lit triangle is cut into n² smaller ones ([`pieces_per_edge`]),
//! each corner lit by the triangle's normal (the effect's lights, `Lights::received`,
//! `Lit::shade`), so that the colours the strip shader blends between follow the light across
//! the face.

use glam::DVec3;
use plume_compiler::ir::EffectIr;
use plume_compiler::lights::{LightSource, Lights};

use crate::draw::camera::Camera;
use crate::oracle::sprites::Sprite;
use crate::oracle::strips::StripVertex;

/// The pieces each edge of a lit triangle `t` is cut into, n: one where the light is the same
/// across it (directional and ambient light, no shadow); else enough that a piece's longest
/// edge is at most an eighth of its distance from the nearest point light (and at least 4 with
/// a shadow map), at most 16. A point light's inverse square then changes by at most about a
/// quarter across a piece, which a straight blend follows within the tests' 8-bit tolerance.
pub(crate) fn pieces_per_edge(lights: &Lights, t: &[DVec3; 3]) -> usize {
    let edge = (0..3)
        .map(|k| t[k].distance(t[(k + 1) % 3]))
        .fold(0.0, f64::max);
    let middle = (t[0] + t[1] + t[2]) / 3.0;
    let nearest = lights
        .sources
        .iter()
        .filter_map(|s| match s {
            LightSource::Point { position, .. } => Some(position.distance(middle) - edge),
            LightSource::Directional { .. } => None,
        })
        .fold(f64::INFINITY, f64::min);
    let by_light = match nearest.is_finite() {
        true => (8.0 * edge / nearest.max(1e-3)).ceil().clamp(1.0, 16.0) as usize,
        false => 1,
    };
    match lights.shadow {
        Some(_) => by_light.max(4),
        None => by_light,
    }
}

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
            let vertex = |p: DVec3| {
                let c = match &ir.render.lit {
                    Some(lit) => lit.shade(rgb, ir.lights.received(normal, p, lit.wrap)),
                    None => rgb,
                };
                StripVertex {
                    position: [p.x as f32, p.y as f32, p.z as f32],
                    across: 0.0,
                    color: [c.x as f32, c.y as f32, c.z as f32, s.color[3]],
                }
            };
            match ir.render.lit {
                Some(_) => {
                    out.extend(grid(corners, pieces_per_edge(&ir.lights, &corners)).map(vertex))
                }
                None => out.extend(corners.map(vertex)),
            }
        }
    }
    out
}

/// Triangle `t` cut into n² triangles wound as it is: their corners, three each.
fn grid(t: [DVec3; 3], n: usize) -> impl Iterator<Item = DVec3> {
    let at = move |i: usize, j: usize| {
        t[0] + (t[1] - t[0]) * (i as f64 / n as f64) + (t[2] - t[0]) * (j as f64 / n as f64)
    };
    (0..n).flat_map(move |j| {
        (0..n - j).flat_map(move |i| {
            // The piece with its corner at (i, j), and the one above its far edge.
            let up = [at(i, j), at(i + 1, j), at(i, j + 1)];
            let down = (i + j + 1 < n).then(|| [at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
            up.into_iter().chain(down.into_iter().flatten())
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grid_covers_its_triangle_once_wound_the_same_way() {
        let t = [
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 3.0, 0.0),
        ];
        let n = 5;
        let corners: Vec<DVec3> = grid(t, n).collect();
        assert_eq!(corners.len(), 3 * n * n);
        let area = |c: &[DVec3]| (c[1] - c[0]).cross(c[2] - c[0]).z / 2.0;
        // Every piece inside the triangle, with the same winding and an n²th of its area: so
        // they tile it.
        let inside = |p: DVec3| p.x >= 0.0 && p.y >= 0.0 && p.x / 2.0 + p.y / 3.0 <= 1.0 + 1e-12;
        for piece in corners.chunks(3) {
            assert!(piece.iter().all(|p| inside(*p)), "{piece:?}");
            let want = area(&t) / (n * n) as f64;
            assert!((area(piece) - want).abs() < 1e-12, "{piece:?}");
        }
    }
}
