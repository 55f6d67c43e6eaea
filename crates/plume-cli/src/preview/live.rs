//! The effect running in the preview: (re)loading it from its file, replacing it all or
//! nothing, restarting it, and looping a one-shot effect whose particles have all died.

use std::time::Instant;

use plume_compiler::graph::CompiledGraph;
use plume_runtime::{DrawTarget, Effect};

use super::clock::StepClock;
use super::frame_target::FrameTarget;
use super::orbit::Orbit;
use super::reload::Outcome;
use super::state::{Loaded, Running};
use super::Options;
use crate::render::DrawMethod;

impl Running {
    /// Reloads the file (`noticed`: when a change was seen; None for the first load).
    pub(super) fn reload(&mut self, noticed: Option<Instant>) {
        match self.file.reload() {
            Outcome::Unchanged => {}
            Outcome::Replaced(compiled, warnings) => {
                if !warnings.is_empty() {
                    eprintln!("{warnings}");
                }
                match self.load(*compiled, warnings) {
                    Ok(()) => {
                        eprintln!("{}: loaded", self.file.name());
                        self.problem = None;
                        // Timed from the save itself (the file's modification time), which
                        // includes the watcher's debounce and the frame in progress.
                        self.reload_started = noticed.and(self.file.saved_at());
                    }
                    Err(e) => {
                        eprintln!("{}: error: {e}", self.file.name());
                        self.problem = Some(e);
                    }
                }
            }
            Outcome::Invalid(diagnostics) | Outcome::Unreadable(diagnostics) => {
                eprintln!("{diagnostics}");
                if self.effect.is_some() {
                    eprintln!("{}: the last good effect keeps running", self.file.name());
                }
                self.problem = Some(diagnostics);
            }
        }
    }

    /// Replaces the running effect by `compiled`, from t = 0; the camera stays where the user
    /// put it (it starts as the effect's own).
    pub(super) fn load(&mut self, compiled: CompiledGraph, warnings: String) -> Result<(), String> {
        let top = &compiled.groups[0].effect.ir;
        let mut about = format!(
            "{}: integrator {}; {}",
            top.name,
            top.integrator.name(),
            if top.stateless.is_some() {
                "stateless (0 bytes of state)"
            } else {
                "stateful"
            }
        );
        if compiled.groups.len() > 1 {
            let names: Vec<&str> = compiled.groups[1..]
                .iter()
                .map(|g| g.name.as_str())
                .collect();
            about.push_str(&format!(
                "; groups {} ({} events)",
                names.join(", "),
                compiled.streams.len()
            ));
        }
        let dt = top.dt;
        let top_name = top.name.clone();
        let camera = top.camera;
        let glow = top.render.glow;
        let triangles: Vec<_> = compiled
            .groups
            .iter()
            .flat_map(|g| g.effect.ir.scene_triangles())
            .collect();
        let format = FrameTarget::draw_format(glow.as_ref());
        let size = (self.config.width.max(1), self.config.height.max(1));
        let mut meshes = plume_runtime::outputs::Scene::new(&self.gpu, &triangles, format, size)
            .map_err(|e| e.to_string())?;
        // The file's lights light what its particles meet too, when it names any or its look
        // is lit.
        let top = &compiled.groups[0].effect.ir;
        let scene_lights = match top.render.lit.is_some() || top.lights_named {
            true => top.lights.clone(),
            false => plume_runtime::outputs::Scene::plain_lights(),
        };
        // A light that casts a shadow is blocked by the meshes' shadow map.
        let scene_lights = match &mut meshes {
            Some(meshes) => meshes
                .cast_shadow(&scene_lights)
                .map_err(|e| e.to_string())?,
            None => scene_lights,
        };
        if let Some(meshes) = &meshes {
            meshes.set_lights(&scene_lights);
        }
        let (method, why) = self.draw.resolve(&self.gpu, &compiled);
        let effect = Effect::from_graph(&self.gpu, compiled).map_err(|e| e.to_string())?;
        let target = match &meshes {
            Some(_) => plume_runtime::outputs::Scene::target(DrawTarget::new(format)),
            None => DrawTarget::new(format),
        };
        let mut renderer = match method {
            DrawMethod::Compute => effect.compute_renderer(&target, size.0, size.1),
            _ => effect.renderer(&target),
        }
        .map_err(|e| e.to_string())?;
        let drawn_by = if renderer.is_compute() {
            "compute"
        } else {
            "raster"
        };
        about.push_str(&format!("; drawn by {drawn_by} ({why})"));
        eprintln!("{}: drawn by {drawn_by} ({why})", top_name);
        if let Some(meshes) = &meshes {
            meshes
                .bind_to(&mut renderer, &scene_lights)
                .map_err(|e| e.to_string())?;
        }
        let particle_lights = match &meshes {
            Some(_) => {
                Some(effect.particle_lights().map_err(|e| e.to_string())?).filter(|p| !p.is_empty())
            }
            None => None,
        };
        // Last, and all or nothing: the old effect keeps drawing into a matching scene if this
        // fails.
        self.target.set_glow(&self.gpu, glow)?;
        self.effect = Some(Loaded {
            effect,
            renderer,
            target,
            meshes,
            scene_lights,
            particle_lights,
            about,
            warnings,
        });
        // Counters read from the old effect mean nothing for the new one.
        self.probe.totals = None;
        let mut clock = StepClock::new(dt);
        clock.scale = self.clock.scale;
        clock.paused = self.clock.paused;
        self.clock = clock;
        self.orbit
            .get_or_insert_with(|| Orbit::from_effect(&camera));
        Ok(())
    }

    /// Restarts the last good effect from t = 0 (the camera stays).
    pub(super) fn restart(&mut self) {
        if let Some(good) = self.file.good().cloned() {
            let warnings = self
                .effect
                .as_ref()
                .map(|l| l.warnings.clone())
                .unwrap_or_default();
            if let Err(e) = self.load(good, warnings) {
                self.problem = Some(e);
            }
            self.clock.restart();
        }
        self.finished_at = None;
    }

    /// A one-shot effect (bursts only) whose particles have all died starts again half a
    /// second later, so the window never sits empty. Not in scripted runs.
    pub(super) fn loop_if_finished(&mut self, options: &Options) {
        if options.frames.is_some() || self.clock.paused {
            return;
        }
        let Some(loaded) = &self.effect else {
            return;
        };
        // With groups, the top group's end is not the effect's (its children live on).
        let top = &loaded.effect;
        let one_shot = top.group_names().len() == 1
            && top
                .compiled()
                .ir
                .emitters
                .iter()
                .all(|e| e.spawns_once_at_start());
        let totals = match top.counters() {
            Some(_) => self.probe.totals,
            None => top.group_totals(0).ok(),
        };
        let done =
            one_shot && top.steps_done() > 0 && totals.is_some_and(|t| t.alive == 0 && t.steps > 0);
        if !done {
            self.finished_at = None;
            return;
        }
        let since = *self.finished_at.get_or_insert_with(Instant::now);
        if since.elapsed().as_secs_f64() > 0.5 {
            self.restart();
        }
    }
}
