//! The WGSL twin of the scene depth collider's swept test and push-out (see the parent module),
//! reading the `scene_depth` texture and the `scene_camera` words.

use super::{SceneDepthIr, BISECTIONS, DEPTH_ULPS, MAX_SAMPLES, TINY_W, VIEW_ROUNDING};
use crate::base::writer::{f32_lit, Writer};

impl SceneDepthIr {
    /// The WGSL twins of [`SceneDepthIr::hit`] and [`SceneDepthIr::push_out`], reading the
    /// `scene_depth` texture and the `scene_camera` words.
    pub fn emit(&self, w: &mut Writer, i: usize) {
        let thickness = f32_lit(self.thickness);
        let mat = |first: usize| {
            format!(
                "mat4x4<f32>(scene_camera[{}], scene_camera[{}], scene_camera[{}], scene_camera[{}])",
                first,
                first + 1,
                first + 2,
                first + 3
            )
        };
        let (view, proj, inv_proj, inv_view) = (mat(1), mat(5), mat(9), mat(13));
        w.comment("The view-space surface point of pixel p, w = 1 when there is one.");
        w.block(format!("fn sd{i}_surface(p: vec2<i32>) -> vec4<f32>"), |w| {
            w.line("let size = vec2<i32>(scene_camera[0].xy);");
            w.block("if (any(p < vec2<i32>(0)) || any(p >= size))", |w| {
                w.line("return vec4<f32>(0.0);")
            });
            w.line("let d = textureLoad(scene_depth, p, 0).r;");
            w.block("if (!(d > 0.0 && d < 1.0))", |w| {
                w.line("return vec4<f32>(0.0);")
            });
            w.line("let sz = scene_camera[0].xy;");
            w.line("let ndc = vec2<f32>((f32(p.x) + 0.5) / sz.x * 2.0 - 1.0, 1.0 - (f32(p.y) + 0.5) / sz.y * 2.0);");
            w.line(format!("let u = {inv_proj} * vec4<f32>(ndc, d, 1.0);"));
            w.block(format!("if (!(abs(u.w) > {}))", f32_lit(TINY_W)), |w| {
                w.line("return vec4<f32>(0.0);")
            });
            w.line("return vec4<f32>(u.xyz / u.w, 1.0);");
        });
        w.comment("The view-space point of x and its NDC (x, y); w = 0 when behind the camera.");
        w.block(format!("fn sd{i}_project(x: vec3<f32>) -> array<vec4<f32>, 2>"), |w| {
            w.line(format!("let v = ({view} * vec4<f32>(x, 1.0)).xyz;"));
            w.line(format!("let c = {proj} * vec4<f32>(v, 1.0);"));
            w.block(format!("if (!(c.w > {}))", f32_lit(TINY_W)), |w| {
                w.line("return array<vec4<f32>, 2>(vec4<f32>(v, 0.0), vec4<f32>(0.0));")
            });
            w.line("return array<vec4<f32>, 2>(vec4<f32>(v, 1.0), vec4<f32>(c.xy / c.w, 0.0, 0.0));");
        });
        w.comment("The depth of pixel p clamped to the image; -1 where it is empty.");
        w.block(format!("fn sd{i}_depth(p: vec2<i32>) -> f32"), |w| {
            w.line("let size = vec2<i32>(scene_camera[0].xy);");
            w.line("let d = textureLoad(scene_depth, clamp(p, vec2<i32>(0), size - vec2<i32>(1)), 0).r;");
            w.line("return select(-1.0, d, d > 0.0 && d < 1.0);");
        });
        w.comment("Where x is: (view point, 1 when it meets a surface), (surface point on its ray, nearest pixel x), (ndc, nearest pixel y).");
        w.block(format!("fn sd{i}_place(x: vec3<f32>) -> array<vec4<f32>, 3>"), |w| {
            w.line(format!("let pr = sd{i}_project(x);"));
            w.line("let none = array<vec4<f32>, 3>(vec4<f32>(pr[0].xyz, 0.0), vec4<f32>(0.0), vec4<f32>(0.0));");
            w.block("if (pr[0].w == 0.0)", |w| w.line("return none;"));
            w.line("let n = pr[1].xy;");
            w.block("if (!(abs(n.x) < 1.0 && abs(n.y) < 1.0))", |w| {
                w.line("return none;")
            });
            w.line("let sz = scene_camera[0].xy;");
            w.line("let f = vec2<f32>((n.x * 0.5 + 0.5) * sz.x - 0.5, (0.5 - n.y * 0.5) * sz.y - 0.5);");
            w.line("let near = vec2<i32>(clamp(floor(f + vec2<f32>(0.5)), vec2<f32>(0.0), sz - vec2<f32>(1.0)));");
            w.line("let c0 = floor(f);");
            w.line("let t = f - c0;");
            w.line("let p0 = vec2<i32>(c0);");
            w.line(format!("let a = sd{i}_depth(p0);"));
            w.line(format!("let b = sd{i}_depth(p0 + vec2<i32>(1, 0));"));
            w.line(format!("let c = sd{i}_depth(p0 + vec2<i32>(0, 1));"));
            w.line(format!("let e = sd{i}_depth(p0 + vec2<i32>(1, 1));"));
            w.line("var d = 0.0;");
            w.block("if (min(min(a, b), min(c, e)) >= 0.0)", |w| {
                w.line("let top = a + (b - a) * t.x;");
                w.line("let bottom = c + (e - c) * t.x;");
                w.line("d = top + (bottom - top) * t.y;");
            });
            w.block("else", |w| {
                w.line(format!("d = sd{i}_depth(near);"));
                w.block("if (d < 0.0)", |w| w.line("return none;"));
            });
            w.line(format!("let u = {inv_proj} * vec4<f32>(n, d, 1.0);"));
            w.block(format!("if (!(abs(u.w) > {}))", f32_lit(TINY_W)), |w| {
                w.line("return none;")
            });
            w.line(format!("let u2 = {inv_proj} * vec4<f32>(n, d * {}, 1.0);", f32_lit(1.0 + DEPTH_ULPS)));
            w.line("let s = u.xyz / u.w;");
            w.comment("The surface taken nearer by its rounding (see the reference's Place::behind).");
            w.line(format!(
                "let tolerance = select(0.0, abs(u2.z / u2.w - s.z), abs(u2.w) > {}) + {} * abs(pr[0].z);",
                f32_lit(TINY_W),
                f32_lit(VIEW_ROUNDING)
            ));
            w.line("return array<vec4<f32>, 3>(vec4<f32>(pr[0].xyz, 1.0), vec4<f32>(s.xy, s.z + tolerance, f32(near.x)), vec4<f32>(n, f32(near.y), 0.0));");
        });
        w.comment("The tangent at s from its neighbours plus and minus: the one nearer in depth.");
        w.block(
            format!("fn sd{i}_tangent(s: vec3<f32>, plus: vec4<f32>, minus: vec4<f32>) -> vec4<f32>"),
            |w| {
                w.block("if (plus.w != 0.0 && minus.w != 0.0)", |w| {
                    w.line("return select(vec4<f32>(s - minus.xyz, 1.0), vec4<f32>(plus.xyz - s, 1.0), abs(plus.z - s.z) <= abs(s.z - minus.z));");
                });
                w.block("if (plus.w != 0.0)", |w| {
                    w.line("return vec4<f32>(plus.xyz - s, 1.0);")
                });
                w.block("if (minus.w != 0.0)", |w| {
                    w.line("return vec4<f32>(s - minus.xyz, 1.0);")
                });
                w.line("return vec4<f32>(0.0);");
            },
        );
        w.block(
            format!("fn sd{i}_normal(s_in: vec3<f32>, p: vec2<i32>, toward: vec3<f32>) -> vec3<f32>"),
            |w| {
                w.line(format!("let centre = sd{i}_surface(p);"));
                w.line("let s = select(s_in, centre.xyz, centre.w != 0.0);");
                w.line(format!(
                    "let tx = sd{i}_tangent(s, sd{i}_surface(p + vec2<i32>(1, 0)), sd{i}_surface(p - vec2<i32>(1, 0)));"
                ));
                w.line(format!(
                    "let ty = sd{i}_tangent(s, sd{i}_surface(p + vec2<i32>(0, 1)), sd{i}_surface(p - vec2<i32>(0, 1)));"
                ));
                w.line("let to_eye = toward - s;");
                w.line("var n = select(to_eye, cross(tx.xyz, ty.xyz), tx.w != 0.0 && ty.w != 0.0);");
                w.line("n = select(n, -n, dot(n, to_eye) < 0.0);");
                w.line(format!("let iv = {inv_view};"));
                w.line("let world = mat3x3<f32>(iv[0].xyz, iv[1].xyz, iv[2].xyz) * n;");
                w.line("let l = length(world);");
                w.line("let back = iv[2].xyz / max(length(iv[2].xyz), 1e-30);");
                w.line("return select(back, world / l, l > 1e-30 && l < 3.0e38);");
            },
        );
        w.block(
            format!("fn collider_hit_{i}(a: vec3<f32>, b: vec3<f32>) -> vec4<f32>"),
            |w| {
                w.line("let none = vec4<f32>(2.0, 0.0, 1.0, 0.0);");
                w.block("if (scene_camera[0].x < 1.0)", |w| w.line("return none;"));
                w.line("let sz = scene_camera[0].xy;");
                w.line(format!("let pa = sd{i}_project(a);"));
                w.line(format!("let pb = sd{i}_project(b);"));
                w.line(format!("var samples = {MAX_SAMPLES}u;"));
                w.block("if (pa[0].w != 0.0 && pb[0].w != 0.0)", |w| {
                    w.line("let px = max(abs((pb[1].x - pa[1].x) * 0.5 * sz.x), abs((pb[1].y - pa[1].y) * 0.5 * sz.y));");
                    w.line(format!(
                        "samples = u32(clamp(ceil(px), 1.0, {}));",
                        f32_lit(f64::from(MAX_SAMPLES))
                    ));
                });
                w.line(format!("var prev = sd{i}_place(a);"));
                w.line("var prev_t = 0.0;");
                w.block("for (var k = 1u; k <= samples; k++)", |w| {
                    w.line("let t = f32(k) / f32(samples);");
                    w.line(format!("let cur = sd{i}_place(a + (b - a) * t);"));
                    w.block("if (prev[0].w != 0.0 && cur[0].w != 0.0)", |w| {
                        w.line("let deeper = max(prev[0].z - cur[0].z, 0.0);");
                        w.line("let behind_prev = prev[1].z - prev[0].z;");
                        w.line("let behind_cur = cur[1].z - cur[0].z;");
                        w.block(
                            format!("if (behind_prev < 0.0 && behind_cur >= 0.0 && behind_cur <= {thickness} + deeper)"),
                            |w| {
                                w.line("var lo = prev_t;");
                                w.line("var hi = t;");
                                w.line("var front = prev;");
                                w.block(format!("for (var j = 0u; j < {BISECTIONS}u; j++)"), |w| {
                                    w.line("let mid = 0.5 * (lo + hi);");
                                    w.line(format!("let m = sd{i}_place(a + (b - a) * mid);"));
                                    w.block("if (m[0].w != 0.0 && m[1].z - m[0].z >= 0.0)", |w| {
                                        w.line("hi = mid;")
                                    });
                                    w.block("else", |w| {
                                        w.line("lo = mid;");
                                        w.block("if (m[0].w != 0.0)", |w| w.line("front = m;"));
                                    });
                                });
                                w.line(format!(
                                    "return vec4<f32>(lo, sd{i}_normal(front[1].xyz, vec2<i32>(i32(front[1].w), i32(front[2].z)), pa[0].xyz));"
                                ));
                            },
                        );
                    });
                    w.line("prev = cur;");
                    w.line("prev_t = t;");
                });
                w.line("return none;");
            },
        );
        w.block(
            format!("fn collider_push_{i}(x: vec3<f32>, margin: f32) -> vec3<f32>"),
            |w| {
                w.block("if (scene_camera[0].x < 1.0)", |w| w.line("return x;"));
                w.line(format!("let p = sd{i}_place(x);"));
                w.block("if (p[0].w == 0.0)", |w| w.line("return x;"));
                w.line("let behind = p[1].z - p[0].z;");
                w.block(
                    format!("if (!(behind >= 0.0 && behind <= {thickness}))"),
                    |w| w.line("return x;"),
                );
                w.line(format!("let ip = {inv_proj};"));
                w.line("let h0 = ip * vec4<f32>(p[2].xy, 0.25, 1.0);");
                w.line("let h1 = ip * vec4<f32>(p[2].xy, 0.75, 1.0);");
                let tiny = f32_lit(TINY_W);
                w.block(
                    format!("if (!(abs(h0.w) > {tiny} && abs(h1.w) > {tiny}))"),
                    |w| w.line("return x;"),
                );
                w.line("let ray = h1.xyz / h1.w - h0.xyz / h0.w;");
                w.block(format!("if (!(abs(ray.z) > {tiny}))"), |w| {
                    w.line("return x;")
                });
                w.line("let moved = p[0].xyz + ray * ((behind + margin) / ray.z);");
                w.line(format!("return ({inv_view} * vec4<f32>(moved, 1.0)).xyz;"));
            },
        );
    }
}
