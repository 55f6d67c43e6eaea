//! The WGSL twin of the scene depth collider's swept test and push-out (see the parent module),
//! reading the `scene_depth` buffer and the `scene_camera` uniform ([`super::at`] says where
//! each matrix is).

use super::{
    at, SceneDepthIr, BISECTIONS, CONTACT_PRECISION, DEPTH_ULPS, MAX_SAMPLES, TINY_W, VIEW_ROUNDING,
};
use crate::base::writer::{f32_lit, Writer};

/// `mat4x4<f32>` of the four vec4s from `first` of the camera.
fn mat(first: usize) -> String {
    format!(
        "mat4x4<f32>(scene_camera[{}], scene_camera[{}], scene_camera[{}], scene_camera[{}])",
        first,
        first + 1,
        first + 2,
        first + 3
    )
}

impl SceneDepthIr {
    /// The WGSL twins of [`SceneDepthIr::hit`] and `push_out`.
    pub fn emit(&self, w: &mut Writer, i: usize) {
        let thickness = f32_lit(self.thickness);
        let tiny = f32_lit(TINY_W);
        let size = format!("scene_camera[{}].xy", at::SIZE);
        let ip = at::INVERSE_PROJECTION;
        w.comment("The view-space surface point of pixel p, w = 1 when there is one.");
        w.block(format!("fn sd{i}_surface(p: vec2<i32>) -> vec4<f32>"), |w| {
            w.line(format!("let sz = {size};"));
            w.block("if (any(p < vec2<i32>(0)) || any(p >= vec2<i32>(sz)))", |w| {
                w.line("return vec4<f32>(0.0);")
            });
            w.line("let d = scene_depth[u32(p.y) * u32(sz.x) + u32(p.x)];");
            w.block("if (!(d > 0.0 && d < 1.0))", |w| {
                w.line("return vec4<f32>(0.0);")
            });
            w.line("let ndc = vec2<f32>((f32(p.x) + 0.5) / sz.x * 2.0 - 1.0, 1.0 - (f32(p.y) + 0.5) / sz.y * 2.0);");
            w.line(format!("let u = {} * vec4<f32>(ndc, d, 1.0);", mat(ip)));
            w.block(format!("if (!(abs(u.w) > {tiny}))"), |w| {
                w.line("return vec4<f32>(0.0);")
            });
            w.line("return vec4<f32>(u.xyz / u.w, 1.0);");
        });
        w.comment("The depth of pixel p clamped to the image; -1 where it is empty.");
        w.block(format!("fn sd{i}_depth(p: vec2<i32>) -> f32"), |w| {
            w.line(format!("let sz = vec2<i32>({size});"));
            w.line("let q = clamp(p, vec2<i32>(0), sz - vec2<i32>(1));");
            w.line("let d = scene_depth[u32(q.y * sz.x + q.x)];");
            w.line("return select(-1.0, d, d > 0.0 && d < 1.0);");
        });
        w.comment("Where x is: (ndc, view depth, 0 behind the camera / 1 no surface / 2 a surface), (the surface's view depth taken nearer by its rounding, nearest pixel).");
        w.block(format!("fn sd{i}_place(x: vec3<f32>) -> array<vec4<f32>, 2>"), |w| {
            w.line("let p = vec4<f32>(x, 1.0);");
            w.line(format!("let c = {} * p;", mat(at::VIEW_PROJECTION)));
            w.line(format!("let depth = -dot(scene_camera[{}], p);", at::VIEW_ROW_Z));
            w.block(format!("if (!(c.w > {tiny}))"), |w| {
                w.line("return array<vec4<f32>, 2>(vec4<f32>(0.0, 0.0, depth, 0.0), vec4<f32>(0.0));")
            });
            w.line("let n = c.xy / c.w;");
            w.line("let none = array<vec4<f32>, 2>(vec4<f32>(n, depth, 1.0), vec4<f32>(0.0));");
            w.block("if (!(abs(n.x) < 1.0 && abs(n.y) < 1.0))", |w| {
                w.line("return none;")
            });
            w.line(format!("let sz = {size};"));
            w.line("let f = vec2<f32>((n.x * 0.5 + 0.5) * sz.x - 0.5, (0.5 - n.y * 0.5) * sz.y - 0.5);");
            w.line("let near = vec2<i32>(clamp(floor(f + vec2<f32>(0.5)), vec2<f32>(0.0), sz - vec2<f32>(1.0)));");
            w.line("let c0 = floor(f);");
            w.line("let t = f - c0;");
            w.line("let p0 = vec2<i32>(c0);");
            w.line(format!("let a = sd{i}_depth(p0);"));
            w.line(format!("let b = sd{i}_depth(p0 + vec2<i32>(1, 0));"));
            w.line(format!("let e = sd{i}_depth(p0 + vec2<i32>(0, 1));"));
            w.line(format!("let g = sd{i}_depth(p0 + vec2<i32>(1, 1));"));
            w.line("var d = 0.0;");
            w.block("if (min(min(a, b), min(e, g)) >= 0.0)", |w| {
                w.line("let top = a + (b - a) * t.x;");
                w.line("let bottom = e + (g - e) * t.x;");
                w.line("d = top + (bottom - top) * t.y;");
            });
            w.block("else", |w| {
                w.line(format!("d = sd{i}_depth(near);"));
                w.block("if (d < 0.0)", |w| w.line("return none;"));
            });
            w.comment("Only the unprojection's z and w: rows 2 and 3 of the inverse projection.");
            w.line(format!(
                "let zw = scene_camera[{}].zw * n.x + scene_camera[{}].zw * n.y + scene_camera[{}].zw * d + scene_camera[{}].zw;",
                ip,
                ip + 1,
                ip + 2,
                ip + 3
            ));
            w.block(format!("if (!(abs(zw.y) > {tiny}))"), |w| w.line("return none;"));
            w.comment("What 8 ulps of depth are worth there (see the reference's Place::behind).");
            w.line(format!(
                "let zw2 = zw + (d * {}) * scene_camera[{}].zw;",
                f32_lit(DEPTH_ULPS),
                ip + 2
            ));
            w.line(format!(
                "let rounding = select(0.0, abs(zw2.x / zw2.y - zw.x / zw.y), abs(zw2.y) > {tiny});"
            ));
            w.line(format!(
                "let surface = -zw.x / zw.y - rounding - {} * abs(depth);",
                f32_lit(VIEW_ROUNDING)
            ));
            w.line("return array<vec4<f32>, 2>(vec4<f32>(n, depth, 2.0), vec4<f32>(surface, f32(near.x), f32(near.y), 0.0));");
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
        w.comment("The world normal of the surface at pixel p, facing toward (view space).");
        w.block(
            format!("fn sd{i}_normal(p: vec2<i32>, toward: vec3<f32>) -> vec3<f32>"),
            |w| {
                w.line(format!("let iv = {};", mat(at::INVERSE_VIEW)));
                w.line("let back = iv[2].xyz / max(length(iv[2].xyz), 1e-30);");
                w.line(format!("let centre = sd{i}_surface(p);"));
                w.block("if (centre.w == 0.0)", |w| w.line("return back;"));
                w.line("let s = centre.xyz;");
                w.line(format!(
                    "let tx = sd{i}_tangent(s, sd{i}_surface(p + vec2<i32>(1, 0)), sd{i}_surface(p - vec2<i32>(1, 0)));"
                ));
                w.line(format!(
                    "let ty = sd{i}_tangent(s, sd{i}_surface(p + vec2<i32>(0, 1)), sd{i}_surface(p - vec2<i32>(0, 1)));"
                ));
                w.line("let to_eye = toward - s;");
                w.line("var n = select(to_eye, cross(tx.xyz, ty.xyz), tx.w != 0.0 && ty.w != 0.0);");
                w.line("n = select(n, -n, dot(n, to_eye) < 0.0);");
                w.line("let world = mat3x3<f32>(iv[0].xyz, iv[1].xyz, iv[2].xyz) * n;");
                w.line("let l = length(world);");
                w.line("return select(back, world / l, l > 1e-30 && l < 3.0e38);");
            },
        );
        w.block(
            format!("fn collider_hit_{i}(a: vec3<f32>, b: vec3<f32>) -> vec4<f32>"),
            |w| {
                w.line("let none = vec4<f32>(2.0, 0.0, 1.0, 0.0);");
                w.block(format!("if (scene_camera[{}].x < 1.0)", at::SIZE), |w| {
                    w.line("return none;")
                });
                w.line(format!("let sz = {size};"));
                w.line(format!("let pa = sd{i}_place(a);"));
                w.line(format!("let pb = sd{i}_place(b);"));
                w.line(format!("var samples = {MAX_SAMPLES}u;"));
                w.block("if (pa[0].w >= 1.0 && pb[0].w >= 1.0)", |w| {
                    w.line("let px = max(abs((pb[0].x - pa[0].x) * 0.5 * sz.x), abs((pb[0].y - pa[0].y) * 0.5 * sz.y));");
                    w.line(format!(
                        "samples = u32(clamp(ceil(px), 1.0, {}));",
                        f32_lit(f64::from(MAX_SAMPLES))
                    ));
                });
                w.line("var prev = pa;");
                w.line("var prev_t = 0.0;");
                w.block("for (var k = 1u; k <= samples; k++)", |w| {
                    w.line("let t = f32(k) / f32(samples);");
                    w.line("var cur = pb;");
                    w.block("if (k < samples)", |w| {
                        w.line(format!("cur = sd{i}_place(a + (b - a) * t);"))
                    });
                    w.block("if (prev[0].w == 2.0 && cur[0].w == 2.0)", |w| {
                        w.line("let deeper = max(cur[0].z - prev[0].z, 0.0);");
                        w.line("let behind_prev = prev[0].z - prev[1].x;");
                        w.line("let behind_cur = cur[0].z - cur[1].x;");
                        w.block(
                            format!("if (behind_prev < 0.0 && behind_cur >= 0.0 && behind_cur <= {thickness} + deeper)"),
                            |w| {
                                w.line("var lo = prev_t;");
                                w.line("var hi = t;");
                                w.line("var front = prev;");
                                w.line(format!(
                                    "let enough = {} * max(pa[0].z, 0.0) / max(length(b - a), 1e-30);",
                                    f32_lit(CONTACT_PRECISION)
                                ));
                                w.block(format!("for (var j = 0u; j < {BISECTIONS}u && hi - lo > enough; j++)"), |w| {
                                    w.line("let mid = 0.5 * (lo + hi);");
                                    w.line(format!("let m = sd{i}_place(a + (b - a) * mid);"));
                                    w.block("if (m[0].w == 2.0 && m[0].z - m[1].x >= 0.0)", |w| {
                                        w.line("hi = mid;")
                                    });
                                    w.block("else", |w| {
                                        w.line("lo = mid;");
                                        w.block("if (m[0].w == 2.0)", |w| w.line("front = m;"));
                                    });
                                });
                                w.line(format!(
                                    "let toward = ({} * vec4<f32>(a, 1.0)).xyz;",
                                    mat(at::VIEW)
                                ));
                                w.line(format!(
                                    "return vec4<f32>(lo, sd{i}_normal(vec2<i32>(front[1].yz), toward));"
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
                w.block(format!("if (scene_camera[{}].x < 1.0)", at::SIZE), |w| {
                    w.line("return x;")
                });
                w.line(format!("let p = sd{i}_place(x);"));
                w.block("if (p[0].w != 2.0)", |w| w.line("return x;"));
                w.line("let behind = p[0].z - p[1].x;");
                w.block(
                    format!("if (!(behind >= 0.0 && behind <= {thickness}))"),
                    |w| w.line("return x;"),
                );
                w.line(format!("let ip = {};", mat(ip)));
                w.line("let h0 = ip * vec4<f32>(p[0].xy, 0.25, 1.0);");
                w.line("let h1 = ip * vec4<f32>(p[0].xy, 0.75, 1.0);");
                w.block(
                    format!("if (!(abs(h0.w) > {tiny} && abs(h1.w) > {tiny}))"),
                    |w| w.line("return x;"),
                );
                w.line("let ray = h1.xyz / h1.w - h0.xyz / h0.w;");
                w.block(format!("if (!(abs(ray.z) > {tiny}))"), |w| {
                    w.line("return x;")
                });
                w.line(format!(
                    "let view = ({} * vec4<f32>(x, 1.0)).xyz;",
                    mat(at::VIEW)
                ));
                w.line("let moved = view + ray * ((behind + margin) / ray.z);");
                w.line(format!(
                    "return ({} * vec4<f32>(moved, 1.0)).xyz;",
                    mat(at::INVERSE_VIEW)
                ));
            },
        );
    }
}
