//! Reported events (plume_compiler::event_report has the contract): after every step, a
//! one-workgroup kernel (`event_report.wgsl`) appends each reported event's firings of that
//! step (their id, position, velocity and step, from the records the firing group's update
//! wrote) to the event's report buffer, up to the event's bound, and counts them all. A host
//! reads the buffers back without waiting (`Effect::watch_reports`, in `watch.rs`): each
//! readback copies a buffer and starts it again, so a firing is reported once.

use plume_compiler::event_report::{buffer_bytes, REPORT_BYTES, REPORT_HEADER_BYTES};

use crate::device::async_read::AsyncRead;
use crate::device::buffers::{filled_buffer, STORAGE};
use crate::device::gpu::Gpu;
use crate::error::RuntimeError;

/// One kept firing of a reported event.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Firing {
    /// The firing particle's id.
    pub id: u32,
    /// The step at whose end it fired (counted from the effect's first step, 0).
    pub step: u64,
    /// Where it fired (the event's record: where the step left it, or where it died), in the
    /// effect's simulation space.
    pub position: [f32; 3],
    /// Its velocity then.
    pub velocity: [f32; 3],
}

/// What one readback of a reported event brought back: the firings since the readback before.
#[derive(Clone, Debug, PartialEq)]
pub struct EventReport {
    /// The firing group (an index into `Effect::group_names`).
    pub group: usize,
    /// The event's index among the group's `events`.
    pub event: usize,
    /// Every firing counted in that span, kept or not (saturating at `u32::MAX`).
    pub fired: u64,
    /// The firings kept, at most the event's `report` bound, in (step, id) order.
    pub firings: Vec<Firing>,
}

impl EventReport {
    /// The firings counted but not kept (past the bound).
    pub fn missed(&self) -> u64 {
        self.fired - self.firings.len() as u64
    }
}

/// A reported event's report buffer, its gather kernel and its reading.
pub(crate) struct ReportGather {
    group: usize,
    event: usize,
    most: u32,
    pipeline: wgpu::ComputePipeline,
    bind: wgpu::BindGroup,
    buffer: wgpu::Buffer,
    reading: AsyncRead,
}

impl ReportGather {
    /// The gather of event `event` of group `group`, keeping at most `most` firings, from the
    /// firings' `keys`, `slots` and `records` (the event's buffers); `clears` for an event
    /// with no target, whose gather clears the firings' header for the next step.
    pub(crate) fn new(
        gpu: &Gpu,
        (group, event, most): (usize, usize, u32),
        (keys, slots, records): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
        clears: bool,
    ) -> Result<Self, RuntimeError> {
        let bytes = buffer_bytes(most);
        let mut header = [0u8; REPORT_HEADER_BYTES as usize];
        header[8..12].copy_from_slice(&most.to_le_bytes());
        let buffer = filled_buffer(gpu, "event report", bytes, STORAGE, |data| {
            data[..header.len()].copy_from_slice(&header)
        })?;
        let module = gpu.shader_module("event report", include_str!("event_report.wgsl"));
        let entry = if clears { "gather_and_clear" } else { "gather" };
        let pipeline = gpu.compute_pipeline(&module, entry, None);
        let bind = gpu.bind_buffers(
            entry,
            &pipeline.get_bind_group_layout(0),
            &[(0, keys), (1, slots), (2, records), (3, &buffer)],
        );
        Ok(Self {
            group,
            event,
            most,
            pipeline,
            bind,
            buffer,
            reading: AsyncRead::new(gpu, "event report reading", bytes),
        })
    }

    /// Records the gather of the step just recorded into `pass`.
    pub(crate) fn record(&self, pass: &mut wgpu::ComputePass<'_>) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind, &[]);
        pass.dispatch_workgroups(1, 1, 1);
        crate::device::dispatch_marks::mark(pass, "event report");
    }

    /// Takes a reading that came back, and records the next copy (and the restart of the
    /// count) into `encoder` when the last reading was taken. `steps_done` dates the firings.
    pub(crate) fn watch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        steps_done: u64,
    ) -> Result<Option<EventReport>, RuntimeError> {
        let taken = self.reading.poll()?;
        if self.reading.record_copy(encoder, &self.buffer) {
            // The count starts again; the steps' count and the bound stay.
            encoder.clear_buffer(&self.buffer, 0, Some(4));
        }
        Ok(taken.map(|bytes| self.decode(&bytes, steps_done)))
    }

    /// The report in a reading's bytes.
    fn decode(&self, bytes: &[u8], steps_done: u64) -> EventReport {
        let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
        let f32_at = |at: usize| f32::from_bits(word(at));
        let fired = word(0);
        let kept = fired.min(self.most) as usize;
        let mut firings: Vec<Firing> = (0..kept)
            .map(|i| {
                let at = (REPORT_HEADER_BYTES + i as u64 * REPORT_BYTES) as usize;
                // The GPU keeps a step's low 32 bits; the firing is at most 2^32 steps old.
                let behind = (steps_done as u32).wrapping_sub(word(at + 28));
                Firing {
                    id: word(at + 12),
                    step: steps_done.saturating_sub(u64::from(behind)),
                    position: [f32_at(at), f32_at(at + 4), f32_at(at + 8)],
                    velocity: [f32_at(at + 16), f32_at(at + 20), f32_at(at + 24)],
                }
            })
            .collect();
        firings.sort_by_key(|f| (f.step, f.id));
        EventReport {
            group: self.group,
            event: self.event,
            fired: u64::from(fired),
            firings,
        }
    }
}
