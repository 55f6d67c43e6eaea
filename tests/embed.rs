//! The embed example (examples/embed.rs, included here as a module so CI runs its very code):
//! a host application with its own device, depth buffer and geometry, with Plume drawing into
//! its render pass. Headless on llvmpipe: the PNG is not blank, the particles are there, and
//! the host's cube hides the particles behind it, with the raster renderer and the compute one,
//! whose images of the examples match.

#[path = "../examples/embed.rs"]
mod embed;

use embed::{render_headless, write_headless, Headless, Layers};

fn fountain() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("effects/fountain.ron")
}

fn options(layers: Layers) -> Headless {
    Headless {
        size: (320, 180),
        // 120 steps (2 s of fountain) in 6 frames: each frame sorts 200k slots, slow on llvmpipe.
        frames: 6,
        steps_per_frame: 20,
        layers,
    }
}

#[test]
fn the_headless_embed_writes_a_png_that_is_not_blank() {
    let out = std::env::temp_dir().join(format!("plume-embed-{}.png", std::process::id()));
    write_headless(&fountain(), &out, &options(Layers::default())).unwrap();
    let img = image::open(&out).expect("a PNG").to_rgba8();
    std::fs::remove_file(&out).ok();
    assert_eq!(img.dimensions(), (320, 180));
    let first = *img.get_pixel(0, 0);
    let different = img.pixels().filter(|p| **p != first).count();
    assert!(
        different > 1000,
        "only {different} pixels differ from the corner"
    );
}

#[test]
fn the_host_cube_hides_the_particles_behind_it() {
    for compute in [false, true] {
        cube_hides_particles(Layers {
            compute,
            ..Layers::default()
        });
    }
}

/// The cube hides the fountain's particles behind it, drawn with `layers`' renderer.
fn cube_hides_particles(layers: Layers) {
    let path = fountain();
    let full = render_headless(&path, &options(layers)).unwrap();
    let host_only = render_headless(
        &path,
        &options(Layers {
            particles: false,
            ..layers
        }),
    )
    .unwrap();
    let no_depth_test = render_headless(
        &path,
        &options(Layers {
            depth_test: false,
            ..layers
        }),
    )
    .unwrap();
    // The cube's pixels: red well above green and blue (no particle of the fountain is red).
    let cube: Vec<usize> = host_only
        .chunks(4)
        .enumerate()
        .filter(|(_, p)| p[0] > 30 && u32::from(p[0]) > 3 * u32::from(p[1]) + 5)
        .map(|(i, _)| i)
        .collect();
    assert!(cube.len() > 500, "the cube covers {} pixels", cube.len());
    let px = |img: &[u8], i: usize| [img[4 * i], img[4 * i + 1], img[4 * i + 2]];
    // Particles are drawn: away from the cube, many pixels change.
    let changed = (0..full.len() / 4)
        .filter(|i| px(&full, *i) != px(&host_only, *i))
        .count();
    assert!(changed > 500, "only {changed} pixels show particles");
    // Behind the cube they exist (without the depth test they show through it) ...
    let through = cube
        .iter()
        .filter(|&&i| px(&no_depth_test, i) != px(&host_only, i))
        .count();
    assert!(
        through > 50,
        "only {through} cube pixels have particles behind them"
    );
    // ... and the host's depth buffer hides every one of them: the cube is untouched.
    let leaked = cube
        .iter()
        .filter(|&&i| px(&full, i) != px(&host_only, i))
        .count();
    assert_eq!(
        leaked, 0,
        "{leaked} cube pixels show particles behind the cube ({layers:?})"
    );
}

#[test]
fn the_compute_renderer_draws_the_raster_image_into_the_host() {
    // Every kind of look through the host's pass and depth: a soft, textured, sorted flipbook
    // (smoke), ribbons (orbit), a graph of three groups (fireworks), rotating textured quads
    // (snow), round sprites (fountain).
    for name in ["fountain", "smoke", "orbit", "fireworks", "snow"] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("effects")
            .join(format!("{name}.ron"));
        let draw = |compute| {
            render_headless(
                &path,
                &options(Layers {
                    compute,
                    ..Layers::default()
                }),
            )
            .unwrap()
        };
        let (raster, compute) = (draw(false), draw(true));
        let (w, h) = (320, 180);
        let channel =
            |img: &[u8], x: usize, y: usize, c: usize| f64::from(img[4 * (y * w + x) + c]);
        // The raster draw rounds to 8 bits after every blend, the compute one once (it
        // composites in f32): faint layers of many sprites land a step or so apart, so the mean
        // counts only what lies beyond one step. Measured on llvmpipe: at most 5e-5 of full
        // scale (smoke, snow).
        let mut beyond = 0.0;
        for y in 0..h {
            for x in 0..w {
                for c in 0..3 {
                    let d = (channel(&raster, x, y, c) - channel(&compute, x, y, c)).abs();
                    beyond += (d - 1.0).max(0.0) / 255.0;
                }
            }
        }
        let beyond = beyond / (w * h * 3) as f64;
        assert!(
            beyond < 5e-4,
            "{name}: mean difference beyond one step {beyond:.2e}"
        );
        // Single pixels may differ more where the rasteriser snaps an edge that the compute
        // renderer tests at the exact pixel centre (an opaque texel's or a ribbon's edge: up to
        // 48 steps measured on one pixel); 4x4 means of the two stay within 4 steps (smoke:
        // the raster draw's per-blend rounding in its thick base) and get 6 here.
        let mut local = 0.0f64;
        for by in 0..h / 4 {
            for bx in 0..w / 4 {
                for c in 0..3 {
                    let mean = |img: &[u8]| {
                        let mut sum = 0.0;
                        for y in 0..4 {
                            for x in 0..4 {
                                sum += channel(img, 4 * bx + x, 4 * by + y, c);
                            }
                        }
                        sum / 16.0
                    };
                    local = local.max((mean(&raster) - mean(&compute)).abs());
                }
            }
        }
        assert!(
            local <= 6.0,
            "{name}: a 4x4 mean differs by {local:.2} steps"
        );
        // And the particles are there in both: the images differ from the host's scene alone.
        let host_only = render_headless(
            &path,
            &options(Layers {
                particles: false,
                ..Layers::default()
            }),
        )
        .unwrap();
        let lit = |img: &[u8]| {
            img.chunks(4)
                .zip(host_only.chunks(4))
                .filter(|(a, b)| a != b)
                .count()
        };
        assert!(
            lit(&compute) > 200 && lit(&raster) > 200,
            "{name}: particles on {} (compute) and {} (raster) pixels",
            lit(&compute),
            lit(&raster)
        );
    }
}
