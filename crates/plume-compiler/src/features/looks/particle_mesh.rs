//! Mesh particles (`render.mesh`): each particle drawn as a triangle mesh read from an OBJ file
//! instead of a sprite. The mesh sits in the sprite's own frame: its x along the quad's first
//! axis, y along the second, z along their cross product, so `orient`, `rotation`, `size` and
//! `size_y` place, turn and scale it as they would the quad (one unit of the mesh is the
//! particle's width along x and z, its height along y). Colour and opacity are the sprite's;
//! with `render.lit` each triangle is lit by its own face normal, per pixel (Lambert's law,
//! `wrap` and `emissive` as for lit sprites), which the reference drawing does in f64 at a
//! grid of points over each triangle.
//!
//! The draw module's `vs_mesh` draws an instance per particle, its vertices read from a
//! storage buffer (binding [`MESH_VERTICES_BINDING`]) as [`MeshIr::buffers`] lays them out,
//! drawn indexed: each distinct corner once in the buffer, an index per triangle corner, so a
//! corner that several triangles share can be shaded once (the GPU's vertex reuse; the draw of
//! many mesh particles is bound by its vertices, see docs/performance.md). So a vertex has no
//! one face: `fs_mesh` finds a lit triangle's normal from how the view-space point changes
//! from pixel to pixel (`dpdx`, `dpdy`: both lie in the triangle's plane), turned toward the
//! viewer, and lights the pixel there. The raster pipeline culls the back faces (OBJ winds triangles counter-clockwise seen from
//! outside). Particles are drawn in slot order, or back to front
//! with `sort: true`; no depth is written, so meshes of one group cross over each other only as
//! that order says. The compute renderer draws solid meshes (`Opaque`, `Mask`) its own way
//! ([`super::mesh_splat`]).

use std::path::Path;
use std::sync::Arc;

use glam::DVec3;
use serde::Deserialize;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::writer::{u32_lit, Writer};

/// `render.mesh`: the particles drawn as this mesh.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticleMesh {
    /// The OBJ file, relative to the effect file's directory.
    pub file: String,
}

/// Binding of the mesh's vertices in the draw module.
pub const MESH_VERTICES_BINDING: u32 = 28;

/// The most triangles a particle's mesh may have: every particle draws all of them.
pub(crate) const TRIANGLES_MOST: usize = 1 << 16;

/// What a mesh look leaves out: (the `render` field, what it would draw).
pub(crate) const CLASHES: [(&str, &str); 4] = [
    ("trail", "trails"),
    ("texture", "texture"),
    ("ribbon", "ribbons"),
    ("soft", "soft fade"),
];

/// A mesh's vertex and index buffers, as the draw reads them ([`MeshIr::buffers`]).
#[derive(Clone, Debug, PartialEq)]
pub struct MeshBuffers {
    /// The storage buffer's words, as f32: per distinct corner its position (w 0).
    pub vertex_words: Vec<f32>,
    /// The index buffer: three corners per triangle.
    pub indices: Vec<u32>,
}

impl MeshBuffers {
    /// Indices a particle draws: three per triangle.
    pub fn draw_count(&self) -> u32 {
        self.indices.len() as u32
    }
}

/// The mesh, loaded.
#[derive(Clone, PartialEq)]
pub struct MeshIr {
    /// The file as the effect names it.
    pub file: String,
    /// Each triangle's corners in the mesh's own frame, counter-clockwise seen from outside.
    pub triangles: Arc<[[DVec3; 3]]>,
    /// Why the file could not be read, for an effect compiled to be stepped, not drawn
    /// (`CompileOptions::step_only`): a draw refuses with this message.
    pub missing: Option<String>,
}

impl std::fmt::Debug for MeshIr {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:?}: {} triangles", self.file, self.triangles.len())?;
        match &self.missing {
            Some(_) => write!(f, " (missing)"),
            None => Ok(()),
        }
    }
}

impl ParticleMesh {
    /// Checks that the look names a file and draws nothing a mesh leaves out: `set(field)`
    /// says whether the group's `render.FIELD` is given. `render` is the look's path.
    pub(crate) fn check(&self, render: &ValuePath, set: &dyn Fn(&str) -> bool, c: &mut Checker) {
        if self.file.trim().is_empty() {
            c.error(
                &render.field("mesh").field("file"),
                "names no file; give an OBJ file's path relative to the effect file",
            );
        }
        for (field, what) in CLASHES {
            if set(field) {
                c.error(
                    &render.field(field),
                    format!("a group drawn as meshes (render.mesh) draws no {what}; leave {field} out or draw sprites"),
                );
            }
        }
    }
}

impl MeshIr {
    /// Reads the mesh `spec` names; the error says what is wrong with the file, for
    /// `render.mesh.file`.
    pub fn load(spec: &ParticleMesh, base_dir: Option<&Path>) -> Result<Self, String> {
        let path = crate::features::looks::texture::resolve(&spec.file, base_dir);
        let (mesh, _) = crate::base::mesh::read_mesh(&path)?;
        if mesh.triangles.len() > TRIANGLES_MOST {
            return Err(format!(
                "mesh `{}` has {} triangles; a particle's mesh may have at most {TRIANGLES_MOST}, as every particle draws them all: simplify it",
                path.display(),
                mesh.triangles.len()
            ));
        }
        let corners = |t: &[u32; 3]| t.map(|i| mesh.vertices[i as usize]);
        Ok(Self {
            file: spec.file.clone(),
            triangles: mesh.triangles.iter().map(corners).collect(),
            missing: None,
        })
    }

    /// The mesh `spec` names, standing in for a file that could not be read (`missing` says
    /// why): no triangles.
    pub(crate) fn stand_in(spec: &ParticleMesh, missing: String) -> Self {
        Self {
            file: spec.file.clone(),
            triangles: Arc::new([]),
            missing: Some(missing),
        }
    }

    /// The vertex and index buffers the draw module that `emit_draw` writes reads: corners
    /// merged where their f32 positions are equal, in the order the triangles first name them.
    pub fn buffers(&self) -> MeshBuffers {
        let f32s = |p: DVec3| [p.x as f32, p.y as f32, p.z as f32];
        let mut index_of = std::collections::HashMap::new();
        let mut words = Vec::new();
        let mut indices = Vec::with_capacity(self.triangles.len() * 3);
        for p in self.triangles.iter().flatten() {
            let p = f32s(*p);
            let next = index_of.len() as u32;
            let i = *index_of.entry(p.map(f32::to_bits)).or_insert_with(|| {
                words.extend([p[0], p[1], p[2], 0.0]);
                next
            });
            indices.push(i);
        }
        MeshBuffers {
            vertex_words: words,
            indices,
        }
    }

    /// The mesh placed for a sprite of centre `center` and half axes `half_x`, `half_y`: each
    /// triangle's corners and its unit normal (zero for a degenerate one), in the space of
    /// those. The f64 twin of `vs_mesh`'s placement.
    pub fn placed(
        &self,
        center: DVec3,
        (half_x, half_y): (DVec3, DVec3),
    ) -> impl Iterator<Item = ([DVec3; 3], DVec3)> + '_ {
        let (ax, ay) = (2.0 * half_x, 2.0 * half_y);
        let az = ax.cross(ay).normalize_or_zero() * ax.length();
        // Normals go by the inverse transpose: each axis over its length squared.
        let inv = |a: DVec3| match a.length_squared() {
            l2 if l2 > 1e-30 => a / l2,
            _ => DVec3::ZERO,
        };
        let (nx, ny, nz) = (inv(ax), inv(ay), inv(az));
        self.triangles.iter().map(move |t| {
            let n = face_normal(t);
            let corners = t.map(|m| center + m.x * ax + m.y * ay + m.z * az);
            let normal = (n.x * nx + n.y * ny + n.z * nz).normalize_or_zero();
            (corners, normal)
        })
    }

    /// Emits the mesh's vertex buffer and `vs_mesh` / `fs_mesh`: an instance per particle
    /// (`sprite_at`), its mesh placed in the sprite's frame (`oriented`: from its half axes;
    /// else upright facing the camera), each vertex coloured as the sprite; when `lit`, each
    /// pixel lit by its triangle's normal (`lit_color`, `received_light` in scope; a shadow
    /// looked up once a particle at its centre where the look says so), written through
    /// `blend`.
    pub(crate) fn emit_draw(
        &self,
        w: &mut Writer,
        oriented: bool,
        lit: Option<&crate::features::looks::lit::Lit>,
        blend: crate::features::looks::Blend,
    ) {
        let per_particle_shadow = lit.is_some_and(|l| l.shadow_per_particle());
        w.comment(format!(
            "render.mesh {:?}: {} triangles drawn indexed, each distinct corner's position.",
            self.file,
            self.triangles.len()
        ));
        w.line(format!(
            "@group(0) @binding({MESH_VERTICES_BINDING}) var<storage, read> mesh_vertices: array<vec4<f32>>;"
        ));
        let corners = self.buffers().vertex_words.len() / 4;
        w.line(format!(
            "const MESH_VERTICES: u32 = {};",
            u32_lit(corners as u32)
        ));
        w.blank();
        w.block("struct MeshVertex", |w| {
            w.line("@builtin(position) clip: vec4<f32>,");
            w.line("@location(0) color: vec4<f32>,");
            if lit.is_some() {
                w.line("@location(1) at: vec3<f32>,");
            }
            if per_particle_shadow {
                w.line("@location(2) @interpolate(flat) shadow: f32,");
            }
        });
        w.blank();
        w.comment("Instance i: particle i's mesh, in its sprite's frame scaled by its size.");
        w.line("@vertex");
        w.block(
            "fn vs_mesh(@builtin(vertex_index) vertex: u32, @builtin(instance_index) instance: u32) -> MeshVertex",
            |w| {
                w.line("var out: MeshVertex;");
                w.line("out.clip = HIDDEN;");
                w.line("out.color = vec4<f32>(0.0);");
                w.line("let s = sprite_at(instance);");
                w.block("if (!s.visible || vertex >= MESH_VERTICES)", |w| {
                    w.line("return out;")
                });
                emit_mesh_axes(w, oriented);
                w.line("let m = mesh_vertices[vertex].xyz;");
                w.line("let p = s.center.xyz + m.x * ax + m.y * ay + m.z * az;");
                w.line("out.clip = draw.proj * vec4<f32>(p, 1.0);");
                w.line("out.color = s.color;");
                if lit.is_some() {
                    w.line("out.at = p;");
                }
                if per_particle_shadow {
                    w.line("out.shadow = shadow_visibility(s.center.xyz);");
                }
                w.line("return out;");
            },
        );
        w.blank();
        w.line("@fragment");
        let Some(_) = lit else {
            w.block(
                "fn fs_mesh(in: MeshVertex) -> @location(0) vec4<f32>",
                |w| w.line(format!("return {};", blend.strip_out_wgsl("1.0"))),
            );
            return;
        };
        w.block(
            "fn fs_mesh(vertex: MeshVertex) -> @location(0) vec4<f32>",
            |w| {
                w.comment("The triangle's normal: the point's steps to the next pixels both lie in its plane. Back faces are culled, so it faces the viewer: the way to the eye, or +z for an orthographic view.");
                w.line("let across = cross(dpdx(vertex.at), dpdy(vertex.at));");
                w.line("let toward = select(-vertex.at, vec3<f32>(0.0, 0.0, 1.0), draw.proj[3][3] == 1.0);");
                w.line("let facing = select(-across, across, dot(across, toward) >= 0.0);");
                w.line("let unit = facing * inverseSqrt(max(dot(facing, facing), 1e-30));");
                if per_particle_shadow {
                    w.line("particle_shadow = vertex.shadow;");
                }
                w.line("var in = vertex;");
                w.line("in.color = lit_color(vertex.color, received_light(unit, vertex.at));");
                w.line(format!("return {};", blend.strip_out_wgsl("1.0")));
            },
        );
    }
}

/// `ax`, `ay`, `az`: the mesh's axes for sprite `s`, in the sprite's frame scaled by its size
/// (`oriented`: from its half axes; else upright facing the camera), z along their cross
/// product as long as x. Shared by `vs_mesh` and the compute renderer's `mesh_place`.
pub(crate) fn emit_mesh_axes(w: &mut Writer, oriented: bool) {
    match oriented {
        true => {
            w.line("let ax = 2.0 * s.half_x;");
            w.line("let ay = 2.0 * s.half_y;");
        }
        false => {
            w.line("let ax = vec3<f32>(s.size, 0.0, 0.0);");
            w.line("let ay = vec3<f32>(0.0, s.size, 0.0);");
        }
    }
    w.line("let across = cross(ax, ay);");
    w.line("let az = across * (length(ax) * inverseSqrt(max(dot(across, across), 1e-30)));");
}

/// A triangle's unit normal by the right-hand rule (counter-clockwise corners face it); zero
/// for a triangle of no area.
pub(crate) fn face_normal(t: &[DVec3; 3]) -> DVec3 {
    (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_triangle() -> MeshIr {
        MeshIr {
            file: "t.obj".into(),
            triangles: Arc::new([[DVec3::ZERO, DVec3::X, DVec3::Y]]),
            missing: None,
        }
    }

    #[test]
    fn a_placed_mesh_follows_the_sprites_axes_and_size() {
        // A quad 2 m wide and 4 m high turned a quarter about z: x along y, y along -x.
        let half = (DVec3::new(0.0, 1.0, 0.0), DVec3::new(-2.0, 0.0, 0.0));
        let mesh = one_triangle();
        let (corners, normal) = mesh.placed(DVec3::new(1.0, 1.0, 1.0), half).next().unwrap();
        assert_eq!(corners[0], DVec3::new(1.0, 1.0, 1.0));
        assert_eq!(corners[1], DVec3::new(1.0, 3.0, 1.0));
        assert_eq!(corners[2], DVec3::new(-3.0, 1.0, 1.0));
        // The triangle faces +z in its frame; the frame's z is x × y = +z here.
        assert!((normal - DVec3::Z).length() < 1e-12, "{normal}");
    }

    #[test]
    fn normals_stay_at_right_angles_to_a_stretched_face() {
        // A face slanted across x and y, stretched 4x along y: the normal must stay
        // perpendicular to the stretched face, not be stretched with it.
        let mesh = MeshIr {
            triangles: Arc::new([[DVec3::ZERO, DVec3::new(1.0, -1.0, 0.0), DVec3::Z]]),
            ..one_triangle()
        };
        let half = (DVec3::new(0.5, 0.0, 0.0), DVec3::new(0.0, 2.0, 0.0));
        let (c, n) = mesh.placed(DVec3::ZERO, half).next().unwrap();
        assert!(n.dot(c[1] - c[0]).abs() < 1e-12 && n.dot(c[2] - c[0]).abs() < 1e-12);
        assert!((n.length() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_zero_size_places_a_point_with_no_normal_and_no_nan() {
        let mesh = one_triangle();
        let (c, n) = mesh
            .placed(DVec3::ONE, (DVec3::ZERO, DVec3::ZERO))
            .next()
            .unwrap();
        assert!(c.iter().all(|p| *p == DVec3::ONE));
        assert_eq!(n, DVec3::ZERO);
    }

    #[test]
    fn a_mesh_holds_each_distinct_corner_once_and_indexes_them() {
        // Two triangles sharing the edge from x to y: four distinct corners.
        let mesh = MeshIr {
            triangles: Arc::new([
                [DVec3::ZERO, DVec3::X, DVec3::Y],
                [DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
            ]),
            ..one_triangle()
        };
        let buffers = mesh.buffers();
        assert_eq!(buffers.indices, [0, 1, 2, 1, 3, 2]);
        assert_eq!(buffers.draw_count(), 6);
        assert_eq!(buffers.vertex_words.len(), 16);
        assert_eq!(&buffers.vertex_words[12..16], &[1.0, 1.0, 0.0, 0.0]);
        // Each index names the corner the triangle has there.
        for (corner, &i) in mesh.triangles.iter().flatten().zip(&buffers.indices) {
            let at = &buffers.vertex_words[4 * i as usize..4 * i as usize + 3];
            assert_eq!(at, &[corner.x as f32, corner.y as f32, corner.z as f32]);
        }
    }
}
