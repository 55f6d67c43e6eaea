//! Light from particles on the GPU (`render.light`, `plume_compiler::particle_light`): the
//! draw module's two light kernels over a group's slots, with an identity view so that each
//! sprite's centre is its position, and the few lights they pick read back, at once
//! ([`LightProbe::measure`]) or a frame or more later without waiting ([`LightProbe::watch`]).

use glam::{DVec3, Mat4};
use plume_compiler::lights::LightSource;
use plume_compiler::particle_light::{
    ParticleLight, LIGHT_ENTRY_BYTES, LIGHT_KEYS_BINDING, LIGHT_LIST_BINDING,
};
use plume_compiler::wgsl::draw::DrawShape;

use crate::device::async_read::AsyncRead;
use crate::device::buffers::{filled_buffer, STORAGE};
use crate::device::gpu::Gpu;
use crate::device::readback::read_buffer;
use crate::draw::camera::record_draw_view;
use crate::draw::camera::Camera;
use crate::draw::raster::{draw_module, draw_shape};
use crate::error::RuntimeError;
use crate::sim::effect::Effect;
use crate::sim::group::Group;

/// One group's light kernels and their buffers.
pub(crate) struct LightProbe {
    light: ParticleLight,
    keys_pass: wgpu::ComputePipeline,
    pick_pass: wgpu::ComputePipeline,
    keys_group: wgpu::BindGroup,
    pick_group: wgpu::BindGroup,
    view: wgpu::Buffer,
    keys: wgpu::Buffer,
    list: wgpu::Buffer,
    /// Zeros the size of the keys and the list, copied over them before each pick.
    zeros: wgpu::Buffer,
    grid: (u32, u32),
    reading: AsyncRead,
    gpu: Gpu,
}

impl LightProbe {
    /// The light kernels of `group`, whose look gives off `light`.
    pub(crate) fn new(group: &Group, light: ParticleLight) -> Result<Self, RuntimeError> {
        let (gpu, effect, res) = (&group.gpu, &group.effect, &group.res);
        if effect.layout.batched {
            return Err(RuntimeError::Unsupported(format!(
                "{}: a batch's particles give off no light (render.light): run the effect alone",
                effect.ir.name
            )));
        }
        let shape = DrawShape {
            through_list: false,
            particle_light: true,
            ..draw_shape(effect, res)
        };
        let (module, mut entries) = draw_module(gpu, effect, res, &shape, None)?;
        let count = u64::from(light.count);
        let list_bytes = count * LIGHT_ENTRY_BYTES;
        let view = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("light view"),
            size: plume_compiler::wgsl::draw::DRAW_VIEW_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let keys = filled_buffer(gpu, "light keys", 4 * count, STORAGE, |_| {})?;
        let list = filled_buffer(gpu, "light list", list_bytes, STORAGE, |_| {})?;
        let zeros = filled_buffer(gpu, "light zeros", list_bytes, STORAGE, |_| {})?;
        entries.push((0, view.clone()));
        let keys_pass = gpu.compute_pipeline(&module, "light_keys_pass", None);
        let pick_pass = gpu.compute_pipeline(&module, "light_pick_pass", None);
        let mut keys_entries: Vec<(u32, &wgpu::Buffer)> =
            entries.iter().map(|(b, x)| (*b, x)).collect();
        keys_entries.push((LIGHT_KEYS_BINDING, &keys));
        let keys_group = gpu.bind_buffers(
            "light keys",
            &keys_pass.get_bind_group_layout(0),
            &keys_entries,
        );
        let mut pick_entries = keys_entries.clone();
        pick_entries.push((LIGHT_LIST_BINDING, &list));
        let pick_group = gpu.bind_buffers(
            "light pick",
            &pick_pass.get_bind_group_layout(0),
            &pick_entries,
        );
        let grid = gpu.grid(
            u64::from(effect.ir.capacity),
            u64::from(plume_compiler::particle_light::LIGHT_WORKGROUP),
        )?;
        gpu.take_error()?;
        Ok(Self {
            light,
            keys_pass,
            pick_pass,
            keys_group,
            pick_group,
            view,
            keys,
            list,
            zeros,
            grid,
            reading: AsyncRead::new(gpu, "light list reading", list_bytes),
            gpu: gpu.clone(),
        })
    }

    /// Records the pick at `steps` steps done into `encoder`: the keys and the list emptied,
    /// then the two kernels.
    fn record(&self, encoder: &mut wgpu::CommandEncoder, steps: u64) -> Result<(), RuntimeError> {
        let identity = Camera::new(Mat4::IDENTITY, Mat4::IDENTITY);
        record_draw_view(&self.gpu, encoder, &self.view, &identity, steps, 1.0)?;
        encoder.copy_buffer_to_buffer(&self.zeros, 0, &self.keys, 0, self.keys.size());
        encoder.copy_buffer_to_buffer(&self.zeros, 0, &self.list, 0, self.list.size());
        let mut pass = encoder.begin_compute_pass(&Default::default());
        self.dispatch(&mut pass);
        Ok(())
    }

    /// Records the two kernels into `pass` (the benchmark times them alone).
    pub(crate) fn dispatch(&self, pass: &mut wgpu::ComputePass<'_>) {
        for (pipeline, group) in [
            (&self.keys_pass, &self.keys_group),
            (&self.pick_pass, &self.pick_group),
        ] {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(self.grid.0, self.grid.1, 1);
        }
    }

    /// The lights at `steps` steps done (waits for the GPU).
    pub(crate) fn measure(&self, steps: u64) -> Result<Vec<LightSource>, RuntimeError> {
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        self.record(&mut encoder, steps)?;
        self.gpu.queue.submit([encoder.finish()]);
        Ok(self.decode(&read_buffer(&self.gpu, &self.list)?))
    }

    /// The lights of a recent frame if a reading has come back (None: still waiting), and
    /// a new pick recorded into `encoder` when the last reading was taken.
    pub(crate) fn watch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        steps: u64,
    ) -> Result<Option<Vec<LightSource>>, RuntimeError> {
        let taken = self.reading.poll()?;
        if self.reading.is_free() {
            self.record(encoder, steps)?;
            self.reading.record_copy(encoder, &self.list);
        }
        Ok(taken.map(|bytes| self.decode(&bytes)))
    }

    /// The picked lights in `bytes` (the list), brightest first: each a point light of its
    /// particle's colour times opacity times the look's intensity.
    fn decode(&self, bytes: &[u8]) -> Vec<LightSource> {
        let f = |k: usize| f32::from_le_bytes(bytes[4 * k..4 * k + 4].try_into().unwrap());
        let mut picked: Vec<(u32, LightSource)> = (0..self.light.count as usize)
            .filter_map(|b| {
                let w = 8 * b;
                let key = f(w + 3).to_bits();
                let v = |k: usize| {
                    DVec3::new(f64::from(f(k)), f64::from(f(k + 1)), f64::from(f(k + 2)))
                };
                (key > 0).then(|| {
                    (
                        key,
                        LightSource::Point {
                            position: v(w),
                            color: v(w + 4) * self.light.intensity,
                            range: self.light.range,
                        },
                    )
                })
            })
            .collect();
        picked.sort_by_key(|b| std::cmp::Reverse(b.0));
        picked.into_iter().map(|(_, s)| s).collect()
    }
}

/// The light an effect's particles give off (`render.light`): each lit group's light kernels.
/// Made by [`Effect::particle_lights`]; read with [`Self::read`] (waits) or each frame with
/// [`Self::watch`] (does not).
///
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use plume_runtime::{Effect, Gpu, LightSource};
/// // Embers: the 4 brightest (one of each quarter of the slots) light what is around them.
/// let source = r#"Effect(name: "embers", capacity: 64,
///     emitters: [Emitter(burst: 64, shape: Sphere(center: (0.0, 1.0, 0.0), radius: 0.5),
///                        velocity: Constant((0.0, 0.0, 0.0)))],
///     render: Render(color: [(0.0, (1.0, 0.4, 0.1, 1.0))],
///                    light: Some(ParticleLight(count: 4, intensity: 2.0, range: 3.0))))"#;
/// let gpu = Gpu::new(&Default::default())?;
/// let mut embers = Effect::from_source(&gpu, source, &Default::default())?;
/// embers.run(1, |_| {})?;
/// let lights = embers.particle_lights()?.read(&embers)?;
/// assert_eq!(lights.len(), 4);
/// let LightSource::Point { color, range, .. } = lights[0] else { panic!() };
/// assert!((color.x - 2.0).abs() < 1e-6 && range == 3.0);
/// # Ok(())
/// # }
/// ```
pub struct ParticleLights {
    probes: Vec<LightProbe>,
}

impl ParticleLights {
    /// Records every group's light kernels into `pass` (the benchmark times them alone).
    #[cfg(feature = "tools")]
    pub(crate) fn dispatch(&self, pass: &mut wgpu::ComputePass<'_>) {
        for probe in &self.probes {
            probe.dispatch(pass);
        }
    }

    /// Whether no group of the effect gives off light.
    pub fn is_empty(&self) -> bool {
        self.probes.is_empty()
    }

    /// The lights `effect`'s particles give off now, group by group, each brightest first, in
    /// the effect's own space (waits for the GPU).
    pub fn read(&self, effect: &Effect) -> Result<Vec<LightSource>, RuntimeError> {
        let mut lights = Vec::new();
        for probe in &self.probes {
            lights.extend(probe.measure(effect.steps_done())?);
        }
        Ok(lights)
    }

    /// The lights of a recent frame when a reading has come back (None: still waiting; a
    /// host keeps the last ones), and the next reading recorded into `encoder`, after the
    /// frame's steps. Never waits.
    pub fn watch(
        &self,
        effect: &Effect,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<Option<Vec<LightSource>>, RuntimeError> {
        let mut lights = Vec::new();
        let mut came = false;
        for probe in &self.probes {
            if let Some(read) = probe.watch(encoder, effect.steps_done())? {
                came = true;
                lights.extend(read);
            }
        }
        Ok(came.then_some(lights))
    }
}

impl Effect {
    /// The light kernels of every group whose look gives off light (`render.light`).
    pub fn particle_lights(&self) -> Result<ParticleLights, RuntimeError> {
        let mut probes = Vec::new();
        for group in self.groups() {
            if let Some(light) = group.effect.ir.render.light {
                probes.push(LightProbe::new(group, light)?);
            }
        }
        Ok(ParticleLights { probes })
    }
}
