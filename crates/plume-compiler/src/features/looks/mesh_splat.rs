//! Mesh particles drawn by the compute renderer: solid meshes (`blend: Opaque` or `Mask`),
//! rasterised in compute shaders into a visibility buffer, then shaded once a pixel. The
//! raster pipeline's draw of the same meshes (`vs_mesh`, `fs_mesh`: [`super::particle_mesh`])
//! writes depth into the offscreen target, so the nearest triangle shows; here:
//!
//! - `mesh_clear`: every pixel's depth to the far plane, its pick to none;
//! - `mesh_place`: each particle's frame (centre, the mesh's three axes, colour) from
//!   `sprite_at`, as `vs_mesh` places the mesh; hidden particles (and, for `Mask`, those
//!   below the cutoff, which `fs_mesh` discards whole) get none;
//! - `mesh_raster`, twice (a uniform's phase): a thread per (particle, triangle) in draw
//!   order (a workgroup per triangle for big ones, `mesh_raster_big`) covers the pixel
//!   centres inside the triangle (culling back faces, clipped to the near and far planes as
//!   the raster pipeline clips), first keeping each pixel's least
//!   depth (`atomicMin` on the f32's bits, which order as the depths do), then, where its
//!   depth is the one kept, the least (draw position, triangle) there, so a tie goes to the
//!   first drawn as the raster pipeline's `Less` test leaves it. One kernel for both phases,
//!   so both compute each depth with the same instructions;
//! - `mesh_shade`: a thread per pixel shades the picked triangle at the pixel's centre (the
//!   view-space point interpolated perspective-correct, the triangle's face normal turned to
//!   the viewer, as `fs_mesh` finds it from `dpdx` and `dpdy`) and writes the image, or the
//!   background where nothing covers it and this part owns the image.
//!
//! Over a host's image (the embedding API's compute renderer) the image holds light and
//! coverage as f16 pairs, each pixel is tested against the host's depth as its depth test
//! would test a fragment, and with reversed Z (a `Greater` test) the nearest depth is the
//! largest: the kept depth is then the greatest and the far plane 0.
//!
//! Coverage uses homogeneous edge functions (each corner's clip x, y, w): a pixel centre is
//! inside when its three weights are positive, and the weights are the perspective-correct
//! barycentrics up to one factor, so no division by a corner's w is needed and a triangle
//! crossing the eye plane needs no clipping; its pixel box comes from the triangle clipped to
//! the clip volume's depth range (0 <= z <= w).

use super::lit::Lit;
use super::particle_mesh::{emit_mesh_axes, MeshIr, MESH_VERTICES_BINDING};
use super::Blend;
use crate::base::writer::{f32_lit, u32_lit, Writer};

/// The compute mesh kernels' own bindings: the parameters (uniform: width, height, particles,
/// background, phase), the triangles' corner indices, the particles' frames, each pixel's
/// depth and pick, the image (one RGBA8 word a pixel, or a host's two), and the list of big
/// triangles (a count, then ids). The corners are read from [`MESH_VERTICES_BINDING`], as the
/// raster draw reads them.
pub const MESH_SPLAT_BINDINGS: [u32; 7] = [56, 57, 58, 59, 60, 61, 62];

/// Pixels in a triangle's box past which a workgroup covers it (`mesh_raster_big`), not one
/// thread.
pub(crate) const BIG_TRIANGLE_PIXELS: u32 = 256;

/// 32-bit words of one particle's frame in the compute mesh draw: centre (w: 1 shown, 0
/// hidden), the mesh's x, y and z axes, and the colour.
pub const MESH_FRAME_WORDS: u64 = 20;

/// How the compute mesh draw meets a host's image (the embedding API's compute renderer): it
/// writes premultiplied light and coverage as f16 pairs, keeps the nearest particle by the
/// host's depth convention, and tests each pixel against the host's depth.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MeshHost {
    /// Reversed Z: the nearest depth is the largest, the far plane 0.
    pub(crate) reversed: bool,
    /// The host's depth test, a WGSL condition on a pixel's depth `z` and the host's `scene`;
    /// None when the host draws without depth.
    pub(crate) passes: Option<&'static str>,
    /// The binding of the host's depth (one f32 a pixel).
    pub(crate) depth_binding: u32,
}

/// Why the compute renderer cannot draw a mesh look blended by `blend`; `None` when it can.
pub(crate) fn refusal(blend: Blend) -> Option<&'static str> {
    (!matches!(blend, Blend::Opaque | Blend::Mask(_)))
        .then_some("the compute renderer draws solid mesh particles only (blend: Opaque or Mask)")
}

/// Emits the compute mesh kernels (module doc) into the draw module, after `sprite_at`:
/// `oriented` as `vs_mesh` places the mesh, `lit` with `lit_color` and `received_light` in
/// scope, the particles' alpha tested against a `Mask` cutoff.
pub(crate) fn emit_mesh_splat(
    w: &mut Writer,
    mesh: &MeshIr,
    (oriented, lit, blend): (bool, Option<&Lit>, Blend),
    (hdr, host): (bool, Option<&MeshHost>),
) {
    let [params, indices, frames, depth, pick, image, big] = MESH_SPLAT_BINDINGS;
    let reversed = host.is_some_and(|h| h.reversed);
    let triangles = mesh.triangles.len() as u32;
    w.comment(format!(
        "render.mesh {:?} drawn by the compute renderer: {triangles} triangles a particle.",
        mesh.file
    ));
    w.block("struct MeshSplat", |w| {
        w.line("width: u32,");
        w.line("height: u32,");
        w.line("count: u32,");
        w.comment(
            "RGBA8; alpha 0: the parts before drew the image, leave it where nothing covers.",
        );
        w.line("background: u32,");
        w.comment("mesh_raster: 0 keeps the least depth, 1 the first triangle at it.");
        w.line("phase: u32,");
    });
    w.block("struct MeshFrame", |w| {
        w.line("center: vec4<f32>,");
        w.line("ax: vec4<f32>,");
        w.line("ay: vec4<f32>,");
        w.line("az: vec4<f32>,");
        w.line("color: vec4<f32>,");
    });
    w.line(format!(
        "@group(0) @binding({MESH_VERTICES_BINDING}) var<storage, read> mesh_vertices: array<vec4<f32>>;"
    ));
    w.line(format!(
        "@group(0) @binding({params}) var<uniform> mesh_splat: MeshSplat;"
    ));
    w.line(format!(
        "@group(0) @binding({indices}) var<storage, read> mesh_indices: array<u32>;"
    ));
    w.line(format!(
        "@group(0) @binding({frames}) var<storage, read_write> mesh_frames: array<MeshFrame>;"
    ));
    w.line(format!(
        "@group(0) @binding({depth}) var<storage, read_write> mesh_depth: array<atomic<u32>>;"
    ));
    w.line(format!(
        "@group(0) @binding({pick}) var<storage, read_write> mesh_pick: array<atomic<u32>>;"
    ));
    match hdr {
        false => w.line(format!(
            "@group(0) @binding({image}) var<storage, read_write> mesh_image: array<u32>;"
        )),
        true => {
            w.comment("An HDR image (a host's, or a glowing effect's): per pixel (r, g) and (b, coverage) as f16 pairs, rows of the width rounded up to 32.");
            w.line(format!(
                "@group(0) @binding({image}) var<storage, read_write> mesh_image: array<vec2<u32>>;"
            ));
        }
    }
    if let Some(h) = host.filter(|h| h.passes.is_some()) {
        w.comment("The host's depth, one f32 a pixel (a copy of its depth image).");
        w.line(format!(
            "@group(0) @binding({}) var<storage, read> host_depth: array<f32>;",
            h.depth_binding
        ));
    }
    w.comment("The big triangles mesh_raster lists for mesh_raster_big: how many it met (the list may hold fewer), and their ids.");
    w.block("struct MeshBig", |w| {
        w.line("count: atomic<u32>,");
        w.line("ids: array<u32>,");
    });
    w.line(format!(
        "@group(0) @binding({big}) var<storage, read_write> mesh_big: MeshBig;"
    ));
    w.line(format!(
        "const MESH_TRIANGLES: u32 = {};",
        u32_lit(triangles)
    ));
    w.comment(
        "The far plane's depth, as the raster draw's depth buffer is cleared (0 with reversed Z).",
    );
    w.line(format!(
        "const MESH_FAR: u32 = {};",
        if reversed { "0u" } else { "0x3f800000u" }
    ));
    w.line("const MESH_NONE: u32 = 0xffffffffu;");
    w.blank();
    emit_place(w, oriented, blend);
    w.blank();
    emit_cover(w);
    w.blank();
    emit_raster(w, reversed, host.and_then(|h| h.passes));
    w.blank();
    emit_shade(w, lit, hdr, host.is_some());
}

/// `mesh_clear` and `mesh_place` (a thread per pixel, a thread per particle).
fn emit_place(w: &mut Writer, oriented: bool, blend: Blend) {
    w.line("@compute @workgroup_size(256)");
    w.block(
        "fn mesh_clear(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            w.line("let pixel = gid.x + gid.y * groups.x * 256u;");
            w.block("if (pixel >= mesh_splat.width * mesh_splat.height)", |w| {
                w.line("return;")
            });
            w.line("atomicStore(&mesh_depth[pixel], MESH_FAR);");
            w.line("atomicStore(&mesh_pick[pixel], MESH_NONE);");
            w.block("if (pixel == 0u)", |w| w.line("atomicStore(&mesh_big.count, 0u);"));
        },
    );
    w.blank();
    w.comment(
        "Particle i's mesh frame, as vs_mesh places the mesh; centre w 0 when it draws nothing.",
    );
    w.line("@compute @workgroup_size(256)");
    w.block(
        "fn mesh_place(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            w.line("let i = gid.x + gid.y * groups.x * 256u;");
            w.block("if (i >= mesh_splat.count)", |w| w.line("return;"));
            w.line("var f: MeshFrame;");
            w.line("f.center = vec4<f32>(0.0);");
            w.line("let s = sprite_at(i);");
            let shows = match blend {
                Blend::Mask(cutoff) => format!("s.visible && s.color.a >= {}", f32_lit(cutoff)),
                _ => "s.visible".to_string(),
            };
            w.block(format!("if ({shows})"), |w| {
                emit_mesh_axes(w, oriented);
                w.line("f.center = vec4<f32>(s.center.xyz, 1.0);");
                w.line("f.ax = vec4<f32>(ax, 0.0);");
                w.line("f.ay = vec4<f32>(ay, 0.0);");
                w.line("f.az = vec4<f32>(az, 0.0);");
                w.line("f.color = s.color;");
            });
            w.line("mesh_frames[i] = f;");
        },
    );
}

/// `mesh_corner`, `mesh_edges` and `mesh_box`: a corner in view space, the triangle's
/// homogeneous edge functions, and the pixels its part in front of the near plane may cover.
fn emit_cover(w: &mut Writer) {
    w.block("fn mesh_corner(f: MeshFrame, k: u32) -> vec3<f32>", |w| {
        w.line("let m = mesh_vertices[mesh_indices[k]].xyz;");
        w.line("return f.center.xyz + m.x * f.ax.xyz + m.y * f.ay.xyz + m.z * f.az.xyz;");
    });
    w.blank();
    w.comment("Rows: each corner's edge function (the cross product of the other two corners' clip x, y, w); a pixel centre (x, y, 1) in NDC weighs corner k by dot(row k, p). Zero rows for a back face or one of no area (the determinant is then not positive).");
    w.block(
        "fn mesh_edges(c0: vec4<f32>, c1: vec4<f32>, c2: vec4<f32>) -> mat3x3<f32>",
        |w| {
            w.line("let e0 = cross(c1.xyw, c2.xyw);");
            w.line("let e1 = cross(c2.xyw, c0.xyw);");
            w.line("let e2 = cross(c0.xyw, c1.xyw);");
            w.block("if (!(dot(c0.xyw, e0) > 0.0))", |w| {
                w.line("return mat3x3<f32>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));")
            });
            w.line("return mat3x3<f32>(e0, e1, e2);");
        },
    );
    w.blank();
    w.comment("Pixel centre (px, py) in NDC.");
    w.block("fn mesh_ndc(px: u32, py: u32) -> vec3<f32>", |w| {
        w.line("let size = vec2<f32>(f32(mesh_splat.width), f32(mesh_splat.height));");
        w.line("let at = (vec2<f32>(f32(px), f32(py)) + 0.5) / size;");
        w.line("return vec3<f32>(at.x * 2.0 - 1.0, 1.0 - at.y * 2.0, 1.0);");
    });
    w.blank();
    w.block("fn mesh_in_depth(c: vec4<f32>) -> bool", |w| {
        w.line("return c.w > 0.0 && c.z >= 0.0 && c.z <= c.w;")
    });
    w.blank();
    w.comment("The first and last pixel (x, y) whose centres the triangle's part inside the clip volume's depth range may cover; first > last when none.");
    w.block(
        "fn mesh_box(c0: vec4<f32>, c1: vec4<f32>, c2: vec4<f32>) -> vec4<i32>",
        |w| {
            w.line("var lo = vec2<f32>(1e30);");
            w.line("var hi = vec2<f32>(-1e30);");
            w.line("let c = array<vec4<f32>, 3>(c0, c1, c2);");
            w.comment("The corners inside the clip volume's depth range (0 <= z <= w), and where each edge crosses either of its planes inside the other; the two planes meet only at w = 0.");
            w.block("for (var k = 0u; k < 3u; k++)", |w| {
                w.line("let a = c[k];");
                w.line("let b = c[(k + 1u) % 3u];");
                w.block("if (mesh_in_depth(a))", |w| {
                    w.line("lo = min(lo, a.xy / a.w);");
                    w.line("hi = max(hi, a.xy / a.w);");
                });
                w.comment("Signed distances to the near-side plane z = 0 and the far-side one z = w.");
                w.line("let da = vec2<f32>(a.z, a.w - a.z);");
                w.line("let db = vec2<f32>(b.z, b.w - b.z);");
                w.block("for (var plane = 0u; plane < 2u; plane++)", |w| {
                    w.block("if ((da[plane] >= 0.0) != (db[plane] >= 0.0))", |w| {
                        w.line("let q = mix(a, b, da[plane] / (da[plane] - db[plane]));");
                        w.block("if (q.w > 0.0 && q.z >= -1e-6 * q.w && q.z <= q.w * (1.0 + 1e-6))", |w| {
                            w.line("lo = min(lo, q.xy / q.w);");
                            w.line("hi = max(hi, q.xy / q.w);");
                        });
                    });
                });
            });
            w.line("let size = vec2<f32>(f32(mesh_splat.width), f32(mesh_splat.height));");
            w.comment("NDC to pixels (y down), then the centres inside: x + 0.5 within [lo, hi].");
            w.line("let plo = (vec2<f32>(lo.x, -hi.y) * 0.5 + 0.5) * size - 0.5;");
            w.line("let phi = (vec2<f32>(hi.x, -lo.y) * 0.5 + 0.5) * size - 0.5;");
            w.line("let first = clamp(ceil(plo), vec2<f32>(0.0), size);");
            w.line("let last = clamp(floor(phi), vec2<f32>(-1.0), size - 1.0);");
            w.line("return vec4<i32>(vec2<i32>(first), vec2<i32>(last));");
        },
    );
}

/// `mesh_triangle`, `mesh_cover` and the two kernels that cover pixels: `mesh_raster`, a
/// thread per (particle, triangle) in draw order, and `mesh_raster_big`, a workgroup per
/// triangle of the list `mesh_raster` leaves it (those whose pixel box passes
/// [`BIG_TRIANGLE_PIXELS`], so that a mesh close to the camera is not one thread's thousands of
/// pixels). The nearest depth is the least (the largest with `reversed` Z); each pixel is tested
/// against the host's depth where `passes` gives the test.
fn emit_raster(w: &mut Writer, reversed: bool, passes: Option<&str>) {
    w.block("struct MeshTriangle", |w| {
        w.comment(
            "The edge functions (all zero: nothing to draw), corner depths and w, pixel box, id.",
        );
        w.line("e: mat3x3<f32>,");
        w.line("zs: vec3<f32>,");
        w.line("ws: vec3<f32>,");
        w.line("bounds: vec4<i32>,");
        w.line("id: u32,");
    });
    w.blank();
    w.comment("Triangle t of the particle drawn i-th, set up for covering; e all zero when it draws nothing (a hidden particle, a back face).");
    w.block("fn mesh_triangle(i: u32, t: u32) -> MeshTriangle", |w| {
        w.line("var m: MeshTriangle;");
        w.line("m.id = i * MESH_TRIANGLES + t;");
        w.line("let f = mesh_frames[i];");
        w.block("if (f.center.w == 0.0)", |w| w.line("return m;"));
        w.line("let c0 = draw.proj * vec4<f32>(mesh_corner(f, 3u * t), 1.0);");
        w.line("let c1 = draw.proj * vec4<f32>(mesh_corner(f, 3u * t + 1u), 1.0);");
        w.line("let c2 = draw.proj * vec4<f32>(mesh_corner(f, 3u * t + 2u), 1.0);");
        w.line("m.e = mesh_edges(c0, c1, c2);");
        w.line("m.zs = vec3<f32>(c0.z, c1.z, c2.z);");
        w.line("m.ws = vec3<f32>(c0.w, c1.w, c2.w);");
        w.line("m.bounds = mesh_box(c0, c1, c2);");
        w.line("return m;");
    });
    w.blank();
    w.comment("Pixel (px, py) of triangle m: its depth kept if nearest (phase 0), then its id if its depth is the one kept (phase 1).");
    w.block("fn mesh_cover(m: MeshTriangle, px: i32, py: i32)", |w| {
        w.line("let p = mesh_ndc(u32(px), u32(py));");
        w.line("let b = vec3<f32>(dot(m.e[0], p), dot(m.e[1], p), dot(m.e[2], p));");
        w.block("if (any(b < vec3<f32>(0.0)))", |w| w.line("return;"));
        w.line("let depth = dot(b, m.zs) / dot(b, m.ws);");
        w.comment("Inside the clip volume's depth range, and not at the far plane's depth, which the depth buffer's clear holds and a strict test fails.");
        let inside = match reversed {
            false => "depth >= 0.0 && depth < 1.0",
            true => "depth > 0.0 && depth <= 1.0",
        };
        w.block(format!("if (!(dot(b, m.ws) > 0.0) || !({inside}))"), |w| {
            w.line("return;")
        });
        w.line("let pixel = u32(py) * mesh_splat.width + u32(px);");
        if let Some(passes) = passes {
            w.line("let z = depth;");
            w.line("let scene = host_depth[pixel];");
            w.block(format!("if (!({passes}))"), |w| w.line("return;"));
        }
        w.comment("Without the sign, so that -0 orders as 0.");
        w.line("let bits = bitcast<u32>(depth) & 0x7fffffffu;");
        w.block("if (mesh_splat.phase == 0u)", |w| {
            w.line(format!(
                "{}(&mesh_depth[pixel], bits);",
                if reversed { "atomicMax" } else { "atomicMin" }
            ));
        });
        w.block(
            "else if (atomicLoad(&mesh_depth[pixel]) == bits)",
            |w| w.line("atomicMin(&mesh_pick[pixel], m.id);"),
        );
    });
    w.blank();
    w.line("@compute @workgroup_size(256)");
    w.block(
        "fn mesh_raster(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            w.line("let job = gid.x + gid.y * groups.x * 256u;");
            w.line("let i = job / MESH_TRIANGLES;");
            w.block("if (i >= mesh_splat.count)", |w| w.line("return;"));
            w.line("let m = mesh_triangle(i, job % MESH_TRIANGLES);");
            w.block("if (all(m.e[0] == vec3<f32>(0.0)))", |w| w.line("return;"));
            w.line("let span = max(m.bounds.zw - m.bounds.xy + 1, vec2<i32>(0));");
            w.block(format!("if (span.x * span.y > {BIG_TRIANGLE_PIXELS})"), |w| {
                w.comment("A big triangle is mesh_raster_big's, listed in phase 0. Past the list's end it is counted, not drawn: the runtime grows the list by the count and draws the frame again.");
                w.block("if (mesh_splat.phase == 0u)", |w| {
                    w.line("let k = atomicAdd(&mesh_big.count, 1u);");
                    w.block("if (k < arrayLength(&mesh_big.ids))", |w| {
                        w.line("mesh_big.ids[k] = m.id;");
                    });
                });
                w.line("return;");
            });
            w.block("for (var py = m.bounds.y; py <= m.bounds.w; py++)", |w| {
                w.block("for (var px = m.bounds.x; px <= m.bounds.z; px++)", |w| {
                    w.line("mesh_cover(m, px, py);");
                });
            });
        },
    );
    w.blank();
    w.line("@compute @workgroup_size(256)");
    w.block(
        "fn mesh_raster_big(@builtin(local_invocation_index) lane: u32, @builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            w.line("let listed = min(atomicLoad(&mesh_big.count), arrayLength(&mesh_big.ids));");
            w.block("for (var k = group.x; k < listed; k += groups.x)", |w| {
                w.line("let id = mesh_big.ids[k];");
                w.line("let m = mesh_triangle(id / MESH_TRIANGLES, id % MESH_TRIANGLES);");
                w.line("let span = m.bounds.zw - m.bounds.xy + 1;");
                w.line("let n = u32(span.x * span.y);");
                w.block("for (var q = lane; q < n; q += 256u)", |w| {
                    w.line("mesh_cover(m, m.bounds.x + i32(q % u32(span.x)), m.bounds.y + i32(q / u32(span.x)));");
                });
            });
        },
    );
}

/// `mesh_shade`: a thread per pixel, into an 8-bit image, or an HDR one (`hdr`: light and
/// coverage as f16 pairs, unclamped as the raster draw into an HDR target leaves it but for
/// f16's largest finite value), a `host`'s or a glowing effect's.
fn emit_shade(w: &mut Writer, lit: Option<&Lit>, hdr: bool, host: bool) {
    w.line("@compute @workgroup_size(256)");
    w.block(
        "fn mesh_shade(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>)",
        |w| {
            w.line("let pixel = gid.x + gid.y * groups.x * 256u;");
            w.block("if (pixel >= mesh_splat.width * mesh_splat.height)", |w| {
                w.line("return;")
            });
            w.line("let id = atomicLoad(&mesh_pick[pixel]);");
            if hdr {
                w.line("let at_pixel = (pixel / mesh_splat.width) * ((mesh_splat.width + 31u) & ~31u) + pixel % mesh_splat.width;");
            }
            w.block("if (id == MESH_NONE)", |w| {
                // A host's image is cleared each frame; what the parts before drew stays.
                if !host {
                    w.block("if ((mesh_splat.background >> 24u) != 0u)", |w| match hdr {
                        false => w.line("mesh_image[pixel] = mesh_splat.background;"),
                        true => {
                            w.line("let bg = unpack4x8unorm(mesh_splat.background).rgb;");
                            w.line("mesh_image[at_pixel] = vec2<u32>(pack2x16float(bg.rg), pack2x16float(vec2<f32>(bg.b, 1.0)));");
                        }
                    });
                }
                w.line("return;");
            });
            w.line("let f = mesh_frames[id / MESH_TRIANGLES];");
            w.line("var color = f.color;");
            if let Some(lit) = lit {
                if lit.shadow_per_particle() {
                    w.comment("The shadow looked up once a particle, at its centre, as vs_mesh looks it up.");
                    w.line("particle_shadow = shadow_visibility(f.center.xyz);");
                }
                w.line("let t = id % MESH_TRIANGLES;");
                w.line("let p0 = mesh_corner(f, 3u * t);");
                w.line("let p1 = mesh_corner(f, 3u * t + 1u);");
                w.line("let p2 = mesh_corner(f, 3u * t + 2u);");
                w.line("let e = mesh_edges(draw.proj * vec4<f32>(p0, 1.0), draw.proj * vec4<f32>(p1, 1.0), draw.proj * vec4<f32>(p2, 1.0));");
                w.line("let p = mesh_ndc(pixel % mesh_splat.width, pixel / mesh_splat.width);");
                w.line("let b = vec3<f32>(dot(e[0], p), dot(e[1], p), dot(e[2], p));");
                w.comment("The weights are perspective-correct up to their sum.");
                w.line("let at = (b.x * p0 + b.y * p1 + b.z * p2) / max(b.x + b.y + b.z, 1e-30);");
                w.comment("The face normal turned toward the viewer, as fs_mesh finds it.");
                w.line("let across = cross(p1 - p0, p2 - p0);");
                w.line("let toward = select(-at, vec3<f32>(0.0, 0.0, 1.0), draw.proj[3][3] == 1.0);");
                w.line("let facing = select(-across, across, dot(across, toward) >= 0.0);");
                w.line("let unit = facing * inverseSqrt(max(dot(facing, facing), 1e-30));");
                w.line("color = lit_color(color, received_light(unit, at));");
            }
            match hdr {
                false => w.line("mesh_image[pixel] = pack4x8unorm(vec4<f32>(clamp(color.rgb, vec3<f32>(0.0), vec3<f32>(1.0)), 1.0));"),
                true => {
                    w.line("let c = min(color.rgb, vec3<f32>(65504.0));");
                    w.line("mesh_image[at_pixel] = vec2<u32>(pack2x16float(c.rg), pack2x16float(vec2<f32>(c.b, 1.0)));");
                }
            }
        },
    );
}
