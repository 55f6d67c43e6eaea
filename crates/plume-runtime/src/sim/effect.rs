//! [`Effect`], the public object: any effect file running on a device, a single system (one
//! group) or a graph of groups and the events between them. One group without events steps
//! alone, exactly as it always has ([`Group::advance_timed`]); a graph steps every group and
//! stream in one pass per batch ([`Events::advance_timed`]). Drawing an effect is
//! [`crate::draw::renderer`]'s (`Effect::renderer`, `Effect::prepare_draw`).

use std::path::Path;

use plume_compiler::bursts::Burst;
use plume_compiler::graph::{compile_graph_str, CompiledGraph};
use plume_compiler::placement::Placement;
use plume_compiler::{CompileOptions, CompiledEffect, Diagnostics};

use crate::device::gpu::Gpu;
use crate::device::resources::STEPS_PER_SUBMIT;
use crate::error::RuntimeError;
use crate::sim::graph::Events;
use crate::sim::group::Group;

/// A compiled effect running on a GPU: every group's buffers, kernels and spawn schedule, and
/// the event streams between them. One type for any effect file, with or without groups.
///
/// ```no_run
/// # fn frame(device: &wgpu::Device, queue: &wgpu::Queue, view: &wgpu::TextureView)
/// #     -> Result<(), Box<dyn std::error::Error>> {
/// use plume_runtime::{DrawTarget, Effect, Gpu};
/// // On the host's own device and queue:
/// let gpu = Gpu::from_device(device, queue);
/// let mut fountain = Effect::from_file(&gpu, "effects/fountain.ron", &Default::default())?;
/// let renderer = fountain.renderer(&DrawTarget::new(wgpu::TextureFormat::Rgba8Unorm))?;
/// let camera = fountain.camera(16.0 / 9.0); // or the host's own view and projection
/// // Each frame: steps and the draw's preparation go into the host's encoder ...
/// let mut encoder = device.create_command_encoder(&Default::default());
/// fountain.advance(&mut encoder, 1)?;
/// fountain.prepare_draw(&mut encoder, &renderer, &camera)?;
/// {
///     // ... and the draw into the host's render pass, beside its own geometry.
///     let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
///         color_attachments: &[Some(wgpu::RenderPassColorAttachment {
///             view,
///             depth_slice: None,
///             resolve_target: None,
///             ops: wgpu::Operations::default(),
///         })],
///         ..Default::default()
///     });
///     renderer.draw(&mut pass);
/// }
/// queue.submit([encoder.finish()]);
/// # Ok(()) }
/// ```
///
/// An effect with groups and events runs through the same calls:
///
/// ```
/// // Shells that burst when their fuse (0.2 s) runs out, 30 sparks each.
/// let source = r#"Effect(
///     name: "shells",
///     capacity: 8,
///     emitters: [Emitter(burst: 8, shape: Sphere(center: (0.0, 5.0, 0.0), radius: 1.0),
///                        velocity: Constant((0.0, 4.0, 0.0)), lifetime: Some((0.2, 0.2)))],
///     forces: [Gravity((0.0, -9.81, 0.0))],
///     events: [Event(on: Death, target: "sparks", count: 30, velocity: Radial(speed: (2.0, 3.0)),
///                    lifetime: Some((1.0, 1.0)), inherit_velocity: 0.5)],
///     groups: [Group(name: "sparks", capacity: 1000, forces: [Gravity((0.0, -9.81, 0.0))])],
/// )"#;
/// let graph = plume_compiler::graph::compile_graph_str(source, &Default::default()).unwrap();
/// let gpu = plume_runtime::Gpu::new(&Default::default()).unwrap();
/// let mut shells = plume_runtime::Effect::from_graph(&gpu, graph.clone()).unwrap();
/// shells.run(20, |_| {}).unwrap();
/// // The shells died at step 11 (12 steps of 1/60 s); their sparks spawned at step 12.
/// assert_eq!(shells.group_names(), ["shells", "sparks"]);
/// assert_eq!(shells.group_totals(0).unwrap().alive, 0);
/// assert_eq!(shells.group_totals(1).unwrap().spawned, 240);
/// // The f64 reference runs the same graph: the same particles in every group.
/// let mut reference = plume_compiler::graph::ReferenceGraph::new(&graph);
/// reference.run(20);
/// for g in 0..2 {
///     let ids = |records: Vec<plume_compiler::reference::ParticleRecord>| {
///         records.iter().map(|r| r.id).collect::<Vec<_>>()
///     };
///     assert_eq!(ids(shells.group_records(g).unwrap()), ids(reference.records(g)));
/// }
/// ```
pub struct Effect {
    pub(crate) gpu: Gpu,
    pub(crate) names: Vec<String>,
    pub(crate) groups: Vec<Group>,
    /// The event streams; None for one group without events, which steps alone.
    pub(crate) events: Option<Events>,
    pub(crate) warnings: Diagnostics,
    /// The kernels that copy a host's depth for a `SceneDepth` collider (made on first use).
    pub(crate) depth_copy: crate::device::depth_copy::DepthCopy,
    /// The live-bounds reduction (made on first use: [`Self::live_bounds`]).
    pub(crate) bounds: std::sync::OnceLock<crate::sim::bounds::BoundsProbe>,
    /// The totals read without waiting (made on first use: `Effect::watch_totals`).
    pub(crate) totals: std::sync::OnceLock<crate::sim::counts::TotalsWatch>,
}

impl Effect {
    /// Allocates a single-system effect's buffers and builds its kernels on `gpu` (Plume's own
    /// device, or a host's through [`Gpu::from_device`]).
    pub fn new(gpu: &Gpu, effect: CompiledEffect) -> Result<Self, RuntimeError> {
        let name = effect.ir.name.clone();
        Self::from_graph(gpu, CompiledGraph::single(&name, effect))
    }

    /// Allocates every group's buffers and the event streams' on `gpu`, and builds the
    /// kernels: any compiled effect file (`plume_compiler::graph::compile_graph_str`).
    pub fn from_graph(gpu: &Gpu, graph: CompiledGraph) -> Result<Self, RuntimeError> {
        Self::with_chunk_slots(gpu, graph, None)
    }

    /// Compiles `source` (an effect file's text, with or without groups) with `options` and
    /// runs it on `gpu`. A compile error is [`RuntimeError::Compile`], its diagnostics rendered
    /// against `<source>`; the warnings are kept ([`Self::warnings`]).
    pub fn from_source(
        gpu: &Gpu,
        source: &str,
        options: &CompileOptions,
    ) -> Result<Self, RuntimeError> {
        Self::compile(gpu, "<source>", source, options)
    }

    /// Reads and compiles the effect file at `path` (files it names, a texture, resolved from
    /// its directory unless `options` names another) and runs it on `gpu`. Errors say which
    /// file and where ([`RuntimeError::Read`], [`RuntimeError::Compile`]).
    pub fn from_file(
        gpu: &Gpu,
        path: impl AsRef<Path>,
        options: &CompileOptions,
    ) -> Result<Self, RuntimeError> {
        let path = path.as_ref();
        let name = path.display().to_string();
        let source = std::fs::read_to_string(path).map_err(|e| RuntimeError::Read {
            path: name.clone(),
            message: e.to_string(),
        })?;
        let options = CompileOptions {
            base_dir: options
                .base_dir
                .clone()
                .or_else(|| path.parent().map(Path::to_path_buf)),
            ..options.clone()
        };
        Self::compile(gpu, &name, &source, &options)
    }

    fn compile(
        gpu: &Gpu,
        name: &str,
        source: &str,
        options: &CompileOptions,
    ) -> Result<Self, RuntimeError> {
        let graph = compile_graph_str(source, options)
            .map_err(|e| RuntimeError::Compile(e.render(name, source)))?;
        Self::from_graph(gpu, graph)
    }

    /// Like [`Self::from_graph`] with at most `max_chunk_slots` particles per buffer in every
    /// group (tests use it to exercise the split on small effects; a single system is
    /// `CompiledGraph::single(name, effect)`).
    pub fn with_chunk_slots(
        gpu: &Gpu,
        graph: CompiledGraph,
        max_chunk_slots: Option<u64>,
    ) -> Result<Self, RuntimeError> {
        let warnings = graph.all_warnings();
        let reports = graph
            .groups
            .iter()
            .any(|g| g.effect.ir.events.iter().any(|e| e.report > 0));
        let alone = graph.groups.len() == 1 && graph.streams.is_empty() && !reports;
        let (mut events, shared) = match alone {
            true => (None, vec![Vec::new()]),
            false => {
                let (events, shared) = Events::new(gpu, &graph)?;
                (Some(events), shared)
            }
        };
        let mut names = Vec::new();
        let mut groups = Vec::new();
        for (group, shared) in graph.groups.into_iter().zip(&shared) {
            names.push(group.name);
            groups.push(Group::new(gpu, group.effect, max_chunk_slots, shared)?);
        }
        if let Some(events) = &mut events {
            events.bind_children(gpu, &groups)?;
        }
        gpu.take_error()?;
        Ok(Self {
            gpu: gpu.clone(),
            names,
            groups,
            events,
            warnings,
            depth_copy: Default::default(),
            bounds: std::sync::OnceLock::new(),
            totals: std::sync::OnceLock::new(),
        })
    }

    /// Records `steps` steps into the caller's `encoder` (a compute pass per
    /// 256 steps, each preceded by the copy of its steps' parameters; with
    /// groups, per step each stream's ordering and its child's spawn, then each group's own
    /// step). The schedule advances now: submit the encoder before reading the effect back. A
    /// stateless effect only advances its bookkeeping and records nothing.
    pub fn advance(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        steps: u64,
    ) -> Result<(), RuntimeError> {
        self.advance_timed(encoder, steps, None).map(|_| ())
    }

    /// Like [`Self::advance`], with GPU timestamps: `query_set` gets one at index `first` when
    /// the steps' first compute pass begins and one at `first + 1` when the last one ends.
    /// Returns whether any pass was recorded (a stateless effect, or 0 steps, records none).
    pub fn advance_timed(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        steps: u64,
        timestamps: Option<(&wgpu::QuerySet, u32)>,
    ) -> Result<bool, RuntimeError> {
        match &self.events {
            None => self.groups[0].advance_timed(encoder, steps, timestamps),
            Some(events) => events.advance_timed(&mut self.groups, encoder, steps, timestamps),
        }
    }

    /// Places the effect in the world by `placement` for the steps recorded from now on: an
    /// effect compiled with `CompileOptions::placed` (world space) spawns through it, so its
    /// particles stay where they were emitted while the host moves the emitter (every group's
    /// emitters; children of events spawn at their parents). Ignored by an effect that is not
    /// placed. Steps recorded by one [`Self::advance`] all use the placement set before it.
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use plume_compiler::placement::Placement;
    /// use plume_compiler::CompileOptions;
    /// use plume_runtime::{Effect, Gpu};
    /// let source = r#"Effect(name: "puff", capacity: 64,
    ///     emitters: [Emitter(rate: 600.0, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))])"#;
    /// let gpu = Gpu::new(&Default::default())?;
    /// let world_space = CompileOptions { placed: true, ..Default::default() };
    /// let mut puff = Effect::from_source(&gpu, source, &world_space)?;
    /// // The host's model matrix, column-major: here a move to (5, 0, 0).
    /// let mut model = glam::Mat4::from_translation(glam::Vec3::new(5.0, 0.0, 0.0));
    /// puff.set_placement(Placement::from_cols(model.to_cols_array()).expect("finite"));
    /// puff.run(3, |_| {})?;
    /// model = glam::Mat4::IDENTITY; // the emitter moves on; what it emitted stays
    /// puff.set_placement(Placement::from_cols(model.to_cols_array()).expect("finite"));
    /// puff.run(3, |_| {})?;
    /// let xs: Vec<f64> = puff.records()?.iter().map(|r| r.position.x).collect();
    /// assert!(xs.iter().any(|&x| x == 5.0) && xs.iter().any(|&x| x == 0.0));
    /// # Ok(())
    /// # }
    /// ```
    pub fn set_placement(&mut self, placement: Placement) {
        for group in &mut self.groups {
            group.placement = placement;
        }
    }

    /// Records into `encoder` what the effect's `SceneDepth` collider meets in the steps
    /// recorded after it: a copy of `depth` (a 2D depth texture of any depth format and sample
    /// count, multisampled ones by their sample 0, with `TextureUsages::TEXTURE_BINDING`; depth
    /// exactly 0 or 1 is empty, so a clear value of either convention is no surface), drawn
    /// through `view` (world to view, right-handed, looking down −z) and `projection` (view to
    /// wgpu clip space, standard or reversed depth). The copy is the effect's own, so the
    /// texture may be reused or dropped once the encoder is submitted. The previous frame's
    /// depth is fine: particles then meet the scene where it was a frame ago. Until it is
    /// given an image the collider meets nothing; an effect without a `SceneDepth` collider
    /// records nothing. The f64 twin is `ReferenceSim::set_scene_depth`.
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use plume_runtime::{wgpu, Effect, Gpu};
    /// let source = r#"Effect(name: "darts", capacity: 4,
    ///     emitters: [Emitter(burst: 4, shape: Point((0.0, 0.0, -1.0)),
    ///                        velocity: Constant((0.0, 0.0, -10.0)), lifetime: Some((9.0, 9.0)))],
    ///     collide: [SceneDepth(restitution: 0.0, friction: 1.0)])"#;
    /// let gpu = Gpu::new(&Default::default())?;
    /// let mut darts = Effect::from_source(&gpu, source, &Default::default())?;
    /// // The host's camera and depth buffer; here nothing is drawn but a clear to the depth of
    /// // a point 5 m ahead: a wall there.
    /// let view = glam::Mat4::look_at_rh(glam::Vec3::ZERO, -glam::Vec3::Z, glam::Vec3::Y);
    /// let projection = glam::Mat4::perspective_rh(1.0, 1.0, 0.1, 100.0);
    /// let ahead = projection * glam::Vec4::new(0.0, 0.0, -5.0, 1.0);
    /// let depth = gpu.device.create_texture(&wgpu::TextureDescriptor {
    ///     label: None,
    ///     size: wgpu::Extent3d { width: 64, height: 64, depth_or_array_layers: 1 },
    ///     mip_level_count: 1,
    ///     sample_count: 1,
    ///     dimension: wgpu::TextureDimension::D2,
    ///     format: wgpu::TextureFormat::Depth32Float,
    ///     usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
    ///     view_formats: &[],
    /// });
    /// let mut encoder = gpu.device.create_command_encoder(&Default::default());
    /// encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
    ///     label: None,
    ///     color_attachments: &[],
    ///     depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
    ///         view: &depth.create_view(&Default::default()),
    ///         depth_ops: Some(wgpu::Operations {
    ///             load: wgpu::LoadOp::Clear(ahead.z / ahead.w),
    ///             store: wgpu::StoreOp::Store,
    ///         }),
    ///         stencil_ops: None,
    ///     }),
    ///     timestamp_writes: None,
    ///     occlusion_query_set: None,
    ///     multiview_mask: None,
    /// });
    /// // After the host's passes, before the steps that should meet them.
    /// darts.set_scene_depth(&mut encoder, &depth, view, projection)?;
    /// darts.advance(&mut encoder, 60)?;
    /// gpu.queue.submit([encoder.finish()]);
    /// assert!(darts.records()?.iter().all(|r| (r.position.z + 5.0).abs() < 0.01));
    /// # Ok(())
    /// # }
    /// ```
    pub fn set_scene_depth(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        depth: &wgpu::Texture,
        view: glam::Mat4,
        projection: glam::Mat4,
    ) -> Result<(), RuntimeError> {
        crate::sim::scene_depth::check_texture(depth)?;
        let camera = crate::sim::scene_depth::camera(view, projection)?;
        for group in &mut self.groups {
            crate::sim::scene_depth::record(group, &mut self.depth_copy, encoder, depth, &camera)?;
        }
        Ok(())
    }

    /// Whether the effect collides with a depth image the host gives
    /// ([`Self::set_scene_depth`]).
    pub fn collides_with_scene_depth(&self) -> bool {
        self.groups
            .iter()
            .any(|g| g.effect.ir.collides_with_scene_depth())
    }

    /// Fires a burst from code in group `group` (0 for an effect without groups): `burst.count`
    /// particles of emitter `burst.emitter`, spawned at the next step recorded (after the
    /// emitters' own spawns, up to `bursts::SLOTS` bursts a step; more wait, in order), moved
    /// by `burst.offset` and given `burst.velocity` more, in the effect's space. The effect
    /// must be compiled with `CompileOptions::bursts`. Like every spawn, particles that find
    /// no free slot are dropped and counted.
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use plume_compiler::bursts::Burst;
    /// use plume_compiler::CompileOptions;
    /// use plume_runtime::{Effect, Gpu};
    /// let source = r#"Effect(name: "impact", capacity: 256,
    ///     emitters: [Emitter(shape: Sphere(center: (0.0, 0.0, 0.0), radius: 0.1),
    ///                        velocity: Radial(speed: (1.0, 2.0)), lifetime: Some((0.5, 0.5)))])"#;
    /// let gpu = Gpu::new(&Default::default())?;
    /// let takes_bursts = CompileOptions { bursts: true, ..Default::default() };
    /// let mut impact = Effect::from_source(&gpu, source, &takes_bursts)?;
    /// impact.burst(0, Burst::new(0, 40).at([3.0, 0.0, 0.0]).with_velocity([0.0, 5.0, 0.0]))?;
    /// impact.run(1, |_| {})?;
    /// let records = impact.records()?;
    /// assert_eq!(records.len(), 40);
    /// assert!(records.iter().all(|r| (r.position.x - 3.0).abs() < 0.2));
    /// // An emitter the effect does not have is refused, with why.
    /// assert!(impact.burst(0, Burst::new(3, 1)).unwrap_err().to_string().contains("1 emitter"));
    /// # Ok(())
    /// # }
    /// ```
    pub fn burst(&mut self, group: usize, burst: Burst) -> Result<(), RuntimeError> {
        let names = self.names.len();
        let target = self.groups.get_mut(group).ok_or_else(|| {
            RuntimeError::Control(format!(
                "a burst in group {group}, but the effect has {names} group(s)"
            ))
        })?;
        if !target.effect.ir.bursts {
            return Err(RuntimeError::Control(
                "this effect does not take bursts from code: compile it with CompileOptions { bursts: true, .. }".into(),
            ));
        }
        target
            .schedule
            .queue_burst(burst)
            .map_err(RuntimeError::Control)
    }

    /// Sets the effect's param `name` to `value` for the steps recorded from now on, in every
    /// group: custom forces read it at run time, with no recompiling. The effect must be
    /// compiled with `CompileOptions::live_params`; an unknown name is refused with the
    /// names there are, a value that is not finite or beyond ±1e18 (the range expressions
    /// compute in) with why. A vector param (`"wind": (1.0, 0.0, 0.0)`) is set component by
    /// component: `set_param("wind.x", 2.0)`.
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use plume_compiler::CompileOptions;
    /// use plume_runtime::{Effect, Gpu};
    /// let source = r#"Effect(name: "lift", capacity: 16, params: {"up": 0.0},
    ///     emitters: [Emitter(burst: 16, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    ///     forces: [Custom(accel: "vec3(0, up, 0)")])"#;
    /// let gpu = Gpu::new(&Default::default())?;
    /// let live = CompileOptions { live_params: true, ..Default::default() };
    /// let mut lift = Effect::from_source(&gpu, source, &live)?;
    /// lift.run(10, |_| {})?;
    /// assert!(lift.records()?.iter().all(|r| r.position.y == 0.0));
    /// lift.set_param("up", 20.0)?;
    /// lift.run(10, |_| {})?;
    /// assert!(lift.records()?.iter().all(|r| r.position.y > 0.0));
    /// assert!(lift.set_param("down", 1.0).unwrap_err().to_string().contains("up"));
    ///
    /// // A vector param, read whole as a vec3 and set by its components.
    /// let source = r#"Effect(name: "drift", capacity: 4, params: {"wind": (0.0, 0.0, 0.0)},
    ///     emitters: [Emitter(burst: 4, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
    ///     forces: [Custom(accel: "wind")])"#;
    /// let mut drift = Effect::from_source(&gpu, source, &live)?;
    /// drift.set_param("wind.x", 3.0)?;
    /// drift.run(10, |_| {})?;
    /// assert!(drift.records()?.iter().all(|r| r.velocity.x > 0.0 && r.velocity.y == 0.0));
    /// # Ok(())
    /// # }
    /// ```
    pub fn set_param(&mut self, name: &str, value: f32) -> Result<(), RuntimeError> {
        if !(value.is_finite() && f64::from(value.abs()) <= plume_compiler::expr::VALUE_BOUND) {
            return Err(RuntimeError::Control(format!(
                "param `{name}` = {value}: a param must be finite and within ±1e18"
            )));
        }
        let names: Vec<&str> = self.groups[0]
            .effect
            .ir
            .live_params
            .iter()
            .map(|p| p.0.as_str())
            .collect();
        let Some(index) = names.iter().position(|n| *n == name) else {
            return Err(RuntimeError::Control(if names.is_empty() {
                format!("param `{name}`: this effect reads no params at run time; compile it with CompileOptions {{ live_params: true, .. }} (and give the file `params`)")
            } else {
                format!(
                    "unknown param `{name}`: the effect's params are {}",
                    names.join(", ")
                )
            }));
        };
        for group in &mut self.groups {
            group.live_params[index] = value;
            group.schedule.set_param(index, value);
        }
        Ok(())
    }

    /// Keeps `scale` (0 to 1) of every spawn from the next step on: each emitter's rate and
    /// bursts, and bursts fired from code, spawn that fraction (fractions of a particle
    /// carried to the next), in every group; children spawned by events follow their
    /// parents. The particles alive live on, so a thinned effect thins over a lifetime. This
    /// is how a host keeps a budget or draws less of a far effect; the f64 reference does the
    /// same (`ReferenceSim::set_spawn_scale`), and 1, the start, is the unscaled effect.
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use plume_runtime::{Effect, Gpu};
    /// let source = r#"Effect(name: "mist", capacity: 1000,
    ///     emitters: [Emitter(rate: 600.0, lifetime: Some((1.0, 1.0)), shape: Point((0.0, 0.0, 0.0)),
    ///                        velocity: Constant((0.0, 1.0, 0.0)))])"#;
    /// let gpu = Gpu::new(&Default::default())?;
    /// let mut mist = Effect::from_source(&gpu, source, &Default::default())?;
    /// mist.set_spawn_scale(0.25);
    /// mist.run(30, |_| {})?; // half a second at 60 steps a second
    /// assert_eq!(mist.totals()?.spawned, 75); // a quarter of 300
    /// # Ok(())
    /// # }
    /// ```
    pub fn set_spawn_scale(&mut self, scale: f32) {
        for group in &mut self.groups {
            group.schedule.set_spawn_scale(scale);
        }
    }

    /// Runs `steps` steps in submissions of 256 steps, calling `progress(done)`
    /// after each is submitted. Returns when the GPU has finished.
    pub fn run(&mut self, steps: u64, mut progress: impl FnMut(u64)) -> Result<(), RuntimeError> {
        if self.events.is_none() {
            return self.groups[0].run(steps, progress);
        }
        let mut done = 0;
        while done < steps {
            let n = (steps - done).min(u64::from(STEPS_PER_SUBMIT));
            let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
            self.advance(&mut encoder, n)?;
            self.gpu.queue.submit([encoder.finish()]);
            self.gpu.take_error()?;
            done += n;
            progress(done);
        }
        self.gpu.wait()
    }
}
