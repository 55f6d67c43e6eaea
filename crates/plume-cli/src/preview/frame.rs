//! One preview frame: the effect's steps due and its draw into the frame target (GPU
//! timestamps and counters recorded for the probe), the frame and the on-screen text onto the
//! window's surface, and screenshots of the effect's image.

use std::path::PathBuf;
use std::time::Instant;

use plume_runtime::outputs::{png, read_texture, write_atomically, Frame8};

use super::reload::Watcher;
use super::state::{Loaded, Running};
use super::Options;

impl Running {
    /// Draws one frame. Returns false when the preview should close.
    pub(super) fn frame(&mut self, options: &Options) -> Result<bool, String> {
        if let Some(noticed) = self.watcher.as_ref().and_then(Watcher::changed) {
            self.reload(Some(noticed));
        }
        let now = Instant::now();
        let elapsed = now - self.last_frame;
        self.last_frame = now;
        self.frame_ms = 0.9 * self.frame_ms + 0.1 * elapsed.as_secs_f64() * 1e3;
        // A scripted run takes one step per frame, so its frames are the same every run.
        let steps = match options.frames {
            Some(_) => 1,
            None => self.clock.steps_due(elapsed),
        };
        let (w, h) = (self.config.width, self.config.height);
        self.target.resize(&self.gpu, (w, h))?;
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        let mut stepped = None;
        let mut drawn = false;
        let mut counters = None;
        if let Some(loaded) = &mut self.effect {
            let recorded = loaded
                .effect
                .advance_timed(&mut encoder, steps, self.probe.step_writes())
                .map_err(|e| e.to_string())?;
            stepped = recorded.then_some(steps);
            let camera = self
                .orbit
                .as_ref()
                .expect("an orbit exists once an effect is loaded")
                .camera(w as f32 / h.max(1) as f32);
            // A compute renderer draws one size: a resized window needs a new one.
            if loaded.renderer.size().is_some_and(|s| s != (w, h)) {
                loaded.renderer = loaded
                    .effect
                    .compute_renderer(&loaded.target, w, h)
                    .map_err(|e| e.to_string())?;
                if let Some(meshes) = &loaded.meshes {
                    meshes
                        .bind_to(&mut loaded.renderer, &loaded.scene_lights)
                        .map_err(|e| e.to_string())?;
                }
            }
            let bg = loaded.effect.compiled().ir.render.background;
            let mut color = wgpu::RenderPassColorAttachment {
                view: self.target.view(),
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: bg.x,
                        g: bg.y,
                        b: bg.z,
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            };
            // The meshes the effect names go first, with depth; the particles are tested
            // against it (and soft ones fade against it).
            let mut depth = None;
            if let Some(meshes) = &mut loaded.meshes {
                if meshes.resize((w, h)) {
                    meshes
                        .bind_to(&mut loaded.renderer, &loaded.scene_lights)
                        .map_err(|e| e.to_string())?;
                }
                // Particles that give off light light the meshes as a recent frame's reading
                // says (read back without waiting).
                if let Some(particles) = &loaded.particle_lights {
                    let read = particles
                        .watch(&loaded.effect, &mut encoder)
                        .map_err(|e| e.to_string())?;
                    if let Some(read) = read {
                        meshes.set_lights(&loaded.scene_lights.with_sources(read));
                    }
                }
                meshes.record(&mut encoder, color.clone(), &camera);
                // A SceneDepth collider meets the meshes as this frame draws them, from the
                // next frame's steps on (this frame's were recorded above).
                if loaded.effect.collides_with_scene_depth() {
                    loaded
                        .effect
                        .set_scene_depth(
                            &mut encoder,
                            meshes.depth_texture(),
                            camera.view,
                            camera.proj,
                        )
                        .map_err(|e| e.to_string())?;
                }
                color.ops.load = wgpu::LoadOp::Load;
                depth = Some(meshes.particle_depth());
            }
            // After the meshes: the compute renderer reads the depth they drew.
            loaded
                .effect
                .prepare_draw(&mut encoder, &loaded.renderer, &camera)
                .map_err(|e| e.to_string())?;
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("effect"),
                color_attachments: &[Some(color)],
                depth_stencil_attachment: depth,
                timestamp_writes: self.probe.draw_writes(),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            loaded.renderer.draw(&mut pass);
            drop(pass);
            self.target.finish(&mut encoder);
            drawn = true;
            let top = &loaded.effect;
            counters = top
                .counters()
                .map(|c| (c, top.steps_done(), top.compiled().ir.capacity));
        }
        self.probe.record(&mut encoder, stepped, drawn, counters);
        let surface_texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => Some(t),
            _ => {
                self.surface.configure(&self.gpu.device, &self.config);
                None
            }
        };
        if let Some(texture) = &surface_texture {
            let view = texture.texture.create_view(&Default::default());
            let panels = self.panels();
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("present"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            self.target.blit(&mut pass);
            self.overlay.draw(
                &self.gpu.device,
                &self.gpu.queue,
                &mut pass,
                (w, h),
                &panels,
            );
        }
        self.gpu.queue.submit([encoder.finish()]);
        self.probe.submitted();
        self.gpu.take_error().map_err(|e| e.to_string())?;
        if let Some(texture) = surface_texture {
            self.window.pre_present_notify();
            self.gpu.queue.present(texture);
        }
        if let Some(saved) = self.reload_started.take() {
            self.reload_ms = Some(saved.elapsed().map_or(0.0, |d| d.as_secs_f64() * 1e3));
            eprintln!(
                "{}: reloaded, {:.0} ms from save to new frame",
                self.file.name(),
                self.reload_ms.unwrap_or(0.0)
            );
        }
        self.probe.collect(&self.gpu.device);
        self.loop_if_finished(options);
        self.frames += 1;
        if std::mem::take(&mut self.screenshot) {
            let path = screenshot_path(&self.file.name(), self.effect.as_ref());
            self.save_screenshot(&path)?;
            eprintln!("wrote {}", path.display());
        }
        if let Some(n) = options.frames {
            if self.frames >= n {
                if let Some(path) = &options.screenshot {
                    self.save_screenshot(path)?;
                    eprintln!("wrote {} ({} frames)", path.display(), self.frames);
                }
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// Writes the last frame (the effect's image, without the on-screen text) as a PNG.
    pub(super) fn save_screenshot(&self, path: &std::path::Path) -> Result<(), String> {
        let (w, h) = self.target.size();
        let pixels =
            read_texture(&self.gpu, self.target.texture(), w, h).map_err(|e| e.to_string())?;
        let png = png(&Frame8 {
            width: w,
            height: h,
            pixels,
        })
        .map_err(|e| e.to_string())?;
        write_atomically(path, &png, &[std::path::Path::new(&self.file.name())])
            .map_err(|e| e.to_string())
    }
}

/// `name-STEP.png` beside the current directory's files, for the `s` key.
fn screenshot_path(file: &str, loaded: Option<&Loaded>) -> PathBuf {
    let stem = std::path::Path::new(file)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "effect".into());
    let step = loaded.map_or(0, |l| l.effect.steps_done());
    PathBuf::from(format!("{stem}-{step:06}.png"))
}
