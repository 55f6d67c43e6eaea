//! The preview's live figures, read from the GPU without waiting for it: the time of the
//! frame's step passes and of its draw (GPU timestamps, where the adapter has them) and the
//! effect's counters (live, dropped). A frame records a read only when the last one has been
//! collected; a read is collected once the GPU has delivered it, a frame or two later.

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;

use plume_compiler::reference::Totals;
use plume_runtime::Effect;

/// Bytes of the staging buffer: 4 timestamps (u64), then the 6 counters (u32, padded).
const TIMESTAMPS: u64 = 32;
const STAGING: u64 = TIMESTAMPS + 32;
/// Where the draw's timestamps are resolved: query resolves start at multiples of 256 bytes.
const DRAW_RESOLVE: u64 = wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT;

/// A read's state, shared with the map callback.
const IDLE: u8 = 0;
const RECORDED: u8 = 1;
const MAPPING: u8 = 2;
const MAPPED: u8 = 3;
const FAILED: u8 = 4;

/// What the recorded read holds.
#[derive(Clone, Copy)]
struct Pending {
    stepped: bool,
    drawn: bool,
    counters: bool,
    steps: u64,
    capacity: u32,
}

/// The asynchronous reader, and the last figures it delivered.
pub struct Probe {
    queries: Option<(wgpu::QuerySet, wgpu::Buffer)>,
    staging: wgpu::Buffer,
    state: Arc<AtomicU8>,
    period_ns: f64,
    pending: Option<Pending>,
    /// GPU milliseconds of the last measured frame's steps (None: no timestamps, or none yet).
    pub step_ms: Option<f64>,
    /// Steps in that frame.
    pub steps_timed: u64,
    /// GPU milliseconds of the last measured draw.
    pub draw_ms: Option<f64>,
    /// The last counters read (stateful effects).
    pub totals: Option<Totals>,
}

impl Probe {
    /// A reader on `device`; timestamps only where `timestamps` (the device has the feature).
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, timestamps: bool) -> Self {
        let queries = timestamps.then(|| {
            let set = device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("preview times"),
                ty: wgpu::QueryType::Timestamp,
                count: 4,
            });
            let resolve = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("preview times"),
                size: DRAW_RESOLVE + 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            (set, resolve)
        });
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("preview figures"),
            size: STAGING,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self {
            queries,
            staging,
            state: Arc::new(AtomicU8::new(IDLE)),
            period_ns: f64::from(queue.get_timestamp_period()),
            pending: None,
            step_ms: None,
            steps_timed: 0,
            draw_ms: None,
            totals: None,
        }
    }

    /// Whether this frame can take a read (the last one has been collected).
    fn free(&self) -> bool {
        self.state.load(Ordering::Acquire) == IDLE
    }

    /// Where the steps' passes write their timestamps this frame (indices 0 and 1).
    pub fn step_writes(&self) -> Option<(&wgpu::QuerySet, u32)> {
        match (&self.queries, self.free()) {
            (Some((set, _)), true) => Some((set, 0)),
            _ => None,
        }
    }

    /// Where the draw's render pass writes its timestamps this frame (indices 2 and 3).
    pub fn draw_writes(&self) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        match (&self.queries, self.free()) {
            (Some((set, _)), true) => Some(wgpu::RenderPassTimestampWrites {
                query_set: set,
                beginning_of_pass_write_index: Some(2),
                end_of_pass_write_index: Some(3),
            }),
            _ => None,
        }
    }

    /// Records this frame's read into `encoder`, after the passes: the timestamps written (the
    /// steps' only when `stepped`, the draw's when `drawn`) and a copy of `counters`.
    pub fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        stepped: Option<u64>,
        drawn: bool,
        counters: Option<(&wgpu::Buffer, u64, u32)>,
    ) {
        if !self.free() {
            return;
        }
        if let Some((set, resolve)) = &self.queries {
            if stepped.is_some() {
                encoder.resolve_query_set(set, 0..2, resolve, 0);
                encoder.copy_buffer_to_buffer(resolve, 0, &self.staging, 0, 16);
            }
            if drawn {
                encoder.resolve_query_set(set, 2..4, resolve, DRAW_RESOLVE);
                encoder.copy_buffer_to_buffer(resolve, DRAW_RESOLVE, &self.staging, 16, 16);
            }
        }
        if let Some((buffer, _, _)) = counters {
            let bytes = buffer.size().min(STAGING - TIMESTAMPS);
            encoder.copy_buffer_to_buffer(buffer, 0, &self.staging, TIMESTAMPS, bytes);
        }
        self.pending = Some(Pending {
            stepped: stepped.is_some() && self.queries.is_some(),
            drawn: drawn && self.queries.is_some(),
            counters: counters.is_some(),
            steps: counters.map_or(0, |c| c.1),
            capacity: counters.map_or(0, |c| c.2),
        });
        self.steps_timed = stepped.unwrap_or(self.steps_timed);
        self.state.store(RECORDED, Ordering::Release);
    }

    /// After the frame's submission: asks for the read's mapping.
    pub fn submitted(&mut self) {
        if self.state.load(Ordering::Acquire) != RECORDED {
            return;
        }
        self.state.store(MAPPING, Ordering::Release);
        let state = self.state.clone();
        self.staging
            .slice(..)
            .map_async(wgpu::MapMode::Read, move |r| {
                state.store(if r.is_ok() { MAPPED } else { FAILED }, Ordering::Release);
            });
    }

    /// Takes the read's figures if the GPU has delivered them (never waits).
    pub fn collect(&mut self, device: &wgpu::Device) {
        let _ = device.poll(wgpu::PollType::Poll);
        match self.state.load(Ordering::Acquire) {
            MAPPED => {}
            FAILED => {
                self.pending = None;
                self.state.store(IDLE, Ordering::Release);
                return;
            }
            _ => return,
        }
        if let (Some(p), Ok(data)) = (
            self.pending.take(),
            self.staging.slice(..).get_mapped_range(),
        ) {
            let tick =
                |i: usize| u64::from_le_bytes(data[8 * i..8 * i + 8].try_into().expect("8 bytes"));
            let ms = |a: usize| tick(a + 1).saturating_sub(tick(a)) as f64 * self.period_ns * 1e-6;
            if p.stepped {
                self.step_ms = Some(ms(0));
            }
            if p.drawn {
                self.draw_ms = Some(ms(2));
            }
            if p.counters {
                self.totals = Some(Effect::decode_counters(
                    &data[TIMESTAMPS as usize..],
                    p.capacity,
                    p.steps,
                ));
            }
        }
        self.staging.unmap();
        self.state.store(IDLE, Ordering::Release);
    }
}
