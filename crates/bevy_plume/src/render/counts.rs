//! What `PlumeDiagnosticsPlugin` asks the render world for beyond its counts of instances and
//! draws: every instance's and batch's particle counts, read back without waiting after the
//! frame's steps (`Effect::watch_totals`), and the GPU time of the frame's steps, from two
//! timestamps around them where the device has timestamp queries. Nothing is read back while
//! the diagnostics plugin is not added (this resource is absent).

use bevy::prelude::*;
use plume_compiler::reference::Totals;
use plume_runtime::{Gpu, GpuTimer};

use crate::render::batches::PlumeBatches;
use crate::render::instances::{PlumeInstances, PlumeRenderStats};

/// The readings the diagnostics ask for (inserted into the render world by
/// `PlumeDiagnosticsPlugin`), and each effect entity's last counts, shared with the main world.
#[derive(Resource, Default)]
pub(crate) struct WatchedCounts {
    timer: Option<GpuTimer>,
    /// Nanoseconds of the last timed frame's steps.
    last_step_ns: Option<u64>,
    /// Every running instance's last counts, by main-world entity (batched entities aside).
    pub shared: SharedCounts,
    /// Each timed instance's last GPU times ([`crate::PlumeGpuTime`]), by main-world entity.
    pub gpu_times: SharedGpuTimes,
}

/// Each timed effect entity's GPU times: written by the render world, read by the main world.
pub(crate) type SharedGpuTimes = crate::shared::EntityShared<GpuTimes>;

/// A timed effect entity's last GPU times in nanoseconds: its steps', and its draws' summed
/// over the cameras that drew it (each `None` until read).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct GpuTimes {
    pub steps_ns: Option<u64>,
    pub draw_ns: Option<u64>,
}

/// Each effect entity's last counts: written by the render world, read by the main world.
pub(crate) type SharedCounts = crate::shared::EntityShared<Totals>;

impl WatchedCounts {
    /// Before the frame's steps: takes the steps' time that came back and stamps their start.
    pub(crate) fn begin(&mut self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder) {
        if self.timer.is_none() {
            self.timer = GpuTimer::new(gpu);
        }
        if let Some(timer) = &mut self.timer {
            match timer.begin(encoder) {
                Ok(Some(ns)) => self.last_step_ns = Some(ns),
                Ok(None) => {}
                Err(err) => warn_once!("plume steps' timer: {err}"),
            }
        }
    }

    /// After the frame's steps: stamps their end, records every instance's and batch's
    /// counts' copy, takes the counts that came back, and puts the last known ones into
    /// `stats` and the shared map.
    pub(crate) fn end(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        store: &mut PlumeInstances,
        batches: &mut PlumeBatches,
        stats: &mut PlumeRenderStats,
    ) {
        if let Some(timer) = &mut self.timer {
            timer.end(encoder);
        }
        let mut shared = self.shared.lock();
        shared.retain(|entity, _| store.instances.contains_key(entity));
        let mut alive = 0;
        for (entity, instance) in store.instances.iter_mut() {
            match instance.effect.watch_totals(encoder) {
                Ok(Some(totals)) => instance.counts = Some(totals),
                Ok(None) => {}
                Err(err) => warn_once!("{}: {err}", instance.effect.compiled().ir.name),
            }
            if let Some(totals) = instance.counts {
                alive += totals.alive;
                shared.insert(*entity, totals);
            }
        }
        for batch in batches.batches_mut() {
            match batch.batch.effect().watch_totals(encoder) {
                Ok(Some(totals)) => batch.alive = totals.alive,
                Ok(None) => {}
                Err(err) => warn_once!("{}: {err}", batch.batch.compiled().ir.name),
            }
            alive += batch.alive;
        }
        stats.live_particles = alive;
        let mut times = self.gpu_times.lock();
        times.clear();
        for (entity, instance) in store.instances.iter().filter(|(_, i)| i.timed) {
            let draws = instance
                .views
                .values()
                .filter_map(|d| d.timing.as_ref()?.ns());
            let draw_ns = draws.reduce(|a, b| a + b);
            times.insert(
                *entity,
                GpuTimes {
                    steps_ns: instance.step_gpu_ns,
                    draw_ns,
                },
            );
        }
        stats.step_gpu_ns = self.last_step_ns;
    }
}
