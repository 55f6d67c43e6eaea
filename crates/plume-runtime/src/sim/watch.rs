//! What a host reads from an effect every frame without waiting: the box of its live
//! particles, for a host that culls by it ([`Effect::watch_live_bounds`], or in three parts
//! inside a compute pass the host shares between effects; the reduction itself is
//! [`crate::sim::bounds`]'s), its totals ([`Effect::watch_totals`]), and the firings of its reported events
//! ([`Effect::watch_reports`]; the gather is [`crate::sim::reports`]'s).

use crate::error::RuntimeError;
use crate::sim::bounds::{BoundsProbe, BoundsWatch};
use crate::sim::effect::Effect;
use crate::sim::reports::EventReport;

impl Effect {
    /// The reduction over every group's particle buffers (made on first use).
    pub(crate) fn bounds_probe(&self) -> Result<&BoundsProbe, RuntimeError> {
        if self.bounds.get().is_none() {
            let mut buffers = Vec::new();
            for group in self.groups() {
                buffers.push((&group.effect.layout, group.chunks()?));
            }
            let probe = BoundsProbe::new(self.gpu(), &buffers)?;
            let _ = self.bounds.set(probe);
        }
        Ok(self.bounds.get().expect("set above"))
    }

    /// [`Self::live_bounds`] without waiting, for a host that culls by it every frame: records
    /// the reduction into `encoder` (after the frame's steps, where the host puts it) when the
    /// last one's reading has been taken, and returns the box of an earlier frame's reduction
    /// once it has come back (a frame or two after it was recorded, the host's encoders
    /// submitted in between), else [`BoundsWatch::Waiting`]. An error for a stateless effect,
    /// whose particles are only evaluated on demand ([`Self::live_bounds`] does).
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use plume_runtime::{BoundsWatch, Effect, Gpu};
    /// let source = r#"Effect(name: "puff", capacity: 64,
    ///     emitters: [Emitter(burst: 64, shape: Sphere(center: (0.0, 2.0, 0.0), radius: 0.5),
    ///                        velocity: Constant((1.0, 0.0, 0.0)))])"#;
    /// let gpu = Gpu::new(&Default::default())?;
    /// let options = plume_compiler::CompileOptions { state: Some(plume_compiler::schema::State::Stateful), ..Default::default() };
    /// let mut puff = Effect::from_source(&gpu, source, &options)?;
    /// let mut measured = None;
    /// for _ in 0..10 {
    ///     let mut encoder = gpu.device.create_command_encoder(&Default::default());
    ///     puff.advance(&mut encoder, 1)?;
    ///     if let BoundsWatch::Measured(bounds) = puff.watch_live_bounds(&mut encoder)? {
    ///         measured = bounds;
    ///     }
    ///     gpu.queue.submit([encoder.finish()]);
    ///     gpu.device.poll(wgpu::PollType::wait_indefinitely())?;
    /// }
    /// let bounds = measured.expect("a reading came back");
    /// assert!(bounds.min[1] > 1.49 && bounds.max[1] < 2.51);
    /// # Ok(())
    /// # }
    /// ```
    pub fn watch_live_bounds(
        &self,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<BoundsWatch, RuntimeError> {
        let (watch, now) = self.watch_bounds_begin(encoder)?;
        if now {
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                self.watch_bounds_dispatch(&mut pass)?;
            }
            self.watch_bounds_end(encoder)?;
        }
        Ok(watch)
    }

    /// [`Self::watch_live_bounds`] in three parts, for a host that records many effects' work
    /// in one compute pass ([`Self::plan_steps`]): this part, before the pass, returns the
    /// reading and whether a reduction is to be recorded now; if so,
    /// [`Self::watch_bounds_dispatch`] records it into the pass (after the effect's steps) and
    /// [`Self::watch_bounds_end`], after the pass, records its reading.
    pub fn watch_bounds_begin(
        &self,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(BoundsWatch, bool), RuntimeError> {
        if self.is_stateless() {
            return Err(RuntimeError::Control(format!(
                "{}: a stateless effect's bounds are measured on demand (Effect::live_bounds)",
                self.compiled().ir.name
            )));
        }
        self.bounds_probe()?.watch_begin(encoder)
    }

    /// The reduction of a watched measurement, into the host's compute pass (see
    /// [`Self::watch_bounds_begin`]).
    pub fn watch_bounds_dispatch(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
    ) -> Result<(), RuntimeError> {
        self.bounds_probe()?.dispatch(pass);
        Ok(())
    }

    /// The reading of a watched measurement, recorded after the pass that reduced it (see
    /// [`Self::watch_bounds_begin`]).
    pub fn watch_bounds_end(&self, encoder: &mut wgpu::CommandEncoder) -> Result<(), RuntimeError> {
        self.bounds_probe()?.watch_end(encoder);
        Ok(())
    }
}

impl Effect {
    /// The firings of the effect's reported events (`Event(.., report: N)`), read back without
    /// waiting: takes each reading that has come back and records into `encoder` (after the
    /// frame's steps, where the host puts it) the copy of what the steps since the last copy
    /// gathered. A reading comes back a frame or two after its copy (the host submits its
    /// encoder and polls the device in between, as a renderer does every frame). Each firing is
    /// reported once; an event keeps at most its bound between two copies and counts the rest
    /// ([`EventReport::missed`](crate::EventReport::missed)). Empty for an effect without reported events.
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use plume_runtime::{Effect, Gpu};
    /// let source = r#"Effect(name: "drops", capacity: 64, dt: 0.01,
    ///     emitters: [Emitter(burst: 8, shape: Point((0.0, 1.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    ///     forces: [Gravity((0.0, -9.81, 0.0))],
    ///     collide: [Plane(point: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0), restitution: 0.5, friction: 0.0)],
    ///     events: [Event(on: Collide, report: 16)])"#;
    /// let gpu = Gpu::new(&Default::default())?;
    /// let mut drops = Effect::from_source(&gpu, source, &Default::default())?;
    /// let mut firings = Vec::new();
    /// for _ in 0..60 {
    ///     let mut encoder = gpu.device.create_command_encoder(&Default::default());
    ///     drops.advance(&mut encoder, 1)?;
    ///     for report in drops.watch_reports(&mut encoder)? {
    ///         firings.extend(report.firings);
    ///     }
    ///     gpu.queue.submit([encoder.finish()]);
    ///     gpu.device.poll(wgpu::PollType::wait_indefinitely())?;
    /// }
    /// // The eight drops reach the floor together, 0.45 s after they start.
    /// let first = firings.first().expect("the drops hit the floor");
    /// assert_eq!(firings.iter().filter(|f| f.step == first.step).count(), 8);
    /// assert!(first.velocity[1] > 0.0 && first.position[1].abs() < 0.1);
    /// # Ok(())
    /// # }
    /// ```
    pub fn watch_reports(
        &self,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<Vec<EventReport>, RuntimeError> {
        let Some(events) = &self.events else {
            return Ok(Vec::new());
        };
        let steps_done = self.steps_done();
        let mut out = Vec::new();
        for gather in &events.reports {
            out.extend(gather.watch(encoder, steps_done)?);
        }
        Ok(out)
    }

    /// Whether any event of the effect is reported.
    pub fn reports_events(&self) -> bool {
        self.events.as_ref().is_some_and(|e| !e.reports.is_empty())
    }
}

impl Effect {
    /// [`Self::totals`] without waiting, for a host that shows live counts every frame: takes
    /// the reading that has come back (the totals when its copy was recorded, a frame or two
    /// ago; a stateless group's as of now, which the CPU knows) and records into `encoder`
    /// (after the frame's steps) the next copy of the counters when the last was taken.
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use plume_runtime::{Effect, Gpu};
    /// let source = r#"Effect(name: "puff", capacity: 64, state: Stateful,
    ///     emitters: [Emitter(burst: 40, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 1.0, 0.0)))])"#;
    /// let gpu = Gpu::new(&Default::default())?;
    /// let mut puff = Effect::from_source(&gpu, source, &Default::default())?;
    /// let mut counted = None;
    /// for _ in 0..4 {
    ///     let mut encoder = gpu.device.create_command_encoder(&Default::default());
    ///     puff.advance(&mut encoder, 1)?;
    ///     counted = puff.watch_totals(&mut encoder)?.or(counted);
    ///     gpu.queue.submit([encoder.finish()]);
    ///     gpu.device.poll(wgpu::PollType::wait_indefinitely())?;
    /// }
    /// let totals = counted.expect("a reading came back");
    /// assert_eq!((totals.alive, totals.spawned, totals.steps), (40, 40, 1));
    /// # Ok(())
    /// # }
    /// ```
    pub fn watch_totals(
        &self,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<Option<plume_compiler::reference::Totals>, RuntimeError> {
        let watch = self
            .totals
            .get_or_init(|| crate::sim::counts::TotalsWatch::new(self.gpu(), self.groups()));
        watch.watch(self.groups(), encoder, self.steps_done())
    }
}
