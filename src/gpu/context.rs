//! Vulkan instance, physical-device choice, logical device and the memory allocator.

use std::ffi::{c_char, CStr};
use std::mem::ManuallyDrop;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use anyhow::{anyhow, bail, Context, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::kernel_cache::{self, CacheDir};
use super::pipeline_cache::PipelineCache;
use super::shader::{ShaderCache, ShaderCounts};
use super::validation::{Messages, Validation};

/// The device options of every command that opens one (`vkvcm` and `vkvcm-bench`).
#[derive(clap::Args, Clone, Debug)]
pub struct GpuArgs {
    /// Vulkan device: index or name substring (see `vkvcm devices`).
    #[arg(long)]
    pub device: Option<String>,
    /// Build every kernel afresh, neither reading nor writing the kernel cache (compiled
    /// kernels kept in $VKVCM_CACHE_DIR, else $XDG_CACHE_HOME/vkvcm, else ~/.cache/vkvcm;
    /// docs/kernel-cache.md).
    #[arg(long)]
    pub no_kernel_cache: bool,
}

impl GpuArgs {
    /// The device options: these arguments over the environment's ([`GpuOptions::from_env`]).
    pub fn options(&self) -> GpuOptions {
        let opts = GpuOptions::from_env(self.device.clone());
        if self.no_kernel_cache {
            GpuOptions { kernel_cache: None, ..opts }
        } else {
            opts
        }
    }
}

/// How to open the GPU.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// Device index or a case-insensitive substring of its name; `None` picks the best
    /// (discrete > integrated > virtual > CPU).
    pub device: Option<String>,
    /// Enable VK_LAYER_KHRONOS_validation and collect its messages.
    pub validation: bool,
    /// The folder of the kernel cache (compiled SPIR-V and the driver's pipeline cache,
    /// docs/kernel-cache.md); `None` builds every kernel afresh and writes nothing.
    pub kernel_cache: Option<PathBuf>,
    /// Use buffer device addresses where the device has them (`bufferDeviceAddress`);
    /// `false` makes the device look as if it lacked them, so the film and the other frame
    /// buffers are bound as storage buffers (docs/devices.md). `VKVCM_DEVICE_ADDRESSES=0`
    /// sets it from the environment.
    pub device_addresses: bool,
}

impl GpuOptions {
    /// Options from the environment: `VKVCM_VALIDATION=1` turns validation on; the
    /// kernel cache is in its default folder ([`kernel_cache::default_dir`]:
    /// `VKVCM_CACHE_DIR`, `XDG_CACHE_HOME` or `HOME`; `VKVCM_CACHE_DIR=` turns it off).
    pub fn from_env(device: Option<String>) -> Self {
        let validation = std::env::var("VKVCM_VALIDATION").is_ok_and(|v| v != "0" && !v.is_empty());
        let device_addresses = std::env::var("VKVCM_DEVICE_ADDRESSES").map_or(true, |v| v != "0");
        GpuOptions { device, validation, kernel_cache: kernel_cache::default_dir(), device_addresses }
    }

    /// Tests always run with validation and never with the user's kernel cache (they
    /// neither depend on nor write it): with none, or with the folder
    /// `VKVCM_TEST_KERNEL_CACHE` names when it is an absolute path (`make test` gives the
    /// suite one in target/, so that a kernel variant is compiled once per run rather than
    /// once per renderer); `VKVCM_TEST_DEVICE` may choose the device.
    pub fn for_tests() -> Self {
        let kernel_cache = std::env::var_os("VKVCM_TEST_KERNEL_CACHE").map(PathBuf::from).filter(|p| p.is_absolute());
        GpuOptions {
            device: std::env::var("VKVCM_TEST_DEVICE").ok(),
            validation: true,
            kernel_cache,
            device_addresses: true,
        }
    }
}

/// A feature or limit vkvcm checks for, whether the device has it, and what vkvcm does
/// without it.
#[derive(Clone, Debug)]
pub struct FeatureStatus {
    pub name: &'static str,
    pub required: bool,
    pub present: bool,
    /// What is used instead when it is absent (optional features), or why it is needed.
    pub without: &'static str,
    /// The device's value, for limits (empty for plain features).
    pub value: String,
}

impl FeatureStatus {
    fn feature(name: &'static str, required: bool, present: bool, without: &'static str) -> FeatureStatus {
        FeatureStatus { name, required, present, without, value: String::new() }
    }
}

/// Storage buffers the render kernel with the most of them binds (the camera kernel of
/// vcm with the light-vertex cache and storage reads: 8 scene, 2 film, 1 splat, 3
/// light-vertex store, 2 grid, 2 cache). `Gpu::kernel` checks every kernel's own count.
pub const MOST_STORAGE_BUFFERS_PER_KERNEL: u32 = 18;
/// Texel buffers the render kernel with the most of them binds (the same kernel with
/// texel reads: 7 scene, 3 store, 2 grid, 2 cache).
pub const MOST_TEXEL_BUFFERS_PER_KERNEL: u32 = 14;
/// Shared memory of the largest workgroup (exclusive_scan.comp: 2 x 64 uint).
pub const SHARED_MEMORY_BYTES: u32 = 512;
/// Invocations per workgroup of the render kernels (src/render/variants.rs).
pub const WORKGROUP_INVOCATIONS: u32 = 64;

/// What `vkvcm devices` prints for one physical device.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub index: usize,
    pub name: String,
    pub device_type: vk::PhysicalDeviceType,
    pub driver: String,
    pub api_version: String,
    pub features: Vec<FeatureStatus>,
}

impl DeviceInfo {
    pub fn type_name(&self) -> &'static str {
        match self.device_type {
            vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
            vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
            vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
            vk::PhysicalDeviceType::CPU => "CPU",
            _ => "other",
        }
    }

    pub fn missing_required(&self) -> Vec<&'static str> {
        self.features.iter().filter(|f| f.required && !f.present).map(|f| f.name).collect()
    }
}

/// The opened device and everything that lives as long as it.
pub struct Gpu {
    /// Keeps the Vulkan loader loaded for the instance's lifetime.
    #[allow(dead_code)]
    entry: ash::Entry,
    pub(crate) instance: ash::Instance,
    pub(crate) physical: vk::PhysicalDevice,
    pub(crate) device: ash::Device,
    pub(crate) queue: vk::Queue,
    pub(crate) queue_family: u32,
    pub(crate) allocator: ManuallyDrop<Mutex<Allocator>>,
    pub(crate) shaders: ShaderCache,
    pub(crate) pipelines: PipelineCache,
    kernel_cache: Option<CacheDir>,
    pub(crate) timestamp_period_ns: f64,
    pub(crate) timestamps: bool,
    pub info: DeviceInfo,
    pub limits: vk::PhysicalDeviceLimits,
    pub subgroup_size: u32,
    /// maxMemoryAllocationSize: the largest buffer (a buffer lies in one allocation).
    pub max_allocation_bytes: u64,
    validation: Option<Validation>,
    /// VK_EXT_debug_utils names and labels (src/gpu/debug_names.rs).
    pub(crate) debug: super::debug_names::DebugNames,
}

const API_VERSION: u32 = vk::API_VERSION_1_2;

fn cstr(chars: &[c_char]) -> String {
    // SAFETY: Vulkan guarantees NUL-terminated fixed-size strings.
    unsafe { CStr::from_ptr(chars.as_ptr()) }.to_string_lossy().into_owned()
}

fn version_string(v: u32) -> String {
    format!("{}.{}.{}", vk::api_version_major(v), vk::api_version_minor(v), vk::api_version_patch(v))
}

fn load_entry() -> Result<ash::Entry> {
    // SAFETY: loading the system Vulkan loader; no other invariants.
    unsafe { ash::Entry::load() }.map_err(|e| {
        anyhow!("cannot load the Vulkan loader (libvulkan.so.1): {e}; install libvulkan1 and a driver (scripts/setup-debian.sh)")
    })
}

fn create_instance(entry: &ash::Entry, validation: bool) -> Result<ash::Instance> {
    let app = vk::ApplicationInfo::default().application_name(c"vkvcm").engine_name(c"vkvcm").api_version(API_VERSION);
    let mut layers: Vec<*const c_char> = Vec::new();
    let mut exts: Vec<*const c_char> = Vec::new();
    if validation {
        // SAFETY: plain enumeration call.
        let available = unsafe { entry.enumerate_instance_layer_properties() }?;
        let name = c"VK_LAYER_KHRONOS_validation";
        if !available.iter().any(|l| l.layer_name_as_c_str().ok() == Some(name)) {
            bail!("validation requested but VK_LAYER_KHRONOS_validation is not installed (apt-get install vulkan-validationlayers)");
        }
        layers.push(name.as_ptr());
    }
    // Validation's messenger and the objects' names (src/gpu/debug_names.rs) need it.
    if super::debug_names::available(entry) {
        exts.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    let info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&exts);
    // SAFETY: all pointers in `info` outlive the call.
    unsafe { entry.create_instance(&info, None) }.context("vkCreateInstance failed")
}

/// Names of the entries of [`feature_status`] that code looks up.
pub const SHADER_INT64: &str = "shaderInt64";
pub const SHADER_INT64_ATOMICS: &str = "shaderBufferInt64Atomics";
pub const TEXEL_BUFFER_FORMATS: &str = "uniform texel buffers of R32G32B32A32_UINT and R32_UINT";
pub const TIMESTAMPS: &str = "timestampComputeAndGraphics";
pub const BUFFER_DEVICE_ADDRESS: &str = "bufferDeviceAddress";

/// Every feature and limit the kernels use (docs/devices.md): required ones, and
/// optional ones with the fallback vkvcm uses without them.
fn feature_status(instance: &ash::Instance, pd: vk::PhysicalDevice) -> Vec<FeatureStatus> {
    // SAFETY: valid handle.
    let props = unsafe { instance.get_physical_device_properties(pd) };
    let mut out = device_features(instance, pd, &props);
    out.extend(device_limits(instance, pd, &props.limits));
    out
}

/// The features of [`feature_status`].
fn device_features(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    props: &vk::PhysicalDeviceProperties,
) -> Vec<FeatureStatus> {
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f12);
    // SAFETY: valid handles, chain of stack structs.
    unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    let base = f2.features;
    // SAFETY: valid handle.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let texel_ok = [vk::Format::R32G32B32A32_UINT, vk::Format::R32_UINT].iter().all(|&f| {
        // SAFETY: valid handle.
        let fp = unsafe { instance.get_physical_device_format_properties(pd, f) };
        fp.buffer_features.contains(vk::FormatFeatureFlags::UNIFORM_TEXEL_BUFFER)
    });
    let without_int64 = super::fault_injection::simulated_missing_int64();
    let l = &props.limits;
    vec![
        FeatureStatus::feature("Vulkan 1.2", true, props.api_version >= API_VERSION, "the API vkvcm is written to"),
        FeatureStatus::feature(
            "a compute queue",
            true,
            families.iter().any(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE)),
            "every kernel is a compute shader",
        ),
        FeatureStatus::feature(
            SHADER_INT64,
            false,
            base.shader_int64 == vk::TRUE && !without_int64,
            "the BVH is read with 32-bit loads",
        ),
        FeatureStatus::feature(
            SHADER_INT64_ATOMICS,
            false,
            f12.shader_buffer_int64_atomics == vk::TRUE && base.shader_int64 == vk::TRUE && !without_int64,
            "splats are summed in two 32-bit words per channel (--atomics 32; the same image)",
        ),
        FeatureStatus::feature(
            TEXEL_BUFFER_FORMATS,
            false,
            texel_ok,
            "read-only buffers are read as storage buffers (--reads storage)",
        ),
        FeatureStatus::feature(
            BUFFER_DEVICE_ADDRESS,
            false,
            f12.buffer_device_address == vk::TRUE,
            "the film and the other frame buffers are bound as storage buffers, each at most maxStorageBufferRange",
        ),
        FeatureStatus::feature(
            TIMESTAMPS,
            false,
            l.timestamp_compute_and_graphics == vk::TRUE,
            "--profile reports no GPU times",
        ),
    ]
}

/// The limits of [`feature_status`]: required minimums, and the sizes a render is
/// checked against.
fn device_limits(instance: &ash::Instance, pd: vk::PhysicalDevice, l: &vk::PhysicalDeviceLimits) -> Vec<FeatureStatus> {
    let limit = |name: &'static str, value: u64, needed: u64, why: &'static str| FeatureStatus {
        name,
        required: true,
        present: value >= needed,
        without: why,
        value: format!("{value} (needs {needed})"),
    };
    let report = |name: &'static str, value: String, why: &'static str| FeatureStatus {
        name,
        required: false,
        present: true,
        without: why,
        value,
    };
    vec![
        limit(
            "maxComputeWorkGroupInvocations",
            l.max_compute_work_group_invocations as u64,
            WORKGROUP_INVOCATIONS as u64,
            "workgroups of 64 invocations",
        ),
        limit(
            "maxComputeWorkGroupSize[0]",
            l.max_compute_work_group_size[0] as u64,
            WORKGROUP_INVOCATIONS as u64,
            "workgroups of 64 invocations",
        ),
        limit(
            "maxComputeSharedMemorySize",
            l.max_compute_shared_memory_size as u64,
            SHARED_MEMORY_BYTES as u64,
            "the prefix sum's workgroup scan",
        ),
        limit(
            "maxPerStageDescriptorStorageBuffers",
            l.max_per_stage_descriptor_storage_buffers as u64,
            MOST_STORAGE_BUFFERS_PER_KERNEL as u64,
            "the camera kernel's buffers with storage reads",
        ),
        limit(
            "maxPerStageDescriptorSampledImages",
            l.max_per_stage_descriptor_sampled_images as u64,
            MOST_TEXEL_BUFFERS_PER_KERNEL as u64,
            "the camera kernel's texel buffers with texel reads",
        ),
        limit("maxPushConstantsSize", l.max_push_constants_size as u64, 128, "the kernels' push constants"),
        report(
            "maxStorageBufferRange",
            format!("{} MiB", l.max_storage_buffer_range as u64 >> 20),
            "the largest buffer a render may bind (checked per render)",
        ),
        report(
            "maxTexelBufferElements",
            // Exact: SwiftShader's 65536 would print as 0 M.
            format!(
                "{} texels ({} bytes of 16-byte texels)",
                l.max_texel_buffer_elements,
                l.max_texel_buffer_elements as u64 * 16
            ),
            "the largest texel buffer (checked per render)",
        ),
        report(
            "maxMemoryAllocationSize",
            format!("{} MiB", max_allocation_bytes(instance, pd) >> 20),
            "the largest buffer, and the largest one reached by device address (checked per render)",
        ),
        report(
            "largest device-local memory heap",
            format!("{} MiB", largest_heap_bytes(instance, pd) >> 20),
            "all of a render's buffers (checked per render)",
        ),
        report(
            "maxComputeWorkGroupCount[0]",
            l.max_compute_work_group_count[0].to_string(),
            "larger dispatches are folded into 2-D",
        ),
    ]
}

/// maxMemoryAllocationSize of `pd` (Vulkan 1.1).
fn max_allocation_bytes(instance: &ash::Instance, pd: vk::PhysicalDevice) -> u64 {
    let mut m3 = vk::PhysicalDeviceMaintenance3Properties::default();
    let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut m3);
    // SAFETY: valid handle, chain of stack structs.
    unsafe { instance.get_physical_device_properties2(pd, &mut p2) };
    m3.max_memory_allocation_size
}

/// Size in bytes of the largest device-local memory heap of `pd` (the largest heap if
/// none is marked device-local).
fn largest_heap_bytes(instance: &ash::Instance, pd: vk::PhysicalDevice) -> u64 {
    // SAFETY: valid handles.
    let mem = unsafe { instance.get_physical_device_memory_properties(pd) };
    let heaps = &mem.memory_heaps[..mem.memory_heap_count as usize];
    let local = heaps.iter().filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL)).map(|h| h.size).max();
    local.or_else(|| heaps.iter().map(|h| h.size).max()).unwrap_or(0)
}

fn describe(instance: &ash::Instance, index: usize, pd: vk::PhysicalDevice) -> DeviceInfo {
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
    // SAFETY: valid handle; the driver-properties struct is core in 1.2 and ignored by
    // older drivers (then driver_name stays empty).
    unsafe { instance.get_physical_device_properties2(pd, &mut p2) };
    let props = p2.properties;
    let driver_name = cstr(&driver.driver_name);
    let driver_info = cstr(&driver.driver_info);
    DeviceInfo {
        index,
        name: cstr(&props.device_name),
        device_type: props.device_type,
        driver: if driver_info.is_empty() { driver_name } else { format!("{driver_name} {driver_info}") },
        api_version: version_string(props.api_version),
        features: feature_status(instance, pd),
    }
}

fn type_rank(t: vk::PhysicalDeviceType) -> u32 {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// Every Vulkan device on the machine.
pub fn list_devices() -> Result<Vec<DeviceInfo>> {
    let entry = load_entry()?;
    let instance = create_instance(&entry, false)?;
    // SAFETY: instance is valid until destroyed below.
    let pds = unsafe { instance.enumerate_physical_devices() };
    let out = pds.map(|pds| pds.iter().enumerate().map(|(i, &pd)| describe(&instance, i, pd)).collect());
    // SAFETY: nothing created from the instance survives.
    unsafe { instance.destroy_instance(None) };
    Ok(out?)
}

/// Picks a device: by index or name substring when asked, otherwise the best type that
/// has every required feature.
fn choose(infos: &[DeviceInfo], wanted: Option<&str>) -> Result<usize> {
    if infos.is_empty() {
        bail!("no Vulkan device found (is a driver installed? lavapipe: apt-get install mesa-vulkan-drivers)");
    }
    let names = || infos.iter().map(|d| format!("{}: {}", d.index, d.name)).collect::<Vec<_>>().join(", ");
    let idx = match wanted {
        Some(w) => {
            if let Ok(i) = w.parse::<usize>() {
                if i >= infos.len() {
                    bail!("no Vulkan device with index {i} (devices: {})", names());
                }
                i
            } else {
                let lw = w.to_lowercase();
                infos
                    .iter()
                    .position(|d| d.name.to_lowercase().contains(&lw))
                    .ok_or_else(|| anyhow!("no Vulkan device named like {w:?} (devices: {})", names()))?
            }
        }
        None => {
            let usable = infos.iter().filter(|d| d.missing_required().is_empty());
            match usable.min_by_key(|d| (type_rank(d.device_type), d.index)) {
                Some(d) => d.index,
                None => 0, // reported as a missing feature below
            }
        }
    };
    let missing = infos[idx].missing_required();
    if !missing.is_empty() {
        bail!("Vulkan device {:?} lacks required feature(s): {}", infos[idx].name, missing.join(", "));
    }
    Ok(idx)
}

/// What `Gpu::open` creates from the instance: the device and what comes with it.
struct DeviceParts {
    physical: vk::PhysicalDevice,
    device: ash::Device,
    queue: vk::Queue,
    queue_family: u32,
    allocator: Allocator,
    timestamps: bool,
    info: DeviceInfo,
    props: vk::PhysicalDeviceProperties,
    max_allocation_bytes: u64,
    subgroup_size: u32,
    pipelines: PipelineCache,
    kernel_cache: Option<CacheDir>,
}

impl Gpu {
    /// Opens a device as `opts` says.
    pub fn new(opts: &GpuOptions) -> Result<Arc<Gpu>> {
        let entry = load_entry()?;
        let instance = create_instance(&entry, opts.validation)?;
        let validation = if opts.validation { Some(Validation::new(&entry, &instance)?) } else { None };
        match Self::open(entry.clone(), instance.clone(), opts, validation) {
            Ok(g) => Ok(Arc::new(g)),
            Err((e, validation)) => {
                drop(validation);
                // SAFETY: only the messenger was created from it, and it is gone.
                unsafe { instance.destroy_instance(None) };
                Err(e)
            }
        }
    }

    #[allow(clippy::result_large_err)]
    fn open(
        entry: ash::Entry,
        instance: ash::Instance,
        opts: &GpuOptions,
        validation: Option<Validation>,
    ) -> std::result::Result<Gpu, (anyhow::Error, Option<Validation>)> {
        let step = || -> Result<DeviceParts> {
            // SAFETY: valid instance.
            let pds = unsafe { instance.enumerate_physical_devices() }?;
            let infos: Vec<DeviceInfo> = pds.iter().enumerate().map(|(i, &pd)| describe(&instance, i, pd)).collect();
            let idx = choose(&infos, opts.device.as_deref())?;
            let mut info = infos[idx].clone();
            if !opts.device_addresses {
                info.features.iter_mut().filter(|f| f.name == BUFFER_DEVICE_ADDRESS).for_each(|f| f.present = false);
            }
            let physical = pds[idx];
            // SAFETY: valid handle.
            let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
            let queue_family = families
                .iter()
                .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
                .ok_or_else(|| anyhow!("device {:?} has no compute queue", infos[idx].name))?
                as u32;
            let timestamps = families[queue_family as usize].timestamp_valid_bits > 0
                && infos[idx].features.iter().any(|f| f.name == TIMESTAMPS && f.present);
            let prio = [1.0f32];
            let qinfo = [vk::DeviceQueueCreateInfo::default().queue_family_index(queue_family).queue_priorities(&prio)];
            // Only what the device has is enabled; kernels that would need more are not
            // built (src/render/variants.rs chooses the 32-bit fallbacks).
            let has = |name: &str| info.features.iter().any(|f| f.name == name && f.present);
            let device_addresses = has(BUFFER_DEVICE_ADDRESS);
            let base = vk::PhysicalDeviceFeatures::default().shader_int64(has(SHADER_INT64));
            let mut f12 = vk::PhysicalDeviceVulkan12Features::default()
                .shader_buffer_int64_atomics(has(SHADER_INT64_ATOMICS))
                .buffer_device_address(device_addresses);
            let dinfo =
                vk::DeviceCreateInfo::default().queue_create_infos(&qinfo).enabled_features(&base).push_next(&mut f12);
            // SAFETY: features were checked present by `choose`.
            let device = unsafe { instance.create_device(physical, &dinfo, None) }.context("vkCreateDevice failed")?;
            // SAFETY: queue 0 of the family was requested.
            let queue = unsafe { device.get_device_queue(queue_family, 0) };
            let allocator = Allocator::new(&AllocatorCreateDesc {
                instance: instance.clone(),
                device: device.clone(),
                physical_device: physical,
                debug_settings: Default::default(),
                buffer_device_address: device_addresses,
                allocation_sizes: Default::default(),
            });
            let allocator = match allocator {
                Ok(a) => a,
                Err(e) => {
                    // SAFETY: nothing else was created from the device.
                    unsafe { device.destroy_device(None) };
                    return Err(anyhow!("cannot create the memory allocator: {e}"));
                }
            };
            let mut sub = vk::PhysicalDeviceSubgroupProperties::default();
            let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut sub);
            // SAFETY: valid handle.
            unsafe { instance.get_physical_device_properties2(physical, &mut p2) };
            let props = p2.properties;
            let kernel_cache = opts.kernel_cache.clone().map(CacheDir::new);
            let pipelines = PipelineCache::open(&device, &props, kernel_cache.clone());
            Ok(DeviceParts {
                physical,
                device,
                queue,
                queue_family,
                allocator,
                timestamps,
                info,
                props,
                max_allocation_bytes: max_allocation_bytes(&instance, physical),
                subgroup_size: sub.subgroup_size,
                pipelines,
                kernel_cache,
            })
        };
        let debug_utils = super::debug_names::available(&entry);
        match step() {
            Ok(p) => Ok(Gpu {
                debug: super::debug_names::DebugNames::new(&instance, &p.device, debug_utils),
                entry,
                instance,
                physical: p.physical,
                device: p.device,
                queue: p.queue,
                queue_family: p.queue_family,
                allocator: ManuallyDrop::new(Mutex::new(p.allocator)),
                shaders: ShaderCache::new(p.kernel_cache.clone()),
                pipelines: p.pipelines,
                kernel_cache: p.kernel_cache,
                timestamp_period_ns: p.props.limits.timestamp_period as f64,
                timestamps: p.timestamps,
                info: p.info,
                limits: super::fault_injection::capped_binding_limits(p.props.limits),
                subgroup_size: p.subgroup_size,
                max_allocation_bytes: p.max_allocation_bytes,
                validation,
            }),
            Err(e) => Err((e, validation)),
        }
    }

    /// Whether the device has the feature or limit `name` of [`feature_status`] (and vkvcm
    /// enabled it).
    pub fn has(&self, name: &str) -> bool {
        self.info.features.iter().any(|f| f.name == name && f.present)
    }

    /// Validation messages received so far (empty when validation is off).
    pub fn validation_messages(&self) -> Messages {
        self.validation.as_ref().map(|v| v.messages()).unwrap_or_default()
    }

    pub fn validation_enabled(&self) -> bool {
        self.validation.is_some()
    }

    /// VK_EXT_debug_utils objects named and dispatch labels recorded so far; `None` where
    /// the instance has no VK_EXT_debug_utils.
    pub fn debug_name_counts(&self) -> Option<(u64, u64)> {
        self.debug.counts()
    }

    /// Size in bytes of the largest device-local memory heap (the largest heap if none is
    /// marked device-local): where every vkvcm buffer lives. On lavapipe it is system RAM.
    pub fn device_local_heap_bytes(&self) -> u64 {
        largest_heap_bytes(&self.instance, self.physical)
    }

    /// The kernel cache's folder (`None`: no kernel cache).
    pub fn kernel_cache_dir(&self) -> Option<&Path> {
        self.kernel_cache.as_ref().map(CacheDir::path)
    }

    /// How many kernel variants were compiled and how many read from the kernel cache.
    pub fn shader_counts(&self) -> ShaderCounts {
        self.shaders.counts()
    }

    /// Bytes of pipeline-cache data read from the kernel cache when the device was opened
    /// (0: the pipeline cache started empty).
    pub fn pipeline_cache_loaded_bytes(&self) -> usize {
        self.pipelines.loaded_bytes()
    }

    /// Writes the pipeline cache to the kernel cache now if pipelines were created since
    /// it was last written (it is also written when the `Gpu` is dropped): called once a
    /// renderer's kernels exist, so a process that does not end normally keeps them.
    pub fn save_pipeline_cache(&self) {
        self.pipelines.save(&self.device);
    }

    /// Waits until the device is idle.
    pub fn wait_idle(&self) -> Result<()> {
        // SAFETY: valid device.
        unsafe { self.device.device_wait_idle() }.context("vkDeviceWaitIdle failed (device lost?)")
    }
}

impl Drop for Gpu {
    fn drop(&mut self) {
        // SAFETY: every object created from the device is owned by something holding an
        // `Arc<Gpu>`, so all of them are gone by now.
        unsafe {
            let _ = self.device.device_wait_idle();
            self.shaders.destroy(&self.device);
            self.pipelines.destroy(&self.device);
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
        }
        if let Some(v) = self.validation.take() {
            let msgs = v.messages();
            drop(v);
            for m in msgs.list() {
                eprintln!("vulkan validation: {m}");
            }
        }
        // SAFETY: the messenger (if any) was destroyed above.
        unsafe { self.instance.destroy_instance(None) };
        let _ = &self.physical;
    }
}
