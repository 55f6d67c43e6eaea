//! Received shadows (`plume_compiler::shadow`) on llvmpipe: a lit sprite or surface gets of
//! the shadowed light exactly what its shadow map lets through. A host's map through the
//! embedding API (standard and reversed depth), pixel by pixel across the shadow's edge, and
//! the map `plume render` draws from the scene's meshes, on the ground and on lit particles;
//! the lookup at each pixel and once a particle (`shadow_at: Particle`) on a sprite and a mesh
//! particle (drawn by both renderers), and
//! how little it changes a picture of smoke;
//! each pixel against the f64 light ([`Shadow::visibility`] on the map's depths read back) in
//! both renderers: within one 8-bit step for an opaque surface, two for a sprite's blended
//! pixel (llvmpipe blends an 8-bit target in 8-bit fixed point: the source colour and its
//! alpha are each rounded to a step before they multiply, then the result).

mod common;

use common::meshes::{box_obj, write};
use common::*;
use glam::{DMat4, DVec3};
use plume::compiler::lights::{LightSource, Lights};
use plume::compiler::shadow::{Shadow, ShadowDepths};
use plume::runtime::outputs::{ComputeOffscreen, Offscreen, Scene, SCENE_GREY};
use plume::runtime::{Camera, Effect, Gpu};

const COLOR: [f64; 3] = [0.8, 0.6, 0.4];

/// The images of `sim` from `camera`, over `scene` when given, by the raster draw and the
/// compute renderer, each given `lights` and `map` first when given (a host's).
fn images(
    gpu: &Gpu,
    sim: &Effect,
    camera: &Camera,
    (w, h): (u32, u32),
    scene: Option<(&Scene, &Lights)>,
    host: Option<(&Lights, &wgpu::Texture)>,
) -> Vec<(&'static str, Vec<u8>)> {
    let target = Offscreen::new(gpu, w, h).unwrap();
    let draw_target = match scene {
        Some(_) => Scene::target(target.target()),
        None => target.target(),
    };
    let mut out = Vec::new();
    for (kind, compute) in [("raster", false), ("compute renderer", true)] {
        let mut renderer = match compute {
            true => sim.compute_renderer(&draw_target, w, h).unwrap(),
            false => sim.renderer(&draw_target).unwrap(),
        };
        if let Some((lights, map)) = host {
            renderer.set_lights(lights);
            renderer.set_shadow_map(map).unwrap();
        }
        let image = match scene {
            Some((scene, lights)) => {
                scene.bind_to(&mut renderer, lights).unwrap();
                target
                    .render_over_scene(sim, &renderer, camera, scene)
                    .unwrap()
            }
            None => target.render(sim, &renderer, camera).unwrap(),
        };
        out.push((kind, image));
    }
    out
}

/// A `side` x `side` depth texture holding `far` but in its left half, which holds `near`.
fn half_map(gpu: &Gpu, side: u32, (near, far): (f32, f32)) -> wgpu::Texture {
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
    let format = wgpu::TextureFormat::Depth32Float;
    let map = gpu.texture_2d("host shadow", (side, side), format, usage);
    let source = format!(
        "@vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {{
            let p = vec2<f32>(f32(i & 1u) * 4.0 - 1.0, f32(i >> 1u) * 4.0 - 1.0);
            return vec4<f32>(p, {near:?}, 1.0);
        }}"
    );
    let module = gpu
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("half map"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
    let pipeline = gpu
        .device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("half map"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: None,
            multiview_mask: None,
            cache: None,
        });
    let view = map.create_view(&Default::default());
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("half map"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(far),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_viewport(0.0, 0.0, (side / 2) as f32, side as f32, 0.0, 1.0);
        pass.draw(0..3, 0..1);
    }
    gpu.queue.submit([encoder.finish()]);
    map
}

/// A host's shadow map seen from 5 m along +z, orthographic over x and y in [−4, 4] and depth
/// over [0, 10] m, 16 x 16 texels: its left half (x < 0) holds a surface 2.5 m from the light,
/// its right half nothing; and the lights that name it (ambient 0.1, a white light travelling
/// along −z that the map shadows), with its depths for the f64 verdicts.
fn host_shadow(gpu: &Gpu, reversed: bool) -> (Lights, wgpu::Texture) {
    const MAP: u32 = 16;
    let sun_view = DMat4::look_at_rh(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y);
    // Depth 0.25 is 2.5 m from the light; the origin is at 5 m (0.5).
    let (near, far, projection) = match reversed {
        false => (
            0.25,
            1.0,
            DMat4::orthographic_rh(-4.0, 4.0, -4.0, 4.0, 0.0, 10.0),
        ),
        true => (
            0.75,
            0.0,
            DMat4::orthographic_rh(-4.0, 4.0, -4.0, 4.0, 10.0, 0.0),
        ),
    };
    let map = half_map(gpu, MAP, (near, far));
    let layer = (0..MAP * MAP)
        .map(|i| if i % MAP < MAP / 2 { near } else { far })
        .collect();
    let lights = Lights {
        ambient: DVec3::splat(0.1),
        sources: vec![LightSource::Directional {
            direction: -DVec3::Z,
            color: DVec3::ONE,
        }],
        shadow: Some(Shadow {
            source: 0,
            cascades: vec![projection * sun_view],
            reversed,
            depths: Some(ShadowDepths {
                width: MAP,
                height: MAP,
                layers: vec![layer],
            }),
        }),
    };
    (lights, map)
}

/// `effect` run `steps` steps, its camera at the aspect of a `w` x `h` image, and the scene
/// its meshes make in that size, lit by its lights with the shadow map they cast.
fn run_in_scene(
    gpu: &Gpu,
    effect: plume::CompiledEffect,
    steps: u64,
    (w, h): (u32, u32),
) -> (Effect, Camera, Scene, Lights) {
    let triangles = effect.ir.scene_triangles();
    let mut sim = Effect::new(gpu, effect).unwrap();
    sim.run(steps, |_| {}).unwrap();
    let camera = Camera::from_effect(&sim.compiled().ir.camera, w as f32 / h as f32);
    let format = Offscreen::new(gpu, 1, 1).unwrap().target().color_format;
    let mut scene = Scene::new(gpu, &triangles, format, (w, h))
        .unwrap()
        .expect("a scene");
    let lights = scene.cast_shadow(&sim.compiled().ir.lights).unwrap();
    scene.set_lights(&lights);
    (sim, camera, scene, lights)
}

/// How far (8-bit steps) a sprite's blended pixel may be from the f64 one (see the top).
const BLENDED: f64 = 2.0;

/// The Alpha-blended colour (0 to 255) over black of a soft round sprite of `COLOR` lit by
/// `light`, at the pixel whose centre is `offset` pixels from its centre, `radius` pixels
/// across.
fn sprite_pixel(light: DVec3, offset: (f64, f64), radius: f64) -> [f64; 3] {
    let r2 = (offset.0 * offset.0 + offset.1 * offset.1) / (radius * radius);
    let alpha = (1.0 - r2).max(0.0).powi(2);
    (DVec3::from_array(COLOR) * light * alpha)
        .clamp(DVec3::ZERO, DVec3::ONE)
        .to_array()
        .map(|x| x * 255.0)
}

fn pixel(image: &[u8], w: u32, (x, y): (u32, u32)) -> [u8; 3] {
    let at = 4 * (y * w + x) as usize;
    [image[at], image[at + 1], image[at + 2]]
}

/// One flat lit sprite 2.5 m across its radius at the origin, facing the camera 10 m away
/// along +z, under the host's map of `host_shadow` (its left half in front of the sprite).
/// Each pixel of two rows across the sprite, the shadow's edge among them, is the f64 light
/// with the map's verdict, in both renderers, for a standard and a reversed map.
#[test]
fn a_hosts_shadow_map_darkens_a_lit_sprite_by_its_verdict() {
    hosts_map_across_a_sprite("Pixel");
}

/// As above with `shadow_at: Particle`: the map is looked up once, at the sprite's centre,
/// which lies on the shadow's edge (half lit by the bilinear blend), so every pixel of the
/// sprite takes half the light on both sides of the edge, as the f64 twin
/// (`Lights::seen_from_particle`) says.
#[test]
fn a_sprite_looked_up_once_takes_its_centres_verdict_at_every_pixel() {
    hosts_map_across_a_sprite("Particle");
}

/// The host's map of the two tests above across a lit sprite looked up `shadow_at`.
fn hosts_map_across_a_sprite(shadow_at: &str) {
    const SIDE: u32 = 65;
    let gpu = gpu();
    let [r, g, b] = COLOR;
    let src = format!(
        r#"Effect(name: "shadowed", capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    render: Render(color: [(0.0, ({r}, {g}, {b}, 1.0))], size: [(0.0, 5.0)],
                   background: (0.0, 0.0, 0.0), lit: Some(Lit(normals: Flat, shadow_at: {shadow_at}))))"#
    );
    // No light of the file casts a shadow: the host's map is read because it asks for it.
    let options = plume::CompileOptions {
        receive_shadows: true,
        ..Default::default()
    };
    let effect = plume::compile_str(&src, &options).unwrap();
    let mut sim = Effect::new(&gpu, effect).unwrap();
    sim.run(1, |_| {}).unwrap();
    let camera = Camera::from_effect(&sim.compiled().ir.camera, 1.0);
    let radius = 2.5 / (10.0 * 20f64.to_radians().tan()) * f64::from(SIDE) / 2.0;
    for reversed in [false, true] {
        let (lights, map) = host_shadow(&gpu, reversed);
        let metres = 2.5 / radius;
        let shadowed = lights.received(DVec3::Z, DVec3::new(-1.0, 0.0, 0.0), 0.0);
        let lit = lights.received(DVec3::Z, DVec3::new(1.0, 0.0, 0.0), 0.0);
        assert_eq!((shadowed.x, lit.x), (0.1, 1.1), "the map's verdicts");
        let per_particle = shadow_at == "Particle";
        let seen = match per_particle {
            true => lights.seen_from_particle(DVec3::ZERO),
            false => lights.clone(),
        };
        if per_particle {
            let half = seen.received(DVec3::Z, DVec3::new(1.0, 0.0, 0.0), 0.0);
            assert_eq!(half.x, 0.6, "the centre's verdict: half lit");
        }
        let mut wrong = Vec::new();
        let mut ramp = 0;
        for (kind, image) in images(
            &gpu,
            &sim,
            &camera,
            (SIDE, SIDE),
            None,
            Some((&lights, &map)),
        ) {
            for up in [0, 6] {
                for right in -8..=8 {
                    let p = DVec3::new(f64::from(right), f64::from(up), 0.0) * metres;
                    let light = seen.received(DVec3::Z, p, 0.0);
                    ramp += usize::from(light.x > 0.1 && light.x < 1.1);
                    let offset = (f64::from(right), f64::from(up));
                    let want = sprite_pixel(light, offset, radius);
                    let c = (SIDE / 2) as i32;
                    let xy = ((c + right) as u32, (c - up) as u32);
                    let got = pixel(&image, SIDE, xy);
                    if (0..3).any(|k| (f64::from(got[k]) - want[k]).abs() > BLENDED) {
                        wrong.push(format!("{kind}, shadow_at {shadow_at}, reversed {reversed}: pixel ({right}, {up}) is {got:?}, the f64 light gives {want:.2?}"));
                    }
                }
            }
        }
        assert!(wrong.is_empty(), "{}", wrong.join("\n"));
        // Looked up at each pixel, the rows cross the edge's ramp; once a particle, every
        // pixel has the centre's half light.
        let ramp_pixels = match per_particle {
            true => 2 * 2 * 17,
            false => 4,
        };
        assert!(
            ramp >= ramp_pixels,
            "{shadow_at}: {ramp} pixels between shadow and light, want {ramp_pixels}"
        );
    }
}

/// A wall 4 m high on a floor, a sun low from the left and toward the camera that casts its
/// shadow (`shadow: true`), and two lit sprites beside the wall: one low (in the wall's
/// shadow), one high (in the sun). The map `plume render` draws from the scene's meshes says
/// so (its f64 verdicts), and the floor in and out of the shadow, and each sprite's centre,
/// are the f64 light with those verdicts, in both renderers.
#[test]
fn the_scenes_meshes_shadow_the_ground_and_lit_particles() {
    const W: u32 = 320;
    const H: u32 = 180;
    let wall = write(
        "shadow-wall.obj",
        &box_obj([-2.15, 0.0, -2.5], [-1.85, 4.0, 2.5]),
    );
    let floor = write(
        "shadow-floor.obj",
        &box_obj([-6.0, -0.1, -6.0], [6.0, 0.0, 6.0]),
    );
    let [r, g, b] = COLOR;
    let (low, high) = (DVec3::new(1.0, 1.0, 0.0), DVec3::new(1.0, 3.5, 0.0));
    let src = format!(
        r#"Effect(name: "beside the wall", capacity: 2,
    emitters: [
        Emitter(burst: 1, shape: Point(({}, {}, {})), velocity: Constant((0.0, 0.0, 0.0))),
        Emitter(burst: 1, shape: Point(({}, {}, {})), velocity: Constant((0.0, 0.0, 0.0))),
    ],
    camera: Camera(eye: (0.0, 2.0, 12.0), target: (0.0, 2.0, 0.0), fov_y: 45.0),
    scene: [Mesh(file: {wall:?}), Mesh(file: {floor:?})],
    lights: [Directional(direction: (1.0, -0.5, -0.5), shadow: true), Ambient(intensity: 0.2)],
    render: Render(color: [(0.0, ({r}, {g}, {b}, 1.0))], size: [(0.0, 2.0)],
                   background: (0.0, 0.0, 0.0), lit: Some(Lit(normals: Flat))))"#,
        low.x, low.y, low.z, high.x, high.y, high.z
    );
    let gpu = gpu();
    let (sim, camera, scene, lights) = run_in_scene(&gpu, compile(&src), 1, (W, H));
    let mut with_depths = lights.clone();
    let map = scene.shadow_map().expect("a shadow map");
    with_depths.shadow.as_mut().unwrap().depths = Some(map.read_depths().unwrap());
    let seen = |p: DVec3| with_depths.shadow.as_ref().unwrap().visibility(p);
    // Back toward the light, (3, 0, −2) and the low sprite meet the wall; the others pass.
    let (shadowed_floor, lit_floor) = (DVec3::new(3.0, 0.0, -2.0), DVec3::new(-4.0, 0.0, -2.0));
    let verdicts = [shadowed_floor, lit_floor, low, high].map(seen);
    assert_eq!(verdicts, [0.0, 1.0, 0.0, 1.0], "the map's verdicts");
    let mut wrong = Vec::new();
    for (kind, image) in images(&gpu, &sim, &camera, (W, H), Some((&scene, &lights)), None) {
        for floor_point in [shadowed_floor, lit_floor] {
            let (x, y) = camera.project(W, H, floor_point).unwrap();
            let got = pixel(&image, W, (x as u32, y as u32));
            let light = with_depths.received(DVec3::Y, floor_point, 0.0);
            let want = [0, 1, 2].map(|c| f64::from(SCENE_GREY[c]) * light[c] * 255.0);
            if (0..3).any(|k| (f64::from(got[k]) - want[k]).abs() > 1.0) {
                wrong.push(format!(
                    "{kind}: the floor at {floor_point} is {got:?}, the f64 light gives {want:.2?}"
                ));
            }
        }
        for centre in [low, high] {
            let (x, y) = camera.project(W, H, centre).unwrap();
            let (px, py) = (x.floor(), y.floor());
            // 12 m away: the image's half height spans 12 tan 22.5° m.
            let radius = 1.0 / (12.0 * 22.5f64.to_radians().tan()) * f64::from(H) / 2.0;
            let offset = (f64::from(px + 0.5 - x), f64::from(y - py - 0.5));
            let light = with_depths.received(DVec3::Z, centre, 0.0);
            let want = sprite_pixel(light, offset, radius);
            let got = pixel(&image, W, (px as u32, py as u32));
            if (0..3).any(|k| (f64::from(got[k]) - want[k]).abs() > BLENDED) {
                wrong.push(format!(
                    "{kind}: the sprite at {centre} is {got:?}, the f64 light gives {want:.2?}"
                ));
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// A lit look whose file casts no shadow, compiled without `receive_shadows`, holds no shadow
/// lookup (its draw is what it was before shadows existed), and a host's map is refused with
/// the reason rather than silently ignored; an unlit effect takes one and ignores it.
#[test]
fn a_lit_look_reads_shadows_only_where_asked() {
    let gpu = gpu();
    let lit = r#"Effect(name: "plain", capacity: 4,
    emitters: [Emitter(burst: 4, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    render: Render(lit: Some(Lit(normals: Sphere))))"#;
    let plain = compile(lit);
    assert!(!plain.draw_wgsl.contains("shadow_map"), "an unasked lookup");
    let sim = Effect::new(&gpu, plain).unwrap();
    let target = Offscreen::new(&gpu, 8, 8).unwrap();
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
    let format = wgpu::TextureFormat::Depth32Float;
    let map = gpu.texture_2d("map", (4, 4), format, usage);
    for mut renderer in [
        sim.renderer(&target.target()).unwrap(),
        sim.compute_renderer(&target.target(), 8, 8).unwrap(),
    ] {
        let error = renderer.set_shadow_map(&map).unwrap_err().to_string();
        assert!(error.contains("receive_shadows"), "{error}");
    }
    let asked = plume::CompileOptions {
        receive_shadows: true,
        ..Default::default()
    };
    let shadowed = plume::compile_str(lit, &asked).unwrap();
    assert!(shadowed.draw_wgsl.contains("shadow_visibility"));
    let unlit = lit.replace(",\n    render: Render(lit: Some(Lit(normals: Sphere)))", "");
    assert!(!unlit.contains("Lit"), "{unlit}");
    let unlit = compile(&unlit);
    let sim = Effect::new(&gpu, unlit).unwrap();
    let mut renderer = sim.renderer(&target.target()).unwrap();
    renderer.set_shadow_map(&map).unwrap();
}

/// effects/shadowed_smoke.ron drawn with its shadow looked up at every pixel and once a
/// particle (`shadow_at: Particle`), after 4 s of smoke, in both renderers: the two images
/// are told apart by few pixels, and by little (the bounds below; docs/effect-format.md,
/// "Received shadows", quotes the figures this prints). Puffs are small beside the wall's
/// shadow, so a puff across its edge is the only one whose pixels differ, and it is seen
/// through the many puffs over it.
#[test]
fn smoke_looked_up_once_a_particle_looks_as_looked_up_at_every_pixel() {
    const W: u32 = 320;
    const H: u32 = 180;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("effects/shadowed_smoke.ron");
    let per_pixel = std::fs::read_to_string(&path).unwrap();
    let per_particle = per_pixel.replace("wrap: 0.3)", "wrap: 0.3, shadow_at: Particle)");
    assert_ne!(per_pixel, per_particle);
    let gpu = gpu();
    let mut drawn = Vec::new();
    for source in [&per_pixel, &per_particle] {
        let options = plume::CompileOptions {
            base_dir: path.parent().map(|p| p.to_path_buf()),
            ..Default::default()
        };
        let effect = plume::compile_str(source, &options).unwrap();
        let (sim, camera, scene, lights) = run_in_scene(&gpu, effect, 240, (W, H));
        drawn.push(images(
            &gpu,
            &sim,
            &camera,
            (W, H),
            Some((&scene, &lights)),
            None,
        ));
    }
    let (pixel, particle) = (&drawn[0], &drawn[1]);
    for ((kind, a), (_, b)) in pixel.iter().zip(particle) {
        let (mean, most, over) = differences(a, b, 8);
        let changed = differences(a, b, 0).2;
        let channels = a.len();
        eprintln!("{kind}: mean {mean:.4} steps, largest {most}, {changed} of {channels} channels differ, {over} by more than 8 steps");
        assert!(
            changed > 0,
            "{kind}: the lookups differ somewhere (puffs cross the edge)"
        );
        assert!(mean < 0.05, "{kind}: mean difference {mean} steps");
        assert!(
            over * 1000 < channels,
            "{kind}: {over} channels differ by more than 8 steps"
        );
    }
}

/// A lit cube drawn as a mesh particle (`render.mesh`, an opaque 2 m cube at the origin, its
/// front face toward the camera) under the host's map of `host_shadow`, whose shadow's edge
/// runs through its centre: looked up once a particle, its front face is evenly half lit on
/// both sides of the edge (ambient 0.1 plus half the light), as `Lights::seen_from_particle`
/// says, within one 8-bit step (opaque: nothing blended).
/// Pixels across the 65-pixel image of [`cube_in_the_hosts_shadow`].
const CUBE_SIDE: u32 = 65;

/// A lit cube 2 m across at the origin, its front face toward the camera 10 m away, in the
/// host's half-shadowed map (standard depth) looked up `shadow_at`, drawn by the raster
/// pipeline and by the compute renderer: the images, the host's lights and the look.
fn cube_in_the_hosts_shadow(
    shadow_at: &str,
) -> (
    Vec<(&'static str, Vec<u8>)>,
    Lights,
    plume::compiler::lit::Lit,
) {
    let gpu = gpu();
    let cube = write("shadow-cube.obj", &box_obj([-0.5; 3], [0.5; 3]));
    let [r, g, b] = COLOR;
    let src = format!(
        r#"Effect(name: "shadowed cube", capacity: 1,
    emitters: [Emitter(burst: 1, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    camera: Camera(eye: (0.0, 0.0, 10.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    render: Render(color: [(0.0, ({r}, {g}, {b}, 1.0))], size: [(0.0, 2.0)], blend: Opaque,
                   background: (0.0, 0.0, 0.0), mesh: Some(ParticleMesh(file: {cube:?})),
                   lit: Some(Lit(normals: Flat, shadow_at: {shadow_at}))))"#
    );
    let options = plume::CompileOptions {
        receive_shadows: true,
        ..Default::default()
    };
    let effect = plume::compile_str(&src, &options).unwrap();
    let lit = effect.ir.render.lit.clone().unwrap();
    let mut sim = Effect::new(&gpu, effect).unwrap();
    sim.run(1, |_| {}).unwrap();
    let camera = Camera::from_effect(&sim.compiled().ir.camera, 1.0);
    let (lights, map) = host_shadow(&gpu, false);
    let target = Offscreen::new(&gpu, CUBE_SIDE, CUBE_SIDE).unwrap();
    let mut renderer = sim.renderer(&target.target()).unwrap();
    renderer.set_lights(&lights);
    renderer.set_shadow_map(&map).unwrap();
    let raster = target.render(&sim, &renderer, &camera).unwrap();
    let mut compute = ComputeOffscreen::new(&sim, CUBE_SIDE, CUBE_SIDE).unwrap();
    compute.set_lights(&lights);
    compute.set_shadow_map(&map).unwrap();
    let computed = compute.render(&sim, &camera).unwrap();
    (
        vec![("raster", raster), ("compute renderer", computed)],
        lights,
        lit,
    )
}

#[test]
fn a_mesh_particle_looked_up_once_takes_its_centres_verdict() {
    let (images, lights, lit) = cube_in_the_hosts_shadow("Particle");
    let seen = lights.seen_from_particle(DVec3::ZERO);
    let light = seen.received(DVec3::Z, DVec3::new(0.0, 0.0, 1.0), 0.0);
    assert_eq!(light.x, 0.6, "the centre's verdict: half lit");
    let want = lit.shade(DVec3::from(COLOR), light) * 255.0;
    // The face spans about 10 pixels either side of the centre: 5 pixels in, each side.
    let c = CUBE_SIDE / 2;
    for (kind, image) in &images {
        for xy in [(c - 5, c), (c + 5, c), (c, c - 5), (c - 5, c + 5)] {
            let got = pixel(image, CUBE_SIDE, xy);
            for k in 0..3 {
                let diff = (f64::from(got[k]) - want[k]).abs();
                assert!(
                    diff <= 1.0,
                    "{kind}: pixel {xy:?} is {got:?}, the f64 light gives {want:?}"
                );
            }
        }
    }
}

/// As above, looked up at each pixel (the default): a mesh is lit per pixel, so across its
/// face each pixel takes the map's verdict at the point it shows, from shadow to light.
#[test]
fn a_mesh_particle_takes_the_maps_verdict_at_each_pixel() {
    let (images, lights, lit) = cube_in_the_hosts_shadow("Pixel");
    // The front face lies 9 m from the eye: metres a pixel there.
    let metres = 2.0 * 9.0 * 20f64.to_radians().tan() / f64::from(CUBE_SIDE);
    let c = (CUBE_SIDE / 2) as i32;
    let (mut darkest, mut brightest) = (f64::INFINITY, 0f64);
    let mut wrong = Vec::new();
    for (kind, image) in &images {
        for up in [-6, 0, 6] {
            for right in -8..=8 {
                let p = DVec3::new(f64::from(right) * metres, f64::from(up) * metres, 1.0);
                let light = lights.received(DVec3::Z, p, 0.0);
                (darkest, brightest) = (darkest.min(light.x), brightest.max(light.x));
                let want = lit.shade(DVec3::from(COLOR), light) * 255.0;
                let got = pixel(image, CUBE_SIDE, ((c + right) as u32, (c - up) as u32));
                if (0..3).any(|k| (f64::from(got[k]) - want[k]).abs() > 1.0) {
                    wrong.push(format!(
                        "{kind}: pixel ({right}, {up}) is {got:?}, the f64 light gives {want:.2?}"
                    ));
                }
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    assert!(
        darkest == 0.1 && brightest == 1.1,
        "the rows cross the shadow's edge: light from {darkest} to {brightest}"
    );
}
