//! Vulkan instance, physical-device choice, logical device and the memory allocator.

use std::ffi::{c_char, CStr};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

use anyhow::{anyhow, bail, Context, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::shader::ShaderCache;
use super::validation::{Messages, Validation};

/// How to open the GPU.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// Device index or a case-insensitive substring of its name; `None` picks the best
    /// (discrete > integrated > virtual > CPU).
    pub device: Option<String>,
    /// Enable VK_LAYER_KHRONOS_validation and collect its messages.
    pub validation: bool,
}

impl GpuOptions {
    /// Options from the environment: `VKVCM_VALIDATION=1` turns validation on.
    pub fn from_env(device: Option<String>) -> Self {
        let validation = std::env::var("VKVCM_VALIDATION").is_ok_and(|v| v != "0" && !v.is_empty());
        GpuOptions { device, validation }
    }

    /// Tests always run with validation; `VKVCM_TEST_DEVICE` may choose the device.
    pub fn for_tests() -> Self {
        GpuOptions { device: std::env::var("VKVCM_TEST_DEVICE").ok(), validation: true }
    }
}

/// A feature vkvcm checks for, and whether the device has it.
#[derive(Clone, Debug)]
pub struct FeatureStatus {
    pub name: &'static str,
    pub required: bool,
    pub present: bool,
}

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
    pub(crate) timestamp_period_ns: f64,
    pub(crate) timestamps: bool,
    pub info: DeviceInfo,
    pub limits: vk::PhysicalDeviceLimits,
    pub subgroup_size: u32,
    validation: Option<Validation>,
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
        exts.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    let info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&exts);
    // SAFETY: all pointers in `info` outlive the call.
    unsafe { entry.create_instance(&info, None) }.context("vkCreateInstance failed")
}

/// Features vkvcm needs. 64-bit integer buffer atomics carry the deterministic
/// fixed-point splatting of light tracing; timestamps only the profiler.
fn feature_status(instance: &ash::Instance, pd: vk::PhysicalDevice) -> Vec<FeatureStatus> {
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f12);
    // SAFETY: valid handles, chain of stack structs.
    unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    let base = f2.features;
    // SAFETY: valid handle.
    let props = unsafe { instance.get_physical_device_properties(pd) };
    vec![
        FeatureStatus { name: "Vulkan 1.2", required: true, present: props.api_version >= API_VERSION },
        FeatureStatus { name: "shaderInt64", required: true, present: base.shader_int64 == vk::TRUE },
        FeatureStatus {
            name: "shaderBufferInt64Atomics",
            required: true,
            present: f12.shader_buffer_int64_atomics == vk::TRUE,
        },
        FeatureStatus {
            name: "timestampComputeAndGraphics (profiler)",
            required: false,
            present: props.limits.timestamp_compute_and_graphics == vk::TRUE,
        },
    ]
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
        let step = || -> Result<_> {
            // SAFETY: valid instance.
            let pds = unsafe { instance.enumerate_physical_devices() }?;
            let infos: Vec<DeviceInfo> = pds.iter().enumerate().map(|(i, &pd)| describe(&instance, i, pd)).collect();
            let idx = choose(&infos, opts.device.as_deref())?;
            let physical = pds[idx];
            // SAFETY: valid handle.
            let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
            let queue_family = families
                .iter()
                .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
                .ok_or_else(|| anyhow!("device {:?} has no compute queue", infos[idx].name))?
                as u32;
            let timestamps = families[queue_family as usize].timestamp_valid_bits > 0
                && infos[idx].features.iter().any(|f| f.name.starts_with("timestamp") && f.present);
            let prio = [1.0f32];
            let qinfo = [vk::DeviceQueueCreateInfo::default().queue_family_index(queue_family).queue_priorities(&prio)];
            let base = vk::PhysicalDeviceFeatures::default().shader_int64(true);
            let mut f12 = vk::PhysicalDeviceVulkan12Features::default().shader_buffer_int64_atomics(true);
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
                buffer_device_address: false,
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
            Ok((
                physical,
                device,
                queue,
                queue_family,
                allocator,
                timestamps,
                infos[idx].clone(),
                props,
                sub.subgroup_size,
            ))
        };
        match step() {
            Ok((physical, device, queue, queue_family, allocator, timestamps, info, props, subgroup_size)) => Ok(Gpu {
                entry,
                instance,
                physical,
                device,
                queue,
                queue_family,
                allocator: ManuallyDrop::new(Mutex::new(allocator)),
                shaders: ShaderCache::default(),
                timestamp_period_ns: props.limits.timestamp_period as f64,
                timestamps,
                info,
                limits: props.limits,
                subgroup_size,
                validation,
            }),
            Err(e) => Err((e, validation)),
        }
    }

    /// Validation messages received so far (empty when validation is off).
    pub fn validation_messages(&self) -> Messages {
        self.validation.as_ref().map(|v| v.messages()).unwrap_or_default()
    }

    pub fn validation_enabled(&self) -> bool {
        self.validation.is_some()
    }

    /// Size in bytes of the largest device-local memory heap (the largest heap if none is
    /// marked device-local): where every vkvcm buffer lives. On lavapipe it is system RAM.
    pub fn device_local_heap_bytes(&self) -> u64 {
        // SAFETY: valid handles.
        let mem = unsafe { self.instance.get_physical_device_memory_properties(self.physical) };
        let heaps = &mem.memory_heaps[..mem.memory_heap_count as usize];
        let local = heaps.iter().filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL)).map(|h| h.size).max();
        local.or_else(|| heaps.iter().map(|h| h.size).max()).unwrap_or(0)
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
