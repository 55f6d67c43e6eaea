//! The device Plume runs on: one it opens itself ([`Gpu::new`]: `--backend` or `WGPU_BACKEND`
//! choose the backends; on a machine with no GPU, wgpu's GL backend finds Mesa's llvmpipe with
//! nothing to install), or a host application's own device and queue ([`Gpu::from_device`]).

use std::sync::{Arc, Mutex};

use crate::device::pipeline_cache::PipelineCache;
use crate::error::RuntimeError;

/// Which backends to search.
#[derive(Clone, Debug, Default)]
pub struct GpuChoice {
    /// Backend names (`vulkan`, `gl`, `metal`, `dx12`, comma-separated); None: `WGPU_BACKEND`
    /// if set, else all.
    pub backend: Option<String>,
}

impl GpuChoice {
    /// The wgpu backend set this choice means.
    pub fn backends(&self) -> wgpu::Backends {
        match &self.backend {
            Some(names) => wgpu::Backends::from_comma_list(names),
            None => wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all()),
        }
    }

    /// Every adapter wgpu sees for this choice, as (name, backend, device type, driver)
    /// lines (`plume adapters`).
    pub fn list_adapters(&self) -> Vec<String> {
        let backends = self.backends();
        let adapters = pollster::block_on(instance(backends).enumerate_adapters(backends));
        adapters
            .iter()
            .map(|a| {
                let i = a.get_info();
                let compute = a
                    .get_downlevel_capabilities()
                    .flags
                    .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS);
                format!(
                    "{} ({:?}, {:?}, driver {} {}){}",
                    i.name,
                    i.backend,
                    i.device_type,
                    i.driver,
                    i.driver_info,
                    if compute { "" } else { " [no compute shaders]" }
                )
            })
            .collect()
    }
}

/// An open device, its queue and what it is. Cloning is cheap (wgpu's handles are shared), so
/// every effect keeps its own clone.
#[derive(Clone, Debug)]
pub struct Gpu {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Name, backend and driver.
    pub info: wgpu::AdapterInfo,
    /// The limits the device was opened with (all the adapter offers).
    pub limits: wgpu::Limits,
    /// What the adapter can do below WebGPU's baseline, when known (None for a host's device:
    /// the host chose the adapter, and wgpu reports its own validation errors).
    pub downlevel: Option<wgpu::DownlevelFlags>,
    /// The first uncaptured wgpu error since the last [`Gpu::take_error`].
    errors: Arc<Mutex<Option<String>>>,
    /// Why the device was lost, once it has been (never cleared: a lost device stays lost).
    lost: Arc<Mutex<Option<String>>>,
    /// Modules, layouts and pipelines made on this device, shared by every clone.
    pub(crate) cache: Arc<PipelineCache>,
}

/// An instance searching `backends`, with no display (headless work).
pub(crate) fn instance(backends: wgpu::Backends) -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    // No validation pass before each indirect call: Plume's own kernels write every indirect
    // argument it uses (the indirect draws' counts; the draws pull their vertices from storage
    // buffers, bounds-checked), and wgpu's check adds a dispatch and a barrier before each one
    // (docs/performance.md, "Events", measured it while the event spawns were indirect).
    desc.flags
        .remove(wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL);
    // wgpu's own switches (WGPU_VALIDATION, WGPU_VALIDATION_INDIRECT_CALL, ...) apply.
    desc.flags = desc.flags.with_env();
    wgpu::Instance::new(desc)
}

impl Gpu {
    /// Opens the best adapter with compute shaders among `choice`'s backends.
    pub fn new(choice: &GpuChoice) -> Result<Self, RuntimeError> {
        let backends = choice.backends();
        Self::open(&instance(backends), None, backends).map(|(gpu, _)| gpu)
    }

    /// Opens the best adapter among `instance`'s that can present to `surface` (a window of
    /// Plume's own, as `plume preview` opens), with Plume's error handling, and returns it with
    /// the adapter (the surface's configuration needs it).
    pub fn for_surface(
        instance: &wgpu::Instance,
        surface: &wgpu::Surface<'_>,
        backends: wgpu::Backends,
    ) -> Result<(Self, wgpu::Adapter), RuntimeError> {
        Self::open(instance, Some(surface), backends)
    }

    fn open(
        instance: &wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
        backends: wgpu::Backends,
    ) -> Result<(Self, wgpu::Adapter), RuntimeError> {
        let no_adapter = || RuntimeError::NoAdapter {
            backends: format!("{backends:?}"),
        };
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            compatible_surface: surface,
            ..Default::default()
        }))
        .map_err(|_| no_adapter())?;
        if !adapter
            .get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS)
        {
            return Err(no_adapter());
        }
        let info = adapter.get_info();
        let limits = adapter.limits();
        let downlevel = adapter.get_downlevel_capabilities().flags;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("plume"),
            // Timestamps (for `plume bench`, and inside passes for `--profile`) and subgroup
            // operations (the radix sort's ranking) where the adapter has them; nothing else.
            required_features: adapter.features()
                & (wgpu::Features::TIMESTAMP_QUERY
                    | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES
                    | wgpu::Features::SUBGROUP),
            required_limits: limits.clone(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| RuntimeError::Device {
            adapter: info.name.clone(),
            message: e.to_string(),
        })?;
        // wgpu's default handler panics; keep the first error and report it as a RuntimeError.
        let errors: Arc<Mutex<Option<String>>> = Arc::default();
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            let mut slot = sink.lock().unwrap_or_else(|p| p.into_inner());
            slot.get_or_insert_with(|| e.to_string());
        }));
        // A driver reset, a removed GPU or `Device::destroy`: every later call reports it.
        let lost: Arc<Mutex<Option<String>>> = Arc::default();
        let lost_sink = lost.clone();
        device.set_device_lost_callback(move |reason, message| {
            let mut slot = lost_sink.lock().unwrap_or_else(|p| p.into_inner());
            slot.get_or_insert_with(|| format!("{reason:?}: {message}"));
        });
        let gpu = Self {
            device,
            queue,
            info,
            limits,
            downlevel: Some(downlevel),
            errors,
            lost,
            cache: Arc::default(),
        };
        Ok((gpu, adapter))
    }

    /// Wraps a host application's device and queue: Plume's effects then run in the host's
    /// submissions and draw into its render passes. The host's error handlers stay as they
    /// are, so wgpu errors reach the host; [`Gpu::take_error`] reports only what Plume sees
    /// itself (an out-of-memory allocation, a device lost after this call).
    pub fn from_device(device: &wgpu::Device, queue: &wgpu::Queue) -> Self {
        Self {
            device: device.clone(),
            queue: queue.clone(),
            info: device.adapter_info(),
            limits: device.limits(),
            downlevel: None,
            errors: Arc::default(),
            lost: Arc::default(),
            cache: Arc::default(),
        }
    }

    /// Whether the device has subgroup operations and every subgroup has exactly `size`
    /// invocations (kernels that split a workgroup into subgroups by size rely on it).
    pub fn has_subgroups_of(&self, size: u32) -> bool {
        self.device.features().contains(wgpu::Features::SUBGROUP)
            && self.info.subgroup_min_size == size
            && self.info.subgroup_max_size == size
    }

    /// A 2D grid of workgroups of `workgroup` threads covering `threads` (2D because one
    /// dimension holds at most `max_compute_workgroups_per_dimension` groups); at least one.
    pub(crate) fn grid(&self, threads: u64, workgroup: u64) -> Result<(u32, u32), RuntimeError> {
        let per_dim = u64::from(self.limits.max_compute_workgroups_per_dimension);
        let groups = threads.div_ceil(workgroup).max(1);
        // As few rows as fit, of equal length: 65,536 groups are 2 x 32,768, not 65,535 + 1
        // (a second row of 65,535 groups of which all but one exit at once).
        let y = groups.div_ceil(per_dim);
        let x = groups.div_ceil(y);
        if y > per_dim {
            return Err(RuntimeError::Gpu(format!(
                "{threads} threads need more than {per_dim} x {per_dim} workgroups"
            )));
        }
        Ok((x as u32, y as u32))
    }

    /// A bind group of `layout` whose entries are whole buffers, by binding.
    pub(crate) fn bind_buffers(
        &self,
        label: &str,
        layout: &wgpu::BindGroupLayout,
        entries: &[(u32, &wgpu::Buffer)],
    ) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry<'_>> = entries
            .iter()
            .map(|(binding, buffer)| wgpu::BindGroupEntry {
                binding: *binding,
                resource: buffer.as_entire_binding(),
            })
            .collect();
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout,
            entries: &entries,
        })
    }

    /// A `width` x `height` 2D texture of `format` with one mip level and one sample (every
    /// image, frame and lookup texture the runtime makes).
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// let gpu = plume_runtime::Gpu::new(&Default::default())?;
    /// let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
    /// let frame = gpu.texture_2d("frame", (64, 32), wgpu::TextureFormat::Rgba8Unorm, usage);
    /// assert_eq!((frame.width(), frame.height(), frame.mip_level_count()), (64, 32, 1));
    /// # Ok(())
    /// # }
    /// ```
    pub fn texture_2d(
        &self,
        label: &str,
        (width, height): (u32, u32),
        format: wgpu::TextureFormat,
        usage: wgpu::TextureUsages,
    ) -> wgpu::Texture {
        self.device.create_texture(&texture_2d_descriptor(
            label,
            (width, height),
            format,
            usage,
        ))
    }

    /// The compute pipeline of `module`'s entry point `entry` (also its label), on `layout`, or
    /// on the layout derived from the bindings the entry point uses when `None`.
    pub(crate) fn compute_pipeline(
        &self,
        module: &wgpu::ShaderModule,
        entry: &str,
        layout: Option<&wgpu::PipelineLayout>,
    ) -> wgpu::ComputePipeline {
        self.compute_pipeline_with(module, entry, layout, &[])
    }

    /// [`Self::compute_pipeline`] with values for the module's override `constants`.
    pub(crate) fn compute_pipeline_with(
        &self,
        module: &wgpu::ShaderModule,
        entry: &str,
        layout: Option<&wgpu::PipelineLayout>,
        constants: &[(&str, f64)],
    ) -> wgpu::ComputePipeline {
        self.cache.compute((module, entry), layout, constants, || {
            self.device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout,
                    module,
                    entry_point: Some(entry),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants,
                        ..Default::default()
                    },
                    cache: None,
                })
        })
    }

    /// This device with a cache of its own, empty (`plume bench` times a build without the
    /// shared one).
    #[cfg(feature = "tools")]
    pub(crate) fn with_empty_cache(&self) -> Self {
        Self {
            cache: Arc::default(),
            ..self.clone()
        }
    }

    /// The module of WGSL `source`, made once per source on this device (see
    /// [`crate::device::pipeline_cache::shader_module`]).
    pub(crate) fn shader_module(&self, label: &str, source: &str) -> wgpu::ShaderModule {
        self.cache.module(&self.device, label, source)
    }

    /// The bind group layout of `entries`, made once per set of entries on this device.
    pub(crate) fn bind_group_layout(
        &self,
        label: &str,
        entries: &[wgpu::BindGroupLayoutEntry],
    ) -> wgpu::BindGroupLayout {
        self.cache.bind_group_layout(&self.device, label, entries)
    }

    /// The pipeline layout of the one bind group layout `group`, made once per layout.
    pub(crate) fn pipeline_layout(
        &self,
        label: &str,
        group: &wgpu::BindGroupLayout,
    ) -> wgpu::PipelineLayout {
        self.cache.pipeline_layout(&self.device, label, group)
    }

    /// Whether GPU timestamp queries are available.
    pub fn has_timestamps(&self) -> bool {
        self.device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// One line naming the adapter, backend and driver.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?}, {} {})",
            self.info.name,
            self.info.backend,
            self.info.device_type,
            self.info.driver,
            self.info.driver_info
        )
    }

    /// Returns [`RuntimeError::DeviceLost`] once the device is lost, else the first wgpu error
    /// since the last call, as a [`RuntimeError`].
    pub fn take_error(&self) -> Result<(), RuntimeError> {
        if let Some(reason) = self.lost.lock().unwrap_or_else(|p| p.into_inner()).clone() {
            return Err(RuntimeError::DeviceLost {
                adapter: self.info.name.clone(),
                reason,
            });
        }
        let mut slot = self.errors.lock().unwrap_or_else(|p| p.into_inner());
        match slot.take() {
            Some(msg) => Err(RuntimeError::Gpu(msg)),
            None => Ok(()),
        }
    }

    /// Waits until all submitted work is done.
    pub fn wait(&self) -> Result<(), RuntimeError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| RuntimeError::Gpu(e.to_string()))?;
        self.take_error()
    }
}

/// The descriptor [`Gpu::texture_2d`] creates a texture from (for `create_texture_with_data`).
pub(crate) fn texture_2d_descriptor(
    label: &str,
    (width, height): (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::TextureDescriptor<'_> {
    wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    }
}
