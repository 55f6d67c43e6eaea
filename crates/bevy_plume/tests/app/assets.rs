//! An effect's own files go through Bevy's asset server (on llvmpipe, lavapipe): a texture
//! named relative to the effect is read from the effect's asset source, so an edit to it on
//! disk reloads the effect, and an effect and its texture load from Bevy's embedded source,
//! which is not a folder on disk, as do a glTF mesh and the buffer file it names.

use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::common::{asset_dir, project, serial, Harness};
use bevy::asset::io::embedded::EmbeddedAssetRegistry;
use bevy::prelude::*;
use bevy_plume::{PlumeEffect, PlumeEffectAsset};

/// One opaque sprite 3 m across at the origin, white times its texture, `file`.
fn swatch_effect(file: &str) -> String {
    format!(
        r#"Effect(name: "swatch", capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 3.0)], blend: Opaque,
                   texture: Some(Texture(file: "{file}"))))
"#
    )
}

/// An 8 x 8 PNG of one colour.
fn png(rgb: [u8; 3]) -> Vec<u8> {
    let image = image::RgbaImage::from_pixel(8, 8, image::Rgba([rgb[0], rgb[1], rgb[2], 255]));
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write_to(&mut bytes, image::ImageFormat::Png).unwrap();
    bytes.into_inner()
}

/// Whether channel `c` of `rgb` is over 150 and at least 100 above the other two (the
/// texture is read as linear values and the image written as sRGB: 20 of 255 comes out 79).
fn dominant(rgb: [u8; 3], c: usize) -> bool {
    (0..3).all(|k| k == c || i32::from(rgb[c]) >= i32::from(rgb[k]) + 100) && rgb[c] > 150
}

/// The colour at the sprite's centre.
fn centre(h: &mut Harness) -> [u8; 3] {
    let image = h.capture();
    let (x, y) = project(0.0, 0.0);
    let p = image.get_pixel(x as u32, y as u32).0;
    [p[0], p[1], p[2]]
}

/// Loads the effect at `path` of Bevy's embedded source (failing the test where it does not
/// load), spawns it and gives the colour drawn at the origin a few frames on.
fn draw_embedded(h: &mut Harness, path: &str) -> [u8; 3] {
    let handle: Handle<PlumeEffectAsset> = h.load(&format!("embedded://{path}"));
    assert!(
        h.app
            .world()
            .resource::<Assets<PlumeEffectAsset>>()
            .contains(&handle),
        "the embedded effect did not load: {:?}",
        h.load_errors.lock().unwrap()
    );
    h.app.world_mut().spawn(PlumeEffect::new(handle));
    h.update(5);
    centre(h)
}

#[test]
fn an_edited_texture_reloads_the_effect() {
    let _one = serial();
    let dir = asset_dir("texture-reload");
    std::fs::create_dir_all(dir.join("fx/textures")).unwrap();
    std::fs::write(
        dir.join("fx/swatch.plume.ron"),
        swatch_effect("textures/swatch.png"),
    )
    .unwrap();
    let texture = dir.join("fx/textures/swatch.png");
    std::fs::write(&texture, png([230, 20, 20])).unwrap();
    let mut h = Harness::with_watching(&dir, true);
    let handle = h.load("fx/swatch.plume.ron");
    h.app.world_mut().spawn(PlumeEffect::new(handle));
    h.update(5);
    let red = centre(&mut h);
    assert!(dominant(red, 0), "the red texture drew {red:?}");
    std::fs::write(&texture, png([20, 230, 20])).unwrap();
    let green = h.update_until(300, Duration::from_millis(50), |h| dominant(centre(h), 1));
    assert!(
        green,
        "the texture turned green on disk, the effect still draws {:?}",
        centre(&mut h)
    );
}

#[test]
fn an_effect_and_its_texture_load_from_the_embedded_source() {
    let _one = serial();
    // An empty folder: nothing is on disk.
    let dir = asset_dir("embedded");
    let mut h = Harness::new(&dir);
    {
        let registry = h.app.world().resource::<EmbeddedAssetRegistry>();
        let put = |path: &str, bytes: Vec<u8>| {
            registry.insert_asset(PathBuf::from(path), Path::new(path), bytes);
        };
        put(
            "fx/swatch.plume.ron",
            swatch_effect("../art/blue.png").into_bytes(),
        );
        put("art/blue.png", png([20, 20, 230]));
    }
    let blue = draw_embedded(&mut h, "fx/swatch.plume.ron");
    assert!(dominant(blue, 2), "the embedded texture drew {blue:?}");
}

/// A unit cube (±0.5) as glTF, its positions and indices in the buffer file `bin_uri`: the
/// glTF's text and the buffer's bytes.
fn cube_gltf(bin_uri: &str) -> (String, Vec<u8>) {
    let mut bin: Vec<u8> = (0..8u32)
        .flat_map(|k| [0, 1, 2].map(|bit| if k >> bit & 1 == 1 { 0.5f32 } else { -0.5 }))
        .flat_map(f32::to_le_bytes)
        .collect();
    // Each face's corners counter-clockwise seen from outside, fanned into two triangles.
    let faces: [[u32; 4]; 6] = [
        [4, 5, 7, 6],
        [1, 3, 7, 5],
        [0, 2, 3, 1],
        [0, 4, 6, 2],
        [2, 6, 7, 3],
        [0, 1, 5, 4],
    ];
    let indices = faces
        .iter()
        .flat_map(|f| [f[0], f[1], f[2], f[0], f[2], f[3]]);
    bin.extend(indices.flat_map(u32::to_le_bytes));
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
  "buffers": [{{"uri": "{bin_uri}", "byteLength": {}}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 96}}, {{"buffer": 0, "byteOffset": 96, "byteLength": 144}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
                  "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5]}},
                {{"bufferView": 1, "componentType": 5125, "count": 36, "type": "SCALAR"}}]}}"#,
        bin.len()
    );
    (json, bin)
}

#[test]
fn a_gltf_mesh_and_its_buffer_load_from_the_embedded_source() {
    let _one = serial();
    let dir = asset_dir("embedded-gltf");
    let mut h = Harness::new(&dir);
    let (gltf, bin) = cube_gltf("cube.bin");
    {
        let registry = h.app.world().resource::<EmbeddedAssetRegistry>();
        let put = |path: &str, bytes: Vec<u8>| {
            registry.insert_asset(PathBuf::from(path), Path::new(path), bytes);
        };
        // One red cube 3 m across at the origin: the buffer is asked for only once the glTF
        // has been read, so the loader reads a second round of files.
        let effect = swatch_effect("unused.png").replace(
            r#"texture: Some(Texture(file: "unused.png"))"#,
            r#"mesh: Some(ParticleMesh(file: "../art/cube.gltf"))"#,
        );
        let effect = effect.replace("(1.0, 1.0, 1.0, 1.0)", "(0.9, 0.05, 0.05, 1.0)");
        put("fx/cube.plume.ron", effect.into_bytes());
        put("art/cube.gltf", gltf.into_bytes());
        put("art/cube.bin", bin);
    }
    let red = draw_embedded(&mut h, "fx/cube.plume.ron");
    assert!(dominant(red, 0), "the glTF cube drew {red:?}");
}
