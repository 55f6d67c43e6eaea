//! The lights of a lit draw (`render.lit`, lit mesh particles): the uniform the draw module
//! reads them from, written in the view of each prepared frame.

use plume_compiler::lights::{Lights, LIGHTS_BYTES};
use plume_compiler::CompiledEffect;

use crate::device::buffers::staging;
use crate::device::gpu::Gpu;
use crate::draw::camera::Camera;
use crate::error::RuntimeError;

/// A lit draw's lights (`render.lit`): the world-space lights it is drawn with (the effect
/// file's until a host sets its own) and the uniform that holds them in the view of the frame
/// being prepared, written with the `DrawView`, so that no pixel moves a light.
pub(crate) struct LightsUniform {
    pub(crate) buffer: wgpu::Buffer,
    world: std::sync::Mutex<Lights>,
}

impl LightsUniform {
    /// The lights of `effect`'s draw; None for an unlit effect.
    pub(crate) fn new(gpu: &Gpu, effect: &CompiledEffect) -> Option<Self> {
        effect.ir.render.lit.as_ref()?;
        let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lights"),
            size: LIGHTS_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Some(Self {
            buffer,
            world: std::sync::Mutex::new(effect.ir.lights.clone()),
        })
    }

    /// Draws with `lights` (world space) from the next prepared frame on.
    pub(crate) fn set(&self, lights: &Lights) {
        *self.world.lock().unwrap_or_else(|p| p.into_inner()) = lights.clone();
    }

    /// Records a copy of the lights in `camera`'s view into the uniform.
    pub(crate) fn record(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        camera: &Camera,
    ) -> Result<(), RuntimeError> {
        let world = self.world.lock().unwrap_or_else(|p| p.into_inner());
        let bytes = world.transformed(camera.view.as_dmat4()).uniform_bytes();
        let src = staging(gpu, "lights", &bytes)?;
        encoder.copy_buffer_to_buffer(&src, 0, &self.buffer, 0, LIGHTS_BYTES);
        Ok(())
    }
}
