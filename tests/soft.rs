//! Soft particles (`render.soft`) in the embedded path, on llvmpipe: a host's depth buffer
//! holding a wall behind a sprite fades the sprite by the documented fraction of the fade
//! distance, a wall in front hides it, and before the host binds its depth nothing fades;
//! with the raster renderer and with the compute one (`Effect::compute_renderer`), which
//! tests and fades each pixel against a copy of the host's depth.

mod common;

use common::*;
use glam::Vec4;
use plume::compiler::schema::State;
use plume::runtime::outputs::Offscreen;
use plume::runtime::{Camera, DrawTarget, Effect, Gpu};
use plume::{compile_str, CompileOptions};

const SIDE: u32 = 64;
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// One white opaque 0.5 m sprite at the origin, 10 m from the camera, fading over 1 m.
fn probe(gpu: &Gpu, state: State) -> Effect {
    let src = r#"Effect(
    name: "soft-probe",
    capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    render: Render(color: [(0.0, (1.0, 1.0, 1.0, 1.0))], size: [(0.0, 0.5)],
                   background: (0.0, 0.0, 0.0), soft: Some(1.0)),
)"#;
    let options = CompileOptions {
        state: Some(state),
        ..Default::default()
    };
    let effect =
        compile_str(src, &options).unwrap_or_else(|e| panic!("{}", e.render("s.ron", src)));
    let mut sim = Effect::new(gpu, effect).unwrap();
    sim.run(1, |_| {}).unwrap();
    sim
}

/// The centre pixel's red value with the host's depth buffer cleared to a wall `wall` metres
/// from the camera (None: the far plane), the sprite drawn in a pass that tests against it
/// read-only; `bind` says whether the host's depth is bound for the fade.
/// `compute` draws with the compute renderer.
fn centre(gpu: &Gpu, sim: &Effect, wall: Option<f32>, bind: bool, compute: bool) -> u8 {
    let camera = Camera::from_effect(&sim.compiled().ir.camera, 1.0);
    centre_from(gpu, sim, &camera, wall, bind, compute)
}

/// [`centre`] seen through `camera` (the host's matrices).
fn centre_from(
    gpu: &Gpu,
    sim: &Effect,
    camera: &Camera,
    wall: Option<f32>,
    bind: bool,
    compute: bool,
) -> u8 {
    let target = Offscreen::new(gpu, SIDE, SIDE).unwrap();
    let draw_target = DrawTarget::new(plume::runtime::outputs::FORMAT).with_depth(DEPTH);
    let mut renderer = match compute {
        true => sim.compute_renderer(&draw_target, SIDE, SIDE).unwrap(),
        false => sim.renderer(&draw_target).unwrap(),
    };
    assert!(renderer.is_soft());
    assert_eq!(renderer.is_compute(), compute);
    let depth_texture = |label| {
        gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: SIDE,
                height: SIDE,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        })
    };
    let depth = depth_texture("host depth");
    let view = depth.create_view(&Default::default());
    // Where the adapter can use one depth texture as a read-only attachment and a shader
    // resource in the same pass (Vulkan), the draw samples the attachment itself; where it
    // cannot (GL: llvmpipe in CI), the host writes its depth into a second texture too and
    // binds that one (a texture copy of the depth read back as zeros on llvmpipe's GL).
    // (The compute renderer copies the depth in a compute pass before the particles' pass:
    // the texture itself always does.)
    let shared = compute
        || gpu
            .downlevel
            .is_none_or(|f| f.contains(wgpu::DownlevelFlags::READ_ONLY_DEPTH_STENCIL));
    let second = (!shared).then(|| depth_texture("host depth, second"));
    if bind {
        match &second {
            Some(c) => renderer.set_scene_depth(&c.create_view(&Default::default())),
            None => renderer.set_scene_depth(&view),
        }
    }
    // The wall's depth as the host's projection writes it.
    let ndc = match wall {
        Some(d) => {
            let clip = camera.proj * Vec4::new(0.0, 0.0, -d, 1.0);
            clip.z / clip.w
        }
        None => 1.0,
    };
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    // The host's geometry: a wall filling the depth buffer (and its second copy, if any).
    clear_depth(&mut encoder, &view, ndc);
    if let Some(c) = &second {
        clear_depth(&mut encoder, &c.create_view(&Default::default()), ndc);
    }
    sim.prepare_draw(&mut encoder, &renderer, camera).unwrap();
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("particles"),
            color_attachments: &[Some(target.attachment(glam::DVec3::ZERO))],
            // Read-only: the soft draw samples the same texture.
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &view,
                depth_ops: None,
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        renderer.draw(&mut pass);
    }
    gpu.queue.submit([encoder.finish()]);
    gpu.take_error().unwrap();
    let img = target.read().unwrap();
    img[4 * ((SIDE / 2) * SIDE + SIDE / 2) as usize]
}

/// Records a pass that clears the depth `view` to `ndc`.
fn clear_depth(encoder: &mut wgpu::CommandEncoder, view: &wgpu::TextureView, ndc: f32) {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("host geometry"),
        color_attachments: &[],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(ndc),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
}

#[test]
fn a_wall_behind_a_soft_sprite_fades_it_by_its_distance_over_the_fade_distance() {
    let gpu = gpu();
    for (state, compute) in [
        (State::Stateful, false),
        (State::Stateless, false),
        (State::Stateful, true),
        (State::Stateless, true),
    ] {
        let sim = probe(&gpu, state);
        let centre = |wall, bind| centre(&gpu, &sim, wall, bind, compute);
        let state = format!("{state:?}, compute {compute}");
        let full = centre(None, true);
        assert!(
            full > 200,
            "{state:?}: the unfaded centre is bright: {full}"
        );
        // The sprite is 10 m away; walls 0.25, 0.5 and 0.75 m behind it leave that fraction
        // of the 1 m fade, one 2 m behind leaves it whole. (The depth is stored as f32 and
        // linearised back: well under 1% of the fade here, under one 8-bit step.)
        for (wall, fade) in [(10.25, 0.25), (10.5, 0.5), (10.75, 0.75), (12.0, 1.0)] {
            let got = centre(Some(wall), true);
            let want = f64::from(full) * fade;
            assert!(
                (f64::from(got) - want).abs() <= 2.0,
                "{state}: wall at {wall} m: centre {got}, want {want:.1} ({fade} of {full})"
            );
        }
        // A wall in front hides the sprite: the depth test, as without soft particles.
        assert_eq!(centre(Some(9.5), true), 0, "{state}: hidden");
        // Not bound yet: the placeholder is the far plane, nothing fades.
        assert_eq!(centre(Some(10.25), false), full, "{state}: unbound");
    }
}

#[test]
fn an_orthographic_host_camera_fades_by_the_same_distances() {
    // The same eye and sprite through an orthographic projection 4 m across: depth is linear
    // in distance there, and the fade must be too.
    let gpu = gpu();
    let sim = probe(&gpu, State::Stateful);
    let perspective = Camera::from_effect(&sim.compiled().ir.camera, 1.0);
    let camera = Camera {
        view: perspective.view,
        proj: glam::Mat4::orthographic_rh(-2.0, 2.0, -2.0, 2.0, 0.1, 100.0),
    };
    for compute in [false, true] {
        let centre = |wall| centre_from(&gpu, &sim, &camera, wall, true, compute);
        let full = centre(None);
        assert!(
            full > 200,
            "compute {compute}: the unfaded centre is bright: {full}"
        );
        for (wall, fade) in [(10.25, 0.25), (10.5, 0.5), (10.75, 0.75), (12.0, 1.0)] {
            let got = centre(Some(wall));
            let want = f64::from(full) * fade;
            assert!(
                (f64::from(got) - want).abs() <= 2.0,
                "compute {compute}: wall at {wall} m: centre {got}, want {want:.1} ({fade} of {full})"
            );
        }
        assert_eq!(centre(Some(9.5)), 0, "compute {compute}: hidden");
    }
}

#[test]
fn a_soft_draw_needs_a_single_sample_depth_buffer() {
    let gpu = gpu();
    let sim = probe(&gpu, State::Stateful);
    let target = DrawTarget::new(plume::runtime::outputs::FORMAT)
        .with_depth(DEPTH)
        .with_samples(4);
    let message = sim.renderer(&target).err().expect("refused").to_string();
    assert!(
        message.contains("render.soft") && message.contains("one sample"),
        "{message}"
    );
    // Without a depth buffer there is nothing to fade against: an ordinary draw.
    let plain = sim
        .renderer(&DrawTarget::new(plume::runtime::outputs::FORMAT))
        .unwrap();
    assert!(!plain.is_soft());
}
