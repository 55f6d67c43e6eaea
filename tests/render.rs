//! Drawing on the GPU (llvmpipe in CI): particles drawn straight from the GPU buffers by the
//! generated draw module land where the documented camera projection puts them, match the
//! CPU-fed reference drawing for every example (sorted alpha order included), a stateless
//! effect drawn from its closed form matches the same effect drawn from its evaluated state,
//! the draw is the same whether the state is split across buffers or not, and a known effect
//! matches its golden image.

mod common;

use common::*;
use glam::DVec3;
use plume::compiler::schema::State;
use plume::runtime::bench::{renderer_with, DeadSlots, DrawOptions};
use plume::runtime::oracle;
use plume::runtime::oracle::{sprites, ReferenceRenderer};
use plume::runtime::outputs::ComputeOffscreen;
use plume::runtime::outputs::Offscreen;
use plume::runtime::{Camera, Effect, Gpu};
use plume::{compile_str, CompileOptions, CompiledEffect};

/// Draws `sim` from the effect's camera at `w` x `h` on the GPU path.
fn draw_gpu(sim: &Effect, w: u32, h: u32) -> Vec<u8> {
    let gpu = sim.gpu().clone();
    let target = Offscreen::new(&gpu, w, h).unwrap();
    let renderer = sim.renderer(&target.target()).unwrap();
    target
        .render(sim, &renderer, &target.effect_camera(sim))
        .unwrap()
}

/// The mean per-channel difference of two images beyond one 8-bit step.
fn beyond_one_step(a: &[u8], b: &[u8]) -> f64 {
    let sum: u64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| u64::from(x.abs_diff(*y).saturating_sub(1)))
        .sum();
    sum as f64 / a.len() as f64
}

/// Draws `sim` as [`draw_gpu`] does, but into a 16-bit float target that is rounded to 8 bits
/// once at the end (the glow's HDR image; with nothing bright enough to bloom unless the effect
/// glows): the raster draw without a rounding after every blend, as the compute renderer
/// composites.
fn draw_gpu_hdr(sim: &Effect, w: u32, h: u32) -> Vec<u8> {
    let gpu = sim.gpu().clone();
    let no_bloom = plume::compiler::schema::Glow {
        threshold: 1e30,
        strength: 0.0,
        radius: 0.01,
        clamp: 65504.0,
    };
    // A glowing effect blooms as it does in `plume render`.
    let glow = sim.compiled().ir.render.glow.unwrap_or(no_bloom);
    let target = Offscreen::with_glow(&gpu, w, h, Some(&glow)).unwrap();
    let renderer = sim.renderer(&target.target()).unwrap();
    target
        .render(sim, &renderer, &target.effect_camera(sim))
        .unwrap()
}

/// Draws `sim` with the reference path: particles (and trails) read back, coloured, sized and
/// placed on the CPU in f64, in the order the GPU draw follows (the depth order when sorted,
/// else slot order), ribbons first as the GPU draws them.
fn draw_reference(sim: &Effect, w: u32, h: u32) -> Vec<u8> {
    let ir = &sim.compiled().ir;
    let records = if ir.sort {
        sim.records_in_draw_order().unwrap()
    } else {
        oracle::records_by_slot(sim)
            .unwrap()
            .into_iter()
            .flatten()
            .collect()
    };
    let r = ReferenceRenderer::new(sim.gpu(), w, h, ir).unwrap();
    let camera = Camera::from_effect(&ir.camera, w as f32 / h as f32);
    let trails = plume::runtime::oracle::read_trails(sim).unwrap();
    let ribbons = plume::runtime::oracle::trail_strips(&records, &trails, ir, camera.view);
    r.draw_with_strips(&ribbons, &sprites(&records, ir, &camera, false), &camera)
        .unwrap()
}

/// Every example effect file of one group, in name order (tests/events.rs draws the ones
/// with groups, group by group).
fn examples() -> Vec<std::path::PathBuf> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/effects");
    let mut names: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron") && !is_graph_file(p))
        .collect();
    names.sort();
    names
}

/// Runs `sim` 90 steps (1.5 s), or half its longest lifetime when that is shorter (sparks), so
/// that many particles are on screen and overlap.
fn advance_to_show(mut sim: Effect) -> Effect {
    let ir = &sim.compiled().ir;
    let longest = ir
        .emitters
        .iter()
        .filter_map(|e| e.lifetime_steps)
        .map(|l| l.first + l.span - 1)
        .max();
    let steps = longest.map_or(90, |l| u64::from(l / 2).min(90));
    sim.run(steps, |_| {}).unwrap();
    sim
}

/// Runs `effect` for `steps` on a fresh instance.
fn simulate(gpu: &Gpu, effect: CompiledEffect, steps: u64) -> Effect {
    let mut sim = Effect::new(gpu, effect).unwrap();
    sim.run(steps, |_| {}).unwrap();
    sim
}

/// Whether every pixel of `a` and `b` (`w` wide) that differs by more than `over` in some
/// channel has no such neighbour among its eight.
fn lone_pixels(a: &[u8], b: &[u8], w: u32, over: u8) -> bool {
    let (w, h) = (w as i64, (a.len() / 4) as i64 / w as i64);
    let differs = |x: i64, y: i64| {
        (0..w).contains(&x)
            && (0..h).contains(&y)
            && (0..3).any(|c| {
                let k = (4 * (y * w + x) + c) as usize;
                a[k].abs_diff(b[k]) > over
            })
    };
    (0..h).all(|y| {
        (0..w).all(|x| {
            !differs(x, y)
                || !(-1..=1)
                    .any(|dy| (-1..=1).any(|dx| (dx, dy) != (0, 0) && differs(x + dx, y + dy)))
        })
    })
}

fn pixel(img: &[u8], w: u32, x: u32, y: u32) -> [u8; 4] {
    let i = ((y * w + x) * 4) as usize;
    [img[i], img[i + 1], img[i + 2], img[i + 3]]
}

/// Still particles at the given points, white and opaque, on black.
fn still_points(points: &[DVec3], extra: &str) -> String {
    let list: Vec<String> = points
        .iter()
        .map(|p| format!("({:?}, {:?}, {:?})", p.x, p.y, p.z))
        .collect();
    format!(
        r#"Effect(
    name: "probe",
    capacity: {n},
    emitters: [Emitter(burst: {n}, shape: Points([{list}]), velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (1.0, 2.0, 10.0), target: (0.0, 0.5, 0.0), fov_y: 40.0),
    {extra}
)"#,
        n = points.len(),
        list = list.join(", ")
    )
}

#[test]
fn a_particle_lands_on_the_pixel_the_camera_projection_gives() {
    let gpu = gpu();
    // Several positions (off-axis, nearer and farther than the target), on a non-square image
    // with odd sides. Each is drawn alone, so the lit pixels are its sprite only.
    let points = [
        DVec3::new(-2.0, 1.0, 0.0),
        DVec3::new(1.5, -0.5, 2.0),
        DVec3::new(0.5, 1.2, -3.0),
        DVec3::new(2.6, 2.1, 1.0),
        DVec3::new(0.0, 0.5, 0.0),
    ];
    let (w, h) = (331, 187);
    for p in points {
        let src = still_points(
            &[p],
            "render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 0.12)], background: (0.0, 0.0, 0.0)),",
        );
        let sim = simulate(&gpu, compile(&src), 1);
        let img = draw_gpu(&sim, w, h);
        let camera = Camera::from_effect(&sim.compiled().ir.camera, w as f32 / h as f32);
        let (x, y) = camera.project(w, h, p).expect("in front of the camera");
        // The sprite is symmetric about its centre, so the intensity-weighted mean of its
        // pixel centres (at half-integers) is the projected point, up to rasterisation.
        let (mut sw, mut sx, mut sy) = (0.0, 0.0, 0.0);
        for j in 0..h {
            for i in 0..w {
                let v = f64::from(pixel(&img, w, i, j)[0]);
                sw += v;
                sx += v * (f64::from(i) + 0.5);
                sy += v * (f64::from(j) + 0.5);
            }
        }
        assert!(sw > 0.0, "nothing drawn for {p:?}");
        let (cx, cy) = (sx / sw, sy / sw);
        let off = ((cx - f64::from(x)).powi(2) + (cy - f64::from(y)).powi(2)).sqrt();
        assert!(
            off <= 1.0,
            "{p:?}: drawn at ({cx:.2}, {cy:.2}), projected to ({x:.2}, {y:.2}): {off:.2} px apart"
        );
        // And the pixel under the projected point is lit.
        let px = pixel(&img, w, x as u32, y as u32);
        assert!(px[0] > 100, "no sprite under {p:?} -> ({x}, {y}): {px:?}");
        // Background far from it: the corners.
        for (i, j) in [(0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)] {
            assert_eq!(pixel(&img, w, i, j), [0, 0, 0, 255]);
        }
    }
}

#[test]
fn the_gpu_draw_matches_the_cpu_fed_drawing_for_every_example() {
    let gpu = gpu();
    // Both draws rasterise the same quads with the same blend state, in the same order (the
    // GPU depth order for sorted effects, slot order otherwise). They differ only where the
    // colour and size are computed: f32 on the GPU, f64 rounded to f32 on the CPU. A colour
    // then differs by under 1e-6, which moves an 8-bit blend result by at most one step where
    // it lands on a rounding boundary, and a size by under 1e-7 m, which moves a sprite's rim
    // by far less than a pixel. Each blended layer can add one step, so a deep stack of
    // sprites can drift a few steps (llvmpipe: at most 1); a different picture (a sprite
    // missing or misplaced, a wrong colour, another order) changes whole sprites by tens.
    let names = examples();
    assert!(names.len() >= 6);
    // 90 steps (1.5 s) where lifetimes allow (advance_to_show): enough particles overlap that drawing the sorted fountain in id order
    // instead of depth order differs by up to 48 steps in ~900 channels (checked below).
    let within = |(mean, max, over): (f64, u8, usize), len: usize| {
        mean < 0.01 && max <= 4 && over * 2000 < len
    };
    for path in names {
        let sim = advance_to_show(simulate(&gpu, compile_file(&path), 0));
        let (w, h) = (240, 135);
        let gpu_img = draw_gpu(&sim, w, h);
        let cpu_img = draw_reference(&sim, w, h);
        let d = differences(&gpu_img, &cpu_img, 2);
        let name = path.file_name().unwrap().to_string_lossy();
        eprintln!(
            "{name}: mean {:.5}, max {}, {} channels over 2",
            d.0, d.1, d.2
        );
        // A textured sprite samples the mip level its size on screen calls for. Where a pixel
        // centre lies on a sprite's edge (the GPU places corners in view space, the reference
        // in world space, each in f32), one draw covers it and the other does not; at level 0
        // the frame's rim is transparent and nothing shows, but a coarse level's rim texel
        // averages in the opaque texels inside it. Such pixels stand alone: a sprite drawn
        // differently changes a block of neighbouring pixels, which this still refuses.
        let textured = sim.compiled().ir.render.texture.is_some();
        let rim_only = |(mean, _, over): (f64, u8, usize)| {
            mean < 0.01 && over * 2000 < gpu_img.len() && lone_pixels(&gpu_img, &cpu_img, w, 4)
        };
        assert!(
            within(d, gpu_img.len()) || (textured && rim_only(d)),
            "{name}: GPU and CPU-fed draws differ: {d:?}"
        );
        if sim.compiled().ir.sort {
            // The comparison sees the order: the same particles drawn in id order fall outside.
            let ir = &sim.compiled().ir;
            let r = ReferenceRenderer::new(sim.gpu(), w, h, ir).unwrap();
            let camera = Camera::from_effect(&ir.camera, w as f32 / h as f32);
            let ids = sprites(&sim.records().unwrap(), ir, &camera, false);
            let wrong = differences(&gpu_img, &r.draw(&ids, &camera).unwrap(), 2);
            assert!(
                !within(wrong, gpu_img.len()),
                "{name}: id order passes: {wrong:?}"
            );
        }
        // Not a blank picture: some particles are on screen.
        let bg = pixel(&gpu_img, w, 0, 0);
        let lit = gpu_img
            .chunks(4)
            .filter(|p| p.iter().zip(bg).any(|(a, b)| a.abs_diff(b) > 20))
            .count();
        assert!(
            lit > 20,
            "{name}: only {lit} pixels differ from the background"
        );
    }
}

/// sparks.ron with `sort` set, compiled in `state`.
fn sparks(state: State, sort: bool) -> CompiledEffect {
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/effects/sparks.ron"))
        .unwrap();
    compile_str(
        &src,
        &CompileOptions {
            state: Some(state),
            sort: Some(sort),
            ..Default::default()
        },
    )
    .unwrap()
}

#[test]
fn a_stateless_effect_drawn_from_its_closed_form_matches_its_evaluated_state() {
    let gpu = gpu();
    for sort in [false, true] {
        let stateless = simulate(&gpu, sparks(State::Stateless, sort), 25);
        assert!(stateless.is_stateless());
        let (w, h) = (240, 135);
        let closed_form = draw_gpu(&stateless, w, h);
        // Drawing allocated no view: the vertex shader computed every particle.
        assert_eq!(oracle::particle_buffer_bytes(&stateless), 0);
        // The same particles, evaluated into the view by the `evaluate` kernel, read back and
        // drawn by the reference path: the same f32 closed form, so the same pixels up to the
        // colour's f32/f64 rounding (see the every-example test).
        let evaluated = draw_reference(&stateless, w, h);
        let (mean, max, _) = differences(&closed_form, &evaluated, 4);
        assert!(
            mean < 0.01 && max <= 4,
            "sort {sort}: closed form vs evaluated view: mean {mean}, max {max}"
        );
        // And the same effect kept stateful (Exact stepping, the state in a buffer) drawn by
        // the GPU path. Its positions differ from the closed form by f32 rounding (~1e-7
        // relative, see tests/stateless.rs), a thousandth of a pixel here.
        let stateful = simulate(&gpu, sparks(State::Stateful, sort), 25);
        assert!(!stateful.is_stateless());
        let from_state = draw_gpu(&stateful, w, h);
        let (mean, max, _) = differences(&closed_form, &from_state, 4);
        eprintln!("sort {sort}: closed form vs stateful: mean {mean}, max {max}");
        assert!(
            mean < 0.01 && max <= 4,
            "sort {sort}: closed form vs stateful: mean {mean}, max {max}"
        );
    }
}

#[test]
fn the_draw_is_the_same_when_the_state_is_split_across_buffers() {
    let gpu = gpu();
    // The fountain (sorted: every buffer is reachable from the depth order) and snow
    // (unsorted), with their state in one buffer and split into three.
    for name in ["fountain", "snow"] {
        let e = compile_file(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("effects/{name}.ron")),
        );
        let split = u64::from(e.ir.capacity).div_ceil(3);
        let whole = simulate(&gpu, e.clone(), 40);
        let mut parts = common::split(&gpu, e, Some(split));
        parts.run(40, |_| {}).unwrap();
        assert_eq!(oracle::chunk_count(&parts, 0).unwrap(), 3);
        let (a, b) = (draw_gpu(&whole, 200, 120), draw_gpu(&parts, 200, 120));
        assert_eq!(a, b, "{name}: one buffer and three draw differently");
    }
}

#[test]
fn sorting_changes_overlapping_alpha_sprites_as_blending_predicts() {
    let gpu = gpu();
    // Two big sprites with alpha 0.5 on the view axis, on black. Id 0 is near (z = 2) and lives
    // 100 s: after one step its life fraction is 1.7e-4, past the gradient's 1e-4 stop: blue.
    // Id 1 is far (z = -2) and immortal: life fraction 0: red.
    let src = |sort: bool| {
        format!(
            r#"Effect(
    name: "two",
    capacity: 2,
    emitters: [
        Emitter(burst: 1, shape: Point((0.0, 0.0, 2.0)), velocity: Constant((0.0, 0.0, 0.0)),
                lifetime: Some((100.0, 100.0))),
        Emitter(burst: 1, shape: Point((0.0, 0.0, -2.0)), velocity: Constant((0.0, 0.0, 0.0))),
    ],
    sort: {sort},
    camera: Camera(eye: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    render: Render(
        color: [(0.0, (1.0, 0.0, 0.0, 0.5)), (0.0001, (0.0, 0.0, 1.0, 0.5))],
        size: [(0.0, 4.0)],
        background: (0.0, 0.0, 0.0),
    ),
)"#
        )
    };
    let (w, h) = (64, 64);
    let unsorted = pixel(
        &draw_gpu(&simulate(&gpu, compile(&src(false)), 1), w, h),
        w,
        32,
        32,
    );
    let sorted = pixel(
        &draw_gpu(&simulate(&gpu, compile(&src(true)), 1), w, h),
        w,
        32,
        32,
    );
    // Unsorted (slot order, here the spawn order): near blue first, then far red over it:
    //   blue over black = (0, 0, 0.5); red over that = (0.5, 0, 0.25).
    // Sorted (far first): red over black = (0.5, 0, 0); blue over that = (0.25, 0, 0.5).
    // The sprite falloff at the centre pixel is (1 - r²)² with r <= 1 px / 16 px: under 1/255
    // of change; 8-bit rounding of two blends adds at most 1 more.
    let close =
        |a: [u8; 4], b: [f64; 3]| (0..3).all(|i| (f64::from(a[i]) - b[i] * 255.0).abs() <= 3.0);
    assert!(
        close(unsorted, [0.5, 0.0, 0.25]),
        "unsorted centre pixel {unsorted:?}"
    );
    assert!(
        close(sorted, [0.25, 0.0, 0.5]),
        "sorted centre pixel {sorted:?}"
    );
}

#[test]
fn sparks_match_the_golden_image() {
    let gpu = gpu();
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/golden/sparks-160x90-step20.png"
    );
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/effects/sparks.ron"))
        .unwrap();
    let img = draw_gpu(&simulate(&gpu, compile(&src), 20), 160, 90);
    if std::env::var_os("PLUME_WRITE_GOLDEN").is_some() {
        image::save_buffer(path, &img, 160, 90, image::ExtendedColorType::Rgba8).unwrap();
    }
    let golden = image::open(path)
        .expect("golden image")
        .to_rgba8()
        .into_raw();
    assert_eq!(golden.len(), img.len());
    // Different drivers rasterise sprite edges and round blends differently: allow a small mean
    // difference and a few pixels that differ more, but not a different picture.
    let (mean, _, large) = differences(&golden, &img, 24);
    assert!(
        mean < 1.5,
        "mean channel difference {mean} from the golden image"
    );
    assert!(
        large < golden.len() / 200,
        "{large} channels differ by more than 24"
    );
    // And the picture is not empty: sparks are there.
    assert!(img.chunks(4).filter(|p| p[0] > 60).count() > 50);
}

#[test]
fn a_compacted_list_of_live_slots_draws_what_hidden_free_slots_draw() {
    // The tornado after 200 steps: its first particles have died (lifetimes from 2.5 s) and
    // their slots were reused, so free and live slots interleave. The list keeps slot order,
    // so both draws blend the same sprites in the same order: the same image, exactly.
    let gpu = gpu();
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/effects/tornado.ron"))
        .unwrap();
    let sim = simulate(&gpu, compile(&src), 200);
    assert!(sim.totals().unwrap().died > 0, "slots were freed");
    let target = Offscreen::new(&gpu, 200, 120).unwrap();
    let camera = target.effect_camera(&sim);
    let hidden = renderer_with(
        &sim,
        &target.target(),
        &DrawOptions {
            dead_slots: DeadSlots::Hidden,
            ..Default::default()
        },
    )
    .unwrap();
    let hidden = target.render(&sim, &hidden, &camera).unwrap();
    let compacted = renderer_with(
        &sim,
        &target.target(),
        &DrawOptions {
            dead_slots: DeadSlots::Compacted,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(hidden, target.render(&sim, &compacted, &camera).unwrap());
}

#[test]
fn the_compute_renderer_draws_what_the_raster_draw_draws_for_every_example() {
    // The compute renderer tests coverage at pixel centres with exact float arithmetic where the
    // rasteriser snaps vertices to sub-pixel steps, packs a disc's colour to 10 bits and its
    // extent and alpha to f16 (under 0.13 of an 8-bit step per sprite), and composites in f32,
    // rounding once. It is compared with the raster draw into a 16-bit float target, rounded
    // once too: the 8-bit target's rounding after every blend (llvmpipe's blend unit works in
    // 8-bit fixed point) loses faint layers, 13 steps apart in a 4 x 4 square of smoke's
    // piled-up base. A misplaced sprite (half a pixel off: mean difference 1.25 on the
    // tornado), a wrong colour or order is far outside what is allowed below. A lit colour
    // past 1 would blend unclamped in the float target but clamped in the compute renderer's
    // image (as in the 8-bit target `plume render` draws into), so the lit examples' lights
    // keep their colours within 1. Every example the compute renderer draws is compared,
    // glowing ones after the same bloom.
    let gpu = gpu();
    let mut compared = 0;
    for path in examples() {
        let sim = advance_to_show(simulate(&gpu, compile_file(&path), 0));
        let name = path.file_name().unwrap().to_string_lossy();
        if !ComputeOffscreen::draws(&sim.compiled().ir) {
            eprintln!("{name}: trails, not for the compute renderer");
            continue;
        }
        compared += 1;
        // A larger image where sprites are densest (the missed tile edge was found there).
        let dense = ["fountain.ron", "tornado.ron"].contains(&name.as_ref());
        let sizes: &[(u32, u32)] = if dense {
            &[(240, 135), (640, 360)]
        } else {
            &[(240, 135)]
        };
        for &(w, h) in sizes {
            let raster = draw_gpu_hdr(&sim, w, h);
            let mut splat = ComputeOffscreen::new(&sim, w, h).unwrap();
            let camera = Camera::from_effect(&sim.compiled().ir.camera, w as f32 / h as f32);
            let img = splat.render(&sim, &camera).unwrap();
            // Every sprite reached each tile it touches: no entry lost or overwritten.
            assert!(
                splat.entries_are_complete().unwrap(),
                "{name} {w}x{h}: entries lost"
            );
            let (mean, max, over) = differences(&raster, &img, 3);
            let beyond_one = beyond_one_step(&raster, &img);
            if std::env::var_os("PLUME_DUMP").is_some() {
                for (pixels, kind) in [(&raster, "raster"), (&img, "splat")] {
                    image::save_buffer(
                        format!("/tmp/{name}_{w}_{kind}.png"),
                        pixels,
                        w,
                        h,
                        image::ColorType::Rgba8,
                    )
                    .unwrap();
                }
            }
            let local = local_difference(&raster, &img, w, 4);
            eprintln!(
                "{name} {w}x{h}: splat vs raster: mean {mean:.5} ({beyond_one:.5} beyond one step), max {max}, {over} channels over 3, 4x4 {local:.2}"
            );
            // Both images are rounded to 8 bits once: the raster one from its 16-bit float
            // target (each blend there rounds to 1/16 of an 8-bit step or finer), the compute renderer's
            // from f32 sums. The clear colour alone may then land a step apart (f16's 0.1 is
            // 25.49 steps, f32's 25.50), so differences are counted beyond one step. Discs fade
            // to nothing at their rim, and every pixel stays within 3 steps. A textured quad
            // may be opaque up to its edge: a pixel centre within the rasteriser's vertex
            // snapping (1/256 pixel on llvmpipe) of the edge is covered by one draw and not the
            // other and differs by the whole texel (49 steps on one of snow's flakes, 42 on
            // one of boids' 2-pixel birds), which moves a 4 x 4 square's mean by about 3. A
            // misplaced, missing or wrongly ordered sprite moves whole squares by its contrast
            // with the background, and the lit pixels below by its area.
            let ir = &sim.compiled().ir;
            let quads = !plume::compiler::wgsl::draw::splat_discs(ir, ir.render.glow.is_some());
            assert!(
                beyond_one < 0.02 && (max <= 3 || quads) && local < 4.0 && over * 2000 < img.len(),
                "{name} {w}x{h}: splat and raster differ: mean {mean} ({beyond_one} beyond one step), max {max}, {over} over 3, 4x4 {local}"
            );
            // Where something is drawn at all: pixels more than 16 steps off the background
            // in one image and within 8 of it in the other.
            let bg = &raster[..4];
            let off = |img: &[u8], k: usize| {
                (0..3)
                    .map(|c| img[4 * k + c].abs_diff(bg[c]))
                    .max()
                    .unwrap()
            };
            let pixels = raster.len() / 4;
            let shown = (0..pixels).filter(|&k| off(&raster, k) > 16).count();
            let disagree = (0..pixels)
                .filter(|&k| {
                    let (a, b) = (off(&raster, k), off(&img, k));
                    (a > 16 && b <= 8) || (b > 16 && a <= 8)
                })
                .count();
            assert!(
                disagree * 100 <= shown + 100,
                "{name} {w}x{h}: {disagree} pixels lit in one draw only, of {shown}"
            );
        }
    }
    assert!(
        compared >= 8,
        "only {compared} examples drawn by the compute renderer"
    );
}

#[test]
fn the_compute_renderer_draws_every_group_of_a_graph_in_group_order() {
    // The graph examples, every group composited into one image in group order, each over
    // what the ones before drew, against the raster draw of the same groups into a float
    // target (rounded once, as the compute renderer): rain.ron's drops (velocity-aligned streaks, quads:
    // only edge pixels may flip, see the test above) and the splashes their ground hits fire;
    // fireworks.ron's shells, sparks and embers, all drawn into the HDR image the top-level
    // group's glow blooms, as `plume render` does.
    let gpu = gpu();
    let dir = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/effects"));
    for (name, steps) in [("rain.ron", 90), ("fireworks.ron", 150)] {
        let graph = compile_graph_file(&dir.join(name));
        let groups = graph.groups.len();
        assert!(groups > 1);
        let mut sim = Effect::from_graph(&gpu, graph).unwrap();
        sim.run(steps, |_| {}).unwrap();
        let fed = sim.group_records(groups - 1).unwrap().len();
        assert!(
            fed > 20,
            "{name}: only {fed} particles alive in the last group"
        );
        let (w, h) = (320, 180);
        let raster = draw_gpu_hdr(&sim, w, h);
        let mut splat = ComputeOffscreen::new(&sim, w, h).unwrap();
        let camera = Camera::from_effect(&sim.compiled().ir.camera, w as f32 / h as f32);
        let img = splat.render(&sim, &camera).unwrap();
        assert!(splat.entries_are_complete().unwrap());
        let beyond_one = beyond_one_step(&raster, &img);
        let local = local_difference(&raster, &img, w, 4);
        let (mean, max, over) = differences(&raster, &img, 3);
        eprintln!("{name}: mean {mean:.5} ({beyond_one:.5} beyond one step), max {max}, {over} over 3, 4x4 {local:.2}");
        assert!(
            beyond_one < 0.02 && local < 4.0 && over * 2000 < img.len(),
            "{name}: splat and raster differ: mean {mean}, max {max}, {over} over 3, 4x4 {local}"
        );
    }
}

#[test]
fn the_splat_grows_its_entry_list_when_a_frame_needs_more() {
    // 32 sprites 6 m across, each about 220 pixels wide on a 480x270 image (near 200 tiles):
    // some 6,000 (tile, sprite) entries, past the first guess for 32 sprites (4,136). The
    // frame is drawn again with a longer list and matches the raster draw.
    let gpu = gpu();
    let points: Vec<DVec3> = (0..32)
        .map(|i| {
            DVec3::new(
                f64::from(i % 8) * 0.15 - 0.5,
                f64::from(i / 8) * 0.3 - 0.45,
                0.0,
            )
        })
        .collect();
    let src = still_points(
        &points,
        "render: Render(color: [(0.0, (0.9, 0.5, 0.2, 0.3))], size: [(0.0, 6.0)], background: (0.0, 0.0, 0.0)),",
    );
    let sim = simulate(&gpu, compile(&src), 1);
    let (w, h) = (480, 270);
    let mut splat = ComputeOffscreen::new(&sim, w, h).unwrap();
    let first = splat.entries();
    let camera = Camera::from_effect(&sim.compiled().ir.camera, w as f32 / h as f32);
    let img = splat.render(&sim, &camera).unwrap();
    assert!(splat.entries() > first, "the list grew from {first}");
    assert!(splat.entries_are_complete().unwrap());
    // Up to 32 large alpha-0.3 layers over a pixel: llvmpipe's blend unit works in 8-bit fixed
    // point and rounds each of them a little differently from a float blend (rings along the
    // falloff, a bias of -0.2 to -0.6 steps per channel at 16 layers, at most 10 steps there),
    // where a misplaced or missing sprite would differ by tens.
    let (mean, max, _) = differences(&draw_gpu(&sim, w, h), &img, 2);
    assert!(mean < 0.5 && max <= 12, "mean {mean}, max {max}");
}

#[test]
fn additive_light_composites_the_same_whatever_order_its_lists_hold() {
    // Additive light's tile lists are placed by atomics in no fixed order (the composites sum
    // fixed-point light, exactly): the same sprites listed forwards and backwards, 150 of them
    // piled over each other, composite to the same bytes, and the lists hold every entry.
    // Glowing ones are quads into an HDR image (the generated composite); plain ones are discs
    // into an 8-bit image (splat.wgsl's raster, each tile's list split over slices whose light
    // `merge_discs` sums).
    let gpu = gpu();
    let mut seed = 12345u32;
    let mut next = || {
        seed = seed.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
        f64::from(seed >> 8) / f64::from(1u32 << 24) - 0.5
    };
    let points: Vec<DVec3> = (0..150)
        .map(|_| DVec3::new(next() * 1.6, next() * 1.2 + 0.5, next()))
        .collect();
    let sprites = "render: Render(color: [(0.0, (0.9, 0.5, 0.2, 0.35))], size: [(0.0, 4.0)], blend: Additive, background: (0.0, 0.0, 0.0)";
    let glowing =
        format!("{sprites}, glow: Some(Glow(threshold: 2.0, strength: 1.5, radius: 0.02))),");
    let plain = format!("{sprites}),");
    let (w, h) = (192, 108);
    for (look, hdr) in [(glowing, true), (plain, false)] {
        let draw = |points: &[DVec3]| {
            let sim = simulate(&gpu, compile(&still_points(points, &look)), 1);
            let mut splat = ComputeOffscreen::new(&sim, w, h).unwrap();
            let camera = Camera::from_effect(&sim.compiled().ir.camera, w as f32 / h as f32);
            let img = splat.render(&sim, &camera).unwrap();
            assert!(splat.entries_are_complete().unwrap());
            let raster = match hdr {
                true => draw_gpu_hdr(&sim, w, h),
                false => draw_gpu(&sim, w, h),
            };
            (img, raster)
        };
        let (forwards, raster) = draw(&points);
        let reversed: Vec<DVec3> = points.iter().rev().copied().collect();
        let (backwards, _) = draw(&reversed);
        assert!(
            forwards == backwards,
            "the order of the sprites changed the image (hdr {hdr})"
        );
        // Up to a hundred layers of light, saturated where they pile up, against the raster
        // draw, which rounds every blend. Into a float target (f16 sums) a pixel of many dim
        // layers lands a few steps off. Into an 8-bit one each of those layers is rounded to a
        // step, and the errors add up: the discs summed in f32 before they were summed in
        // fixed point landed as far off (mean 0.187, at most 17 steps, 1,486 channels over 3
        // of 82,944 on llvmpipe), where a missing disc would be about 90 steps off at its
        // centre and tens around it.
        let (mean, max, over) = differences(&raster, &forwards, 3);
        eprintln!("hdr {hdr}: mean {mean}, max {max}, {over} over 3");
        let (mean_most, max_most, over_share) = if hdr { (0.5, 12, 100) } else { (0.3, 24, 30) };
        assert!(
            mean < mean_most && max <= max_most && over * over_share < forwards.len(),
            "hdr {hdr}: mean {mean}, max {max}, {over} over 3"
        );
    }
}

#[test]
fn additive_lists_of_more_tiles_than_a_band_hold_every_entry() {
    // The additive lists count a workgroup's entries in workgroup memory 4,096 tiles at a
    // time; a 1,025 x 1,009 image has 65 x 64 = 4,160 tiles (the last column and row a pixel
    // wide), two bands, and its partial sums stay within llvmpipe's 128 MiB binding. Sprites
    // spread over the whole image land in both, and the compute renderer draws what the raster draw draws.
    let gpu = gpu();
    // Rows of sprites from below the image's bottom edge (the second band's one row of tiles)
    // to its top.
    let points: Vec<DVec3> = (0..64)
        .map(|i| {
            DVec3::new(
                f64::from(i % 8) * 1.1 - 3.85,
                f64::from(i / 8) * 0.95 - 3.4,
                0.0,
            )
        })
        .collect();
    let look = "render: Render(color: [(0.0, (0.9, 0.5, 0.2, 0.8))], size: [(0.0, 0.5)], blend: Additive, background: (0.0, 0.0, 0.0), glow: Some(Glow(threshold: 2.0, strength: 1.5, radius: 0.02))),";
    let sim = simulate(&gpu, compile(&still_points(&points, look)), 1);
    let (w, h) = (1025, 1009);
    let mut splat = ComputeOffscreen::new(&sim, w, h).unwrap();
    let camera = Camera::from_effect(&sim.compiled().ir.camera, w as f32 / h as f32);
    let img = splat.render(&sim, &camera).unwrap();
    assert!(splat.entries_are_complete().unwrap());
    let raster = draw_gpu_hdr(&sim, w, h);
    let (mean, max, over) = differences(&raster, &img, 3);
    // Lit pixels in the last row (tiles 4,096 on: the second band) and above it.
    let last_row = (w * (h - 1) * 4) as usize;
    let lit = |pixels: &[u8]| pixels.chunks_exact(4).filter(|p| p[0] > 100).count();
    assert!(
        lit(&img[last_row..]) > 20,
        "{} lit in the last row",
        lit(&img[last_row..])
    );
    assert!(lit(&img[..last_row]) > 10_000);
    assert!(
        mean < 0.05 && max <= 8 && over * 2000 < img.len(),
        "mean {mean}, max {max}, {over} over 3"
    );
}
