//! What the Vulkan driver made of WGSL compute kernels: registers, local and shared memory per
//! entry point, as `VK_KHR_pipeline_executable_properties` reports them (NVIDIA's driver does;
//! Mesa's llvmpipe and lavapipe do not). The driver chooses a kernel's register count itself,
//! and a kernel that needs more spills to local or shared memory: docs/performance.md,
//! "Flocking", shows how the flock's search changed with it.
//!
//! ```sh
//! cargo build --release --example pipeline_stats
//! ./target/release/plume compile effects/boids.ron --emit flock-search -o search.wgsl
//! ./target/release/examples/pipeline_stats search.wgsl [ENTRY_POINT ...]
//! ```
//!
//! Each line is `FILE ENTRY: [statistic=value] ...`. The SPIR-V is naga's, with the bounds
//! checks wgpu gives a Vulkan device with `robustBufferAccess2` (storage buffers left to the
//! driver, fixed-size arrays clamped), so the driver sees what wgpu would give it.

use ash::vk;
use std::ffi::CStr;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.is_empty() {
        eprintln!("usage: pipeline_stats FILE.wgsl [ENTRY_POINT ...]");
        return ExitCode::FAILURE;
    }
    match run(&args[0], &args[1..]) {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::FAILURE
        }
    }
}

/// Compiles every compute entry point of `file` (or those named) and prints its statistics.
fn run(file: &str, wanted: &[String]) -> Result<(), String> {
    let source = std::fs::read_to_string(file).map_err(|e| format!("{file}: {e}"))?;
    let module = naga::front::wgsl::parse_str(&source).map_err(|e| e.emit_to_string(&source))?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .map_err(|e| format!("{file}: {e:?}"))?;
    let vulkan = Vulkan::new()?;
    for entry in &module.entry_points {
        if entry.stage != naga::ShaderStage::Compute
            || !(wanted.is_empty() || wanted.contains(&entry.name))
        {
            continue;
        }
        let words = spirv(&module, &info, &entry.name)?;
        let stats = vulkan.statistics(&module, &words, &entry.name)?;
        println!("{file} {}: {}", entry.name, stats.join(" "));
    }
    Ok(())
}

/// The entry point's SPIR-V, with the bounds-check policies wgpu uses on such a device.
fn spirv(
    module: &naga::Module,
    info: &naga::valid::ModuleInfo,
    entry: &str,
) -> Result<Vec<u32>, String> {
    let mut options = naga::back::spv::Options {
        lang_version: (1, 3),
        ..Default::default()
    };
    options.bounds_check_policies = naga::proc::BoundsCheckPolicies {
        index: naga::proc::BoundsCheckPolicy::Restrict,
        buffer: naga::proc::BoundsCheckPolicy::Unchecked,
        image_load: naga::proc::BoundsCheckPolicy::Unchecked,
        binding_array: naga::proc::BoundsCheckPolicy::Unchecked,
    };
    options.flags.remove(naga::back::spv::WriterFlags::DEBUG);
    let pipeline = naga::back::spv::PipelineOptions {
        shader_stage: naga::ShaderStage::Compute,
        entry_point: entry.to_string(),
    };
    naga::back::spv::write_vec(module, info, &options, Some(&pipeline))
        .map_err(|e| format!("SPIR-V for {entry}: {e}"))
}

/// A Vulkan device with pipeline executable statistics enabled.
struct Vulkan {
    // Kept alive for the device's sake.
    _entry: ash::Entry,
    instance: ash::Instance,
    device: ash::Device,
    executables: ash::khr::pipeline_executable_properties::Device,
}

impl Vulkan {
    fn new() -> Result<Self, String> {
        // SAFETY: loading the system's Vulkan loader; every call below follows the spec's
        // valid usage (structures built by ash's builders, handles from this instance).
        unsafe {
            let entry = ash::Entry::load()
                .map_err(|e| format!("no Vulkan loader ({e}): install libvulkan1 and a driver"))?;
            let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_3);
            let instance = entry
                .create_instance(
                    &vk::InstanceCreateInfo::default().application_info(&app),
                    None,
                )
                .map_err(|e| format!("vkCreateInstance: {e}"))?;
            let physical = *instance
                .enumerate_physical_devices()
                .map_err(|e| format!("no Vulkan device: {e}"))?
                .first()
                .ok_or("no Vulkan device")?;
            let props = instance.get_physical_device_properties(physical);
            let name = CStr::from_ptr(props.device_name.as_ptr()).to_string_lossy();
            let extension = ash::khr::pipeline_executable_properties::NAME;
            let has = instance
                .enumerate_device_extension_properties(physical)
                .map_err(|e| e.to_string())?
                .iter()
                .any(|e| CStr::from_ptr(e.extension_name.as_ptr()) == extension);
            if !has {
                return Err(format!(
                    "{name} has no VK_KHR_pipeline_executable_properties: its driver does not report what it compiled"
                ));
            }
            eprintln!("device: {name}");
            let family = instance
                .get_physical_device_queue_family_properties(physical)
                .iter()
                .position(|q| q.queue_flags.contains(vk::QueueFlags::COMPUTE))
                .ok_or("no compute queue")? as u32;
            let priorities = [1.0f32];
            let queues = [vk::DeviceQueueCreateInfo::default()
                .queue_family_index(family)
                .queue_priorities(&priorities)];
            // Every feature the device has, so that any capability naga's SPIR-V declares is on.
            let (features, mut f11, mut f12, mut f13) = {
                let mut f11 = vk::PhysicalDeviceVulkan11Features::default();
                let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
                let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
                let mut all = vk::PhysicalDeviceFeatures2::default()
                    .push_next(&mut f11)
                    .push_next(&mut f12)
                    .push_next(&mut f13);
                instance.get_physical_device_features2(physical, &mut all);
                let core = all.features;
                // Copies out of the query's chain: their p_next must not point into it.
                let (mut a, mut b, mut c) = (f11, f12, f13);
                a.p_next = std::ptr::null_mut();
                b.p_next = std::ptr::null_mut();
                c.p_next = std::ptr::null_mut();
                (core, a, b, c)
            };
            let mut executable_info =
                vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default()
                    .pipeline_executable_info(true);
            let extensions = [extension.as_ptr()];
            let create = vk::DeviceCreateInfo::default()
                .queue_create_infos(&queues)
                .enabled_extension_names(&extensions)
                .enabled_features(&features)
                .push_next(&mut f11)
                .push_next(&mut f12)
                .push_next(&mut f13)
                .push_next(&mut executable_info);
            let device = instance
                .create_device(physical, &create, None)
                .map_err(|e| format!("vkCreateDevice: {e}"))?;
            let executables =
                ash::khr::pipeline_executable_properties::Device::new(&instance, &device);
            Ok(Self {
                _entry: entry,
                instance,
                device,
                executables,
            })
        }
    }

    /// "name=value" for each statistic of the entry point's pipeline (a layout made from the
    /// module's bound globals).
    fn statistics(
        &self,
        module: &naga::Module,
        words: &[u32],
        entry: &str,
    ) -> Result<Vec<String>, String> {
        let device = &self.device;
        // SAFETY: as in `new`; the objects made here are destroyed before returning.
        unsafe {
            let shader = device
                .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(words), None)
                .map_err(|e| format!("vkCreateShaderModule: {e}"))?;
            let mut sets: Vec<Vec<vk::DescriptorSetLayoutBinding>> = Vec::new();
            for (_, global) in module.global_variables.iter() {
                let Some(binding) = &global.binding else {
                    continue;
                };
                let kind = match global.space {
                    naga::AddressSpace::Uniform => vk::DescriptorType::UNIFORM_BUFFER,
                    naga::AddressSpace::Storage { .. } => vk::DescriptorType::STORAGE_BUFFER,
                    naga::AddressSpace::Handle => match &module.types[global.ty].inner {
                        naga::TypeInner::Sampler { .. } => vk::DescriptorType::SAMPLER,
                        naga::TypeInner::Image {
                            class: naga::ImageClass::Storage { .. },
                            ..
                        } => vk::DescriptorType::STORAGE_IMAGE,
                        _ => vk::DescriptorType::SAMPLED_IMAGE,
                    },
                    _ => continue,
                };
                let group = binding.group as usize;
                if sets.len() <= group {
                    sets.resize(group + 1, Vec::new());
                }
                sets[group].push(
                    vk::DescriptorSetLayoutBinding::default()
                        .binding(binding.binding)
                        .descriptor_type(kind)
                        .descriptor_count(1)
                        .stage_flags(vk::ShaderStageFlags::COMPUTE),
                );
            }
            let mut set_layouts = Vec::new();
            for bindings in &sets {
                set_layouts.push(
                    device
                        .create_descriptor_set_layout(
                            &vk::DescriptorSetLayoutCreateInfo::default().bindings(bindings),
                            None,
                        )
                        .map_err(|e| e.to_string())?,
                );
            }
            let layout = device
                .create_pipeline_layout(
                    &vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts),
                    None,
                )
                .map_err(|e| e.to_string())?;
            let name = std::ffi::CString::new(entry).map_err(|e| e.to_string())?;
            let stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(shader)
                .name(&name);
            let create = [vk::ComputePipelineCreateInfo::default()
                .stage(stage)
                .layout(layout)
                .flags(vk::PipelineCreateFlags::CAPTURE_STATISTICS_KHR)];
            let pipeline = device
                .create_compute_pipelines(vk::PipelineCache::null(), &create, None)
                .map_err(|(_, e)| format!("vkCreateComputePipelines for {entry}: {e}"))?[0];
            let mut out = Vec::new();
            let executables = self
                .executables
                .get_pipeline_executable_properties(
                    &vk::PipelineInfoKHR::default().pipeline(pipeline),
                )
                .map_err(|e| e.to_string())?;
            for index in 0..executables.len() as u32 {
                let stats = self
                    .executables
                    .get_pipeline_executable_statistics(
                        &vk::PipelineExecutableInfoKHR::default()
                            .pipeline(pipeline)
                            .executable_index(index),
                    )
                    .map_err(|e| e.to_string())?;
                for stat in &stats {
                    let name = CStr::from_ptr(stat.name.as_ptr()).to_string_lossy();
                    let value = match stat.format {
                        vk::PipelineExecutableStatisticFormatKHR::BOOL32 => {
                            stat.value.b32.to_string()
                        }
                        vk::PipelineExecutableStatisticFormatKHR::INT64 => {
                            stat.value.i64.to_string()
                        }
                        // NVIDIA's driver sets bit 36 of the memory sizes; the size is below it.
                        vk::PipelineExecutableStatisticFormatKHR::UINT64 => {
                            (stat.value.u64 & ((1 << 36) - 1)).to_string()
                        }
                        _ => stat.value.f64.to_string(),
                    };
                    out.push(format!("[{name}={value}]"));
                }
            }
            device.destroy_pipeline(pipeline, None);
            device.destroy_pipeline_layout(layout, None);
            for set in set_layouts {
                device.destroy_descriptor_set_layout(set, None);
            }
            device.destroy_shader_module(shader, None);
            Ok(out)
        }
    }
}

impl Drop for Vulkan {
    fn drop(&mut self) {
        // SAFETY: nothing made from the device outlives this.
        unsafe {
            self.device.destroy_device(None);
            self.instance.destroy_instance(None);
        }
    }
}
