//! The compute renderer drawn into a host's images: the embedding API's compute renderer
//! ([`crate::EffectRenderer`] made by `Effect::compute_renderer`). Each frame, after the host has
//! drawn its depth, the compute renderer composites every group into its own HDR image, testing (and for
//! `render.soft`, fading) each pixel against a copy of the host's depth; then one full-screen
//! triangle in the host's render pass puts that image over the host's colour (`host.wgsl`).
//!
//! Nothing waits on the GPU: the entries each group's tile lists needed are copied into a small
//! buffer and read a frame or more later, when its mapping is done; a list that was too short
//! grows then (that frame's tiles lost the entries past the end; later frames have them all).

use std::sync::Mutex;

use plume_compiler::wgsl::draw::{splat_hdr_pitch, HostDepthTest, SplatHost};

use super::ComputeOffscreen;
use crate::device::async_read::AsyncRead;
use crate::device::depth_copy::{check_texture, DepthCopy};
use crate::device::gpu::Gpu;
use crate::draw::camera::Camera;
use crate::draw::target::DrawTarget;
use crate::error::RuntimeError;
use crate::sim::effect::Effect;

/// What changes from frame to frame, behind a lock (the renderer is prepared through `&self`).
struct Frame {
    splat: ComputeOffscreen,
    depth_copy: DepthCopy,
    /// The host's depth texture (set by `set_scene_depth`), copied each frame.
    scene_depth: Option<wgpu::Texture>,
    /// Per part, the entries its last frames needed, read back without waiting.
    readbacks: Vec<AsyncRead>,
    /// Whether the depth copy holds the far plane (no scene depth bound yet).
    far_written: bool,
}

/// The compute renderer of an effect into a host's `width` x `height` targets.
pub(crate) struct HostSplat {
    gpu: Gpu,
    width: u32,
    height: u32,
    /// Whether the draw tests the host's depth (the target has a depth attachment).
    tests_depth: bool,
    /// The far plane's depth: 0 for a reversed-Z test, else 1.
    far: f32,
    soft: bool,
    frame: Mutex<Frame>,
    blit: wgpu::RenderPipeline,
    /// The blit tested at one depth against the pass's depth attachment by the target's
    /// compare function ([`Self::set_composite_depth`]), and its bind group; None for a
    /// target without depth.
    blit_at_depth: Option<(wgpu::RenderPipeline, wgpu::BindGroup)>,
    /// Whether the blit is tested at a depth (set by [`Self::set_composite_depth`]).
    at_depth: std::sync::atomic::AtomicBool,
    /// The blit's uniform: the image's pitch, width and height, and the depth it is put at.
    pitch: wgpu::Buffer,
    blit_group: wgpu::BindGroup,
}

/// The compute renderer's test for a host depth test.
fn depth_test(compare: wgpu::CompareFunction) -> Result<HostDepthTest, RuntimeError> {
    Ok(match compare {
        wgpu::CompareFunction::Less => HostDepthTest::Less,
        wgpu::CompareFunction::LessEqual => HostDepthTest::LessEqual,
        wgpu::CompareFunction::Greater => HostDepthTest::Greater,
        wgpu::CompareFunction::GreaterEqual => HostDepthTest::GreaterEqual,
        wgpu::CompareFunction::Always => HostDepthTest::Always,
        other => {
            return Err(RuntimeError::Unsupported(format!(
                "the compute renderer tests depth with Less, LessEqual, Greater, GreaterEqual or Always, not {other:?}; draw with the raster renderer (Effect::renderer)"
            )))
        }
    })
}

impl HostSplat {
    /// The compute renderer of `effect` into targets like `target` of `width` x `height`.
    pub(crate) fn new(
        effect: &Effect,
        target: &DrawTarget,
        width: u32,
        height: u32,
    ) -> Result<Self, RuntimeError> {
        let gpu = effect.gpu().clone();
        let depth = target.depth.map(|d| depth_test(d.compare)).transpose()?;
        let soft = depth.is_some()
            && target.soft
            && effect
                .groups()
                .iter()
                .any(|g| g.effect.ir.render.soft.is_some());
        let host = SplatHost {
            depth,
            soft: target.soft,
        };
        let splat = ComputeOffscreen::with_host(effect, width, height, Some(host))?;
        let readbacks = splat
            .parts
            .iter()
            .map(|_| AsyncRead::new(&gpu, "splat entries needed", 4))
            .collect();
        let module = gpu.shader_module("splat over the host", include_str!("host.wgsl"));
        // Over whatever the pass holds: the compute renderer has tested depth itself, so the triangle
        // passes any depth attachment the pass has, and writes none.
        let blit_target = match target.depth {
            Some(d) => target.with_depth_compare(d.format, wgpu::CompareFunction::Always),
            None => *target,
        }
        .with_depth_writes(false);
        let premultiplied = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
            operation: wgpu::BlendOperation::Add,
        };
        let blit_pipeline = |target: &DrawTarget| {
            crate::draw::pipeline::render_pipeline(
                &gpu,
                &module,
                ("vs", "fs"),
                crate::draw::pipeline::plain(wgpu::PrimitiveTopology::TriangleList),
                target,
                wgpu::BlendState {
                    color: premultiplied,
                    alpha: premultiplied,
                },
            )
        };
        let blit = blit_pipeline(&blit_target);
        let blit_at_depth = target
            .depth
            .map(|_| blit_pipeline(&target.with_depth_writes(false)));
        let pitch = crate::device::buffers::words_buffer(
            &gpu,
            "splat host pitch",
            [splat_hdr_pitch(width), width, height, 0].into_iter(),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        // Each pipeline's own layout (derived from the module): a bind group for each.
        let blit_group = |pipeline: &wgpu::RenderPipeline| {
            gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("splat over the host"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: pitch.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: splat.parts[0].1.image().as_entire_binding(),
                    },
                ],
            })
        };
        let blit_at_depth = blit_at_depth.map(|p| {
            let group = blit_group(&p);
            (p, group)
        });
        let blit_group = blit_group(&blit);
        Ok(Self {
            gpu,
            width,
            height,
            tests_depth: depth.is_some(),
            far: match depth {
                Some(HostDepthTest::Greater | HostDepthTest::GreaterEqual) => 0.0,
                _ => 1.0,
            },
            soft,
            frame: Mutex::new(Frame {
                splat,
                depth_copy: DepthCopy::default(),
                scene_depth: None,
                readbacks,
                far_written: false,
            }),
            blit,
            blit_at_depth,
            at_depth: std::sync::atomic::AtomicBool::new(false),
            pitch,
            blit_group,
        })
    }

    /// Puts the image over the host's at NDC depth `depth`, tested against the pass's depth
    /// attachment by the target's compare function, or (None, the default) everywhere: the
    /// compute renderer has tested each pixel against its copy of the host's depth. For a
    /// host whose depth the compute renderer cannot read (a Bevy 2D camera's), so that what
    /// the host drew in front of that depth hides the effect.
    pub(crate) fn set_composite_depth(&self, depth: Option<f32>) {
        let at = depth.filter(|_| self.blit_at_depth.is_some());
        self.at_depth
            .store(at.is_some(), std::sync::atomic::Ordering::Relaxed);
        let bits = at.unwrap_or(0.0).to_bits();
        self.gpu
            .queue
            .write_buffer(&self.pitch, 12, &bits.to_le_bytes());
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Frame> {
        self.frame.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Whether `render.soft` sprites fade against the host's depth.
    pub(crate) fn is_soft(&self) -> bool {
        self.soft
    }

    /// Keeps the texture behind `depth` to copy each frame (a draw that tests no depth keeps
    /// nothing).
    pub(crate) fn set_scene_depth(&self, depth: &wgpu::TextureView) {
        if self.tests_depth {
            let mut frame = self.lock();
            frame.scene_depth = Some(depth.texture().clone());
            frame.far_written = false;
        }
    }

    /// Scales every sprite's size.
    pub(crate) fn set_size_scale(&self, scale: f32) {
        self.lock().splat.size_scale = scale;
    }

    /// Lights the lit groups' sprites with `lights`.
    pub(crate) fn set_lights(&self, lights: &plume_compiler::lights::Lights) {
        self.lock().splat.set_lights(lights);
    }

    /// Reads `map` (an array view of a depth texture) as the lit groups' shadow map.
    pub(crate) fn set_shadow_map(&self, map: &wgpu::TextureView) {
        self.lock().splat.bind_shadow_map(map);
    }

    /// (Whether a group is lit, whether one reads a shadow map.)
    pub(crate) fn lit_and_shadowed(&self) -> (bool, bool) {
        self.lock().splat.lit_and_shadowed()
    }

    /// The image size the renderer draws.
    pub(crate) fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Records the frame's splat into `encoder`: every group's preparation, the host's depth
    /// copied, the image cleared, the compute pass; and the readback of the entries needed.
    pub(crate) fn prepare(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        effect: &Effect,
        camera: &Camera,
    ) -> Result<(), RuntimeError> {
        let mut frame = self.lock();
        let frame = &mut *frame;
        // Lists a frame before found too short grow now.
        for (readback, (_, part)) in frame.readbacks.iter().zip(frame.splat.parts.iter_mut()) {
            if let Some(bytes) = readback.poll()? {
                let needed = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
                part.grow(u64::from(needed))?;
            }
        }
        if self.tests_depth {
            match &frame.scene_depth {
                Some(texture) => {
                    check_texture(texture)?;
                    if (texture.width(), texture.height()) != (self.width, self.height) {
                        return Err(RuntimeError::Output(format!(
                            "the scene depth is {}x{} but the compute renderer draws {}x{}: make a renderer of the target's size",
                            texture.width(),
                            texture.height(),
                            self.width,
                            self.height
                        )));
                    }
                    let out = frame
                        .splat
                        .host_depth
                        .as_ref()
                        .expect("made for a depth test");
                    frame.depth_copy.record(&self.gpu, encoder, texture, out);
                }
                // Until the host binds its depth, nothing hides particles: the far plane.
                None if !frame.far_written => {
                    let out = frame
                        .splat
                        .host_depth
                        .as_ref()
                        .expect("made for a depth test");
                    let pixels = self.width as usize * self.height as usize;
                    let far: Vec<u8> = std::iter::repeat_n(self.far.to_le_bytes(), pixels)
                        .flatten()
                        .collect();
                    self.gpu.queue.write_buffer(out, 0, &far);
                    frame.far_written = true;
                }
                None => {}
            }
        }
        encoder.clear_buffer(frame.splat.parts[0].1.image(), 0, None);
        frame.splat.prepare(encoder, effect, camera)?;
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("splat"),
                timestamp_writes: None,
            });
            frame.splat.record(&mut pass)?;
        }
        for (readback, (_, part)) in frame.readbacks.iter().zip(frame.splat.parts.iter()) {
            readback.record_copy(encoder, part.status());
        }
        Ok(())
    }

    /// Records the compute renderer's image over the host's colour into `pass`.
    pub(crate) fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        let at_depth = self.at_depth.load(std::sync::atomic::Ordering::Relaxed);
        match (&self.blit_at_depth, at_depth) {
            (Some((tested, group)), true) => {
                pass.set_pipeline(tested);
                pass.set_bind_group(0, group, &[]);
            }
            _ => {
                pass.set_pipeline(&self.blit);
                pass.set_bind_group(0, &self.blit_group, &[]);
            }
        }
        pass.draw(0..3, 0..1);
    }
}
