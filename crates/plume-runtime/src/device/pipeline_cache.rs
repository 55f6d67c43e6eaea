//! Shader modules, layouts and pipelines shared by everything built on one device (each
//! `Gpu` holds a [`PipelineCache`], which its clones share): a second
//! effect of the same compiled file, a second camera's draw of it, an effect built again (a
//! restart, a rebuild in the Bevy plugin) reuse the first one's instead of having the driver
//! compile them again. Creating a pipeline is most of what building an effect costs (the
//! driver compiles its kernels), so the second build of a file is much cheaper than the first.
//!
//! Keys are what the objects are made from: a module by its WGSL source (its length and two
//! 64-bit hashes), a bind group layout by its entries, a pipeline layout by its bind group
//! layout, a pipeline by its module, entry points, layout and fixed-function state. wgpu's
//! objects are reference-counted handles, so a cached one is the same object its first user
//! holds, and a bind group made from a shared pipeline's layout works with every user's copy.
//! Each map holds at most [`KEPT`] objects and is emptied when full (the objects live on in
//! their users): a program that builds many different effects keeps a bounded cache.

use std::collections::HashMap;
use std::hash::{DefaultHasher, Hash, Hasher};
use std::sync::Mutex;

/// The most objects of each kind kept.
const KEPT: usize = 256;

/// A WGSL source, by its length and two independent 64-bit hashes of it.
type SourceKey = (usize, u64, u64);

/// What a compute pipeline is made from.
#[derive(Clone, PartialEq, Eq, Hash)]
struct ComputeKey {
    module: wgpu::ShaderModule,
    entry: String,
    layout: Option<wgpu::PipelineLayout>,
    /// The override constants, by name, as their bits.
    constants: Vec<(String, u64)>,
}

/// What a render pipeline without vertex buffers, on a layout derived from its module, is
/// made from.
#[derive(Clone, PartialEq, Eq, Hash)]
pub(crate) struct RenderKey {
    pub module: wgpu::ShaderModule,
    pub entries: (String, String),
    pub primitive: wgpu::PrimitiveState,
    pub depth: Option<(wgpu::TextureFormat, wgpu::CompareFunction, bool)>,
    pub samples: u32,
    pub color: wgpu::TextureFormat,
    pub blend: wgpu::BlendState,
}

/// The shared objects of one device (every clone of a `Gpu` shares them).
#[derive(Default)]
pub(crate) struct PipelineCache {
    modules: Mutex<HashMap<SourceKey, wgpu::ShaderModule>>,
    bind_group_layouts: Mutex<HashMap<Vec<wgpu::BindGroupLayoutEntry>, wgpu::BindGroupLayout>>,
    pipeline_layouts: Mutex<HashMap<wgpu::BindGroupLayout, wgpu::PipelineLayout>>,
    compute: Mutex<HashMap<ComputeKey, wgpu::ComputePipeline>>,
    render: Mutex<HashMap<RenderKey, wgpu::RenderPipeline>>,
}

/// The object of `key` in `map`, or the one `make` creates, kept. The lock is not held while
/// `make` runs (a driver's compile can take long): two threads that both miss create one each,
/// and the first kept stays.
fn kept<K: Hash + Eq + Clone, V: Clone>(
    map: &Mutex<HashMap<K, V>>,
    key: K,
    make: impl FnOnce() -> V,
) -> V {
    let lock = || map.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(found) = lock().get(&key) {
        return found.clone();
    }
    let made = make();
    let mut map = lock();
    if map.len() >= KEPT {
        map.clear();
    }
    map.entry(key).or_insert(made).clone()
}

impl std::fmt::Debug for PipelineCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PipelineCache")
            .field("modules", &len(&self.modules))
            .field("compute", &len(&self.compute))
            .field("render", &len(&self.render))
            .finish_non_exhaustive()
    }
}

/// How many objects `map` keeps.
fn len<K, V>(map: &Mutex<HashMap<K, V>>) -> usize {
    map.lock().map_or(0, |m| m.len())
}

/// `source`'s key: its length and two hashes, the second salted.
fn source_key(source: &str) -> SourceKey {
    let mut first = DefaultHasher::new();
    source.hash(&mut first);
    let mut second = DefaultHasher::new();
    0x9e37_79b9_7f4a_7c15_u64.hash(&mut second);
    source.hash(&mut second);
    (source.len(), first.finish(), second.finish())
}

impl PipelineCache {
    /// The module of WGSL `source` ([`shader_module`]), made once per source.
    pub(crate) fn module(
        &self,
        device: &wgpu::Device,
        label: &str,
        source: &str,
    ) -> wgpu::ShaderModule {
        kept(&self.modules, source_key(source), || {
            shader_module(device, label, source)
        })
    }

    /// The bind group layout of `entries`, made once per set of entries.
    pub(crate) fn bind_group_layout(
        &self,
        device: &wgpu::Device,
        label: &str,
        entries: &[wgpu::BindGroupLayoutEntry],
    ) -> wgpu::BindGroupLayout {
        kept(&self.bind_group_layouts, entries.to_vec(), || {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries,
            })
        })
    }

    /// The pipeline layout of the one bind group layout `group`, made once per layout.
    pub(crate) fn pipeline_layout(
        &self,
        device: &wgpu::Device,
        label: &str,
        group: &wgpu::BindGroupLayout,
    ) -> wgpu::PipelineLayout {
        kept(&self.pipeline_layouts, group.clone(), || {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: &[Some(group)],
                immediate_size: 0,
            })
        })
    }

    /// The compute pipeline of `module`'s `entry` on `layout` with `constants`, `make`
    /// creating it the first time.
    pub(crate) fn compute(
        &self,
        (module, entry): (&wgpu::ShaderModule, &str),
        layout: Option<&wgpu::PipelineLayout>,
        constants: &[(&str, f64)],
        make: impl FnOnce() -> wgpu::ComputePipeline,
    ) -> wgpu::ComputePipeline {
        let key = ComputeKey {
            module: module.clone(),
            entry: entry.to_string(),
            layout: layout.cloned(),
            constants: constants
                .iter()
                .map(|(name, value)| (name.to_string(), value.to_bits()))
                .collect(),
        };
        kept(&self.compute, key, make)
    }

    /// The render pipeline `key` describes, `make` creating it the first time.
    pub(crate) fn render(
        &self,
        key: RenderKey,
        make: impl FnOnce() -> wgpu::RenderPipeline,
    ) -> wgpu::RenderPipeline {
        kept(&self.render, key, make)
    }
}

/// Builds a WGSL module with wgpu's bounds checks but without its loop bounding.
///
/// By default wgpu gives every loop a hidden counter that breaks out after 2^64 iterations
/// (so a shader cannot hang the driver); that counter hides a loop's trip count from the
/// driver's compiler, which then no longer unrolls `for (var k = 0u; k < 10u; k++)`, and the
/// arrays such loops index move from registers to memory: with the counters the radix sort's
/// downsweep was far slower than with the same loops unrolled by hand (docs/performance.md,
/// "Depth sort and the radix sort"). Every loop in Plume's kernels, written here or generated
/// by the compiler, ends by construction: a counter runs to a bound, a binary search narrows,
/// or a bit is cleared each iteration; effect files cannot write loops.
pub(crate) fn shader_module<'a>(
    device: &wgpu::Device,
    label: &str,
    source: impl Into<std::borrow::Cow<'a, str>>,
) -> wgpu::ShaderModule {
    let checks = wgpu::ShaderRuntimeChecks {
        force_loop_bounding: false,
        ..wgpu::ShaderRuntimeChecks::checked()
    };
    let descriptor = wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    };
    // SAFETY: bounds checks stay on; the loop bounding is off, which wgpu requires only that
    // no loop be infinite, and none is (see above).
    unsafe { device.create_shader_module_trusted(descriptor, checks) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_map_is_emptied_before_it_keeps_more() {
        let map = Mutex::new(HashMap::new());
        for k in 0..KEPT {
            assert_eq!(kept(&map, k, || k * 10), k * 10);
        }
        // Found, not made again.
        assert_eq!(kept(&map, 3, || 0), 30);
        assert_eq!(map.lock().unwrap().len(), KEPT);
        assert_eq!(kept(&map, KEPT, || 7), 7);
        assert_eq!(map.lock().unwrap().len(), 1);
    }

    #[test]
    fn sources_that_differ_have_different_keys() {
        let a = source_key("fn main() {}");
        assert_eq!(a, source_key("fn main() {}"));
        assert_ne!(a, source_key("fn main() { }"));
        assert_ne!(a.1, a.2, "the two hashes are independent");
    }
}
