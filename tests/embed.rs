//! The embed example (examples/embed.rs, included here as a module so CI runs its very code):
//! a host application with its own device, depth buffer and geometry, with Plume drawing into
//! its render pass. Headless on llvmpipe: the PNG is not blank, the particles are there, and
//! the host's cube hides the particles behind it.

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
    let path = fountain();
    let full = render_headless(&path, &options(Layers::default())).unwrap();
    let host_only = render_headless(
        &path,
        &options(Layers {
            particles: false,
            ..Layers::default()
        }),
    )
    .unwrap();
    let no_depth_test = render_headless(
        &path,
        &options(Layers {
            depth_test: false,
            ..Layers::default()
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
        "{leaked} cube pixels show particles behind the cube"
    );
}
