//! The lights of a lit draw (`render.lit`, lit mesh particles): the uniform the draw module
//! reads them from, written in the view of each prepared frame, and the shadow map it reads
//! (`plume_compiler::shadow`): a host's, or until one is given a 1x1 stand-in.

use plume_compiler::lights::{Lights, LIGHTS_BYTES};
use plume_compiler::shadow::{SHADOW_MAP_BINDING, SHADOW_SAMPLER_BINDINGS};
use plume_compiler::CompiledEffect;

use crate::device::buffers::staging;
use crate::device::gpu::Gpu;
use crate::draw::camera::Camera;
use crate::error::RuntimeError;

/// A lit draw's lights (`render.lit`): the world-space lights it is drawn with (the effect
/// file's until a host sets its own), the uniform that holds them in the view of the frame
/// being prepared, written with the `DrawView`, so that no pixel moves a light, and the
/// shadow map bound beside it.
pub(crate) struct LightsUniform {
    pub(crate) buffer: wgpu::Buffer,
    /// The shadow map and its samplers, for a look that reads one (`Lit::shadows`).
    pub(crate) shadow: Option<ShadowBinding>,
    world: std::sync::Mutex<Lights>,
}

/// What a lit draw reads a shadow map through: the map's view (`texture_depth_2d_array`: a
/// host's, or a 1x1 stand-in) and the comparison samplers that filter it, for standard depth
/// (`LessEqual`: lit where the point is no deeper than the map) and reversed (`GreaterEqual`).
#[derive(Clone)]
pub(crate) struct ShadowBinding {
    pub(crate) map: wgpu::TextureView,
    samplers: [wgpu::Sampler; 2],
}

impl ShadowBinding {
    /// The stand-in map and the samplers.
    pub(crate) fn new(gpu: &Gpu) -> Self {
        let sampler = |compare| {
            gpu.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("shadow"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                compare: Some(compare),
                ..Default::default()
            })
        };
        Self {
            map: no_shadow_map(gpu),
            samplers: [
                sampler(wgpu::CompareFunction::LessEqual),
                sampler(wgpu::CompareFunction::GreaterEqual),
            ],
        }
    }

    /// The bind group entries: the map and the two samplers at their bindings.
    pub(crate) fn entries(&self) -> Vec<(u32, wgpu::BindingResource<'_>)> {
        let mut entries = vec![(
            SHADOW_MAP_BINDING,
            wgpu::BindingResource::TextureView(&self.map),
        )];
        for (binding, sampler) in SHADOW_SAMPLER_BINDINGS.into_iter().zip(&self.samplers) {
            entries.push((binding, wgpu::BindingResource::Sampler(sampler)));
        }
        entries
    }
}

impl LightsUniform {
    /// The lights of `effect`'s draw; None for an unlit effect.
    pub(crate) fn new(gpu: &Gpu, effect: &CompiledEffect) -> Option<Self> {
        let lit = effect.ir.render.lit.as_ref()?;
        let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lights"),
            size: LIGHTS_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Some(Self {
            buffer,
            shadow: lit.shadows.then(|| ShadowBinding::new(gpu)),
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

/// A 1x1 one-layer depth texture's array view: what a lit draw binds until a shadow map is
/// given (never read: the lights' shadow names no cascade then).
pub(crate) fn no_shadow_map(gpu: &Gpu) -> wgpu::TextureView {
    let texture = gpu.texture_2d(
        "no shadow map",
        (1, 1),
        wgpu::TextureFormat::Depth32Float,
        wgpu::TextureUsages::TEXTURE_BINDING,
    );
    array_view(&texture)
}

/// The depth-only array view of `map` that a lit draw reads, or why `map` cannot be a shadow
/// map: a depth format, 2D (its layers the cascades), single-sampled, with `TEXTURE_BINDING`.
pub(crate) fn shadow_map_view(map: &wgpu::Texture) -> Result<wgpu::TextureView, RuntimeError> {
    let refuse = |why: String| Err(RuntimeError::Control(format!("shadow map: {why}")));
    if !map.format().has_depth_aspect() {
        return refuse(format!(
            "the texture is {:?}, not a depth format",
            map.format()
        ));
    }
    if map.dimension() != wgpu::TextureDimension::D2 {
        return refuse("the texture must be 2D (its layers the cascades)".into());
    }
    if map.sample_count() != 1 {
        return refuse("the texture must be single-sampled".into());
    }
    if !map.usage().contains(wgpu::TextureUsages::TEXTURE_BINDING) {
        return refuse("the texture needs TextureUsages::TEXTURE_BINDING to be read".into());
    }
    Ok(array_view(map))
}

/// An error where draws are lit and none reads a shadow map (each part: whether it is lit,
/// whether it reads one): the effect was compiled without the lookup.
pub(crate) fn check_reads_shadows(
    parts: impl Iterator<Item = (bool, bool)>,
) -> Result<(), RuntimeError> {
    let (lit, shadowed) = parts.fold((false, false), |a, p| (a.0 || p.0, a.1 || p.1));
    match lit && !shadowed {
        true => Err(RuntimeError::Control(
            "shadow map: the effect's lit look was compiled without the shadow lookup; compile it with CompileOptions::receive_shadows (or give a light of its file `shadow: true`)".into(),
        )),
        false => Ok(()),
    }
}

fn array_view(map: &wgpu::Texture) -> wgpu::TextureView {
    map.create_view(&wgpu::TextureViewDescriptor {
        label: Some("shadow map"),
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        aspect: wgpu::TextureAspect::DepthOnly,
        ..Default::default()
    })
}
