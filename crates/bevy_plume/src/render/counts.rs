//! What `PlumeDiagnosticsPlugin` asks the render world for beyond its counts of instances and
//! draws: every instance's and batch's particle counts, read back without waiting after the
//! frame's steps (`Effect::watch_totals`), and the GPU time of the frame's steps, from two
//! timestamps around them where the device has timestamp queries. Nothing is read back while
//! the diagnostics plugin is not added (this resource is absent).

use std::collections::HashMap;
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::{Arc, Mutex};

use bevy::prelude::*;
use plume_compiler::reference::Totals;
use plume_runtime::Gpu;

use crate::render::batches::PlumeBatches;
use crate::render::instances::{PlumeInstances, PlumeRenderStats};

/// The readings the diagnostics ask for (inserted into the render world by
/// `PlumeDiagnosticsPlugin`), and each effect entity's last counts, shared with the main world.
#[derive(Resource, Default)]
pub(crate) struct WatchedCounts {
    timer: Option<StepTimer>,
    /// Nanoseconds of the last timed frame's steps.
    last_step_ns: Option<u64>,
    /// Every running instance's last counts, by main-world entity (batched entities aside).
    pub shared: SharedCounts,
}

/// Each effect entity's last counts: written by the render world, read by the main world.
#[derive(Resource, Clone, Default)]
pub(crate) struct SharedCounts(pub Arc<Mutex<HashMap<Entity, Totals>>>);

impl SharedCounts {
    /// The map, even if a panicking thread left it poisoned.
    pub fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<Entity, Totals>> {
        self.0.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// Free, the timestamps written (copy recorded), mapping, mapped.
const IDLE: u8 = 0;
const COPIED: u8 = 1;
const MAPPING: u8 = 2;
const MAPPED: u8 = 3;

/// Two timestamps around the frame's steps, resolved and read back without waiting.
struct StepTimer {
    set: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    read: wgpu::Buffer,
    state: Arc<AtomicU8>,
    /// Nanoseconds a tick.
    period: f32,
    /// Whether this frame's first timestamp was written.
    begun: bool,
}

impl StepTimer {
    fn new(gpu: &Gpu) -> Option<Self> {
        if !gpu.has_timestamps() {
            return None;
        }
        let buffer = |label: &str, usage| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 16,
                usage,
                mapped_at_creation: false,
            })
        };
        Some(Self {
            set: gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("plume steps timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            }),
            resolved: buffer(
                "plume steps timestamps resolved",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            read: buffer(
                "plume steps timestamps read",
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            ),
            state: Arc::new(AtomicU8::new(IDLE)),
            period: gpu.queue.get_timestamp_period(),
            begun: false,
        })
    }

    /// An empty compute pass that writes timestamp `index` at its start (0) or end (1).
    fn stamp(&self, encoder: &mut wgpu::CommandEncoder, index: u32) {
        encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("plume steps timestamp"),
            timestamp_writes: Some(wgpu::ComputePassTimestampWrites {
                query_set: &self.set,
                beginning_of_pass_write_index: (index == 0).then_some(0),
                end_of_pass_write_index: (index == 1).then_some(1),
            }),
        });
    }

    /// Takes a reading that came back (nanoseconds), and stamps the start of this frame's
    /// steps when the last reading was taken.
    fn begin(&mut self, encoder: &mut wgpu::CommandEncoder) -> Option<u64> {
        let mut taken = None;
        match self.state.load(Ordering::Acquire) {
            COPIED => {
                self.state.store(MAPPING, Ordering::Release);
                let state = self.state.clone();
                self.read
                    .slice(..)
                    .map_async(wgpu::MapMode::Read, move |r| {
                        state.store(if r.is_ok() { MAPPED } else { IDLE }, Ordering::Release);
                    });
            }
            MAPPED => {
                if let Ok(bytes) = self.read.slice(..).get_mapped_range() {
                    let tick = |at: usize| {
                        u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"))
                    };
                    let ticks = tick(8).saturating_sub(tick(0));
                    taken = Some((ticks as f64 * f64::from(self.period)) as u64);
                }
                self.read.unmap();
                self.state.store(IDLE, Ordering::Release);
            }
            _ => {}
        }
        self.begun = self.state.load(Ordering::Acquire) == IDLE;
        if self.begun {
            self.stamp(encoder, 0);
        }
        taken
    }

    /// Stamps the end of the frame's steps and records the timestamps' copy, when begun.
    fn end(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if !std::mem::take(&mut self.begun) {
            return;
        }
        self.stamp(encoder, 1);
        encoder.resolve_query_set(&self.set, 0..2, &self.resolved, 0);
        encoder.copy_buffer_to_buffer(&self.resolved, 0, &self.read, 0, 16);
        self.state.store(COPIED, Ordering::Release);
    }
}

impl WatchedCounts {
    /// Before the frame's steps: takes the steps' time that came back and stamps their start.
    pub(crate) fn begin(&mut self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder) {
        if self.timer.is_none() {
            self.timer = StepTimer::new(gpu);
        }
        if let Some(timer) = &mut self.timer {
            if let Some(ns) = timer.begin(encoder) {
                self.last_step_ns = Some(ns);
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
        stats.step_gpu_ns = self.last_step_ns;
    }
}
