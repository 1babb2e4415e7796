//! A minimal Vulkan device for the driver's own ray tracing: VK_KHR_acceleration_structure
//! (one opaque triangle BLAS, one TLAS instance) and VK_KHR_ray_query in a compute shader
//! (`rayquery_bench.comp`). Opened with ash next to vkvcm's `Gpu`, which knows nothing of
//! it: the renderer does not depend on ray tracing extensions.
//!
//! Memory: every buffer is host-visible (device-local too when the device has such a
//! type; lavapipe's only type is both), which keeps this small; on a discrete GPU without
//! resizable BAR the rays would live in system memory.

use std::ffi::{c_char, c_void, CStr};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use anyhow::{anyhow, bail, Context, Result};
use ash::vk;
use vkvcm::scene::Triangle;
use vkvcm_tools::bench::traverse::BenchRay;

const SHADER: &str = include_str!("rayquery_bench.comp");
const LOCAL_SIZE: u32 = 64;

type Messages = Arc<Mutex<Vec<String>>>;

unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: `user` is the `Messages` owned by `RqDevice`, alive while the messenger is;
    // `data` is valid for the call.
    unsafe {
        let msgs = &*(user as *const Messages);
        let text = if data.is_null() || (*data).p_message.is_null() {
            "(no message)".to_string()
        } else {
            CStr::from_ptr((*data).p_message).to_string_lossy().into_owned()
        };
        if let Ok(mut v) = msgs.lock() {
            v.push(format!("[{severity:?}] {text}"));
        }
    }
    vk::FALSE
}

/// A buffer with its memory, mapped, and its device address when it has one.
pub struct Buf {
    buffer: vk::Buffer,
    memory: vk::DeviceMemory,
    ptr: *mut u8,
    size: u64,
    address: u64,
}

/// A built BLAS + TLAS over one scene's triangles.
pub struct RqScene {
    blas: vk::AccelerationStructureKHR,
    tlas: vk::AccelerationStructureKHR,
    buffers: Vec<Buf>,
    /// Device time of the BLAS and TLAS builds (timestamps), and the wall time of the
    /// whole build submission.
    pub blas_ms: f64,
    pub tlas_ms: f64,
    pub build_wall_ms: f64,
    pub blas_bytes: u64,
}

/// The rays of one set and room for their results.
pub struct RqRays {
    rays: Buf,
    results: Buf,
    count: u32,
}

pub struct RqDevice {
    _entry: ash::Entry,
    instance: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    messages: Box<Messages>,
    device: ash::Device,
    accel: ash::khr::acceleration_structure::Device,
    queue: vk::Queue,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    queries: vk::QueryPool,
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    descriptor_pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
    memory_type: u32,
    timestamp_period_ns: f64,
    scratch_align: u64,
    /// Device name and driver, as the device reports them.
    pub name: String,
    pub driver: String,
}

fn cstr(chars: &[c_char]) -> String {
    // SAFETY: Vulkan's fixed-size strings are NUL-terminated.
    unsafe { CStr::from_ptr(chars.as_ptr()) }.to_string_lossy().into_owned()
}

fn ray_query_support(instance: &ash::Instance, pd: vk::PhysicalDevice) -> bool {
    // SAFETY: valid handles; chains of stack structs.
    unsafe {
        let exts = instance.enumerate_device_extension_properties(pd).unwrap_or_default();
        let has = |n: &CStr| exts.iter().any(|e| e.extension_name_as_c_str().ok() == Some(n));
        if !(has(ash::khr::acceleration_structure::NAME)
            && has(ash::khr::ray_query::NAME)
            && has(ash::khr::deferred_host_operations::NAME))
        {
            return false;
        }
        let mut asf = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
        let mut rqf = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
        let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut asf).push_next(&mut rqf).push_next(&mut f12);
        instance.get_physical_device_features2(pd, &mut f2);
        let props = instance.get_physical_device_properties(pd);
        props.api_version >= vk::API_VERSION_1_2
            && asf.acceleration_structure == vk::TRUE
            && rqf.ray_query == vk::TRUE
            && f12.buffer_device_address == vk::TRUE
            && props.limits.timestamp_compute_and_graphics == vk::TRUE
    }
}

fn build_info<'a>(
    ty: vk::AccelerationStructureTypeKHR,
    geoms: &'a [vk::AccelerationStructureGeometryKHR<'a>],
    dst: vk::AccelerationStructureKHR,
    scratch: &Buf,
    align: u64,
) -> vk::AccelerationStructureBuildGeometryInfoKHR<'a> {
    vk::AccelerationStructureBuildGeometryInfoKHR::default()
        .ty(ty)
        .flags(vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE)
        .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
        .geometries(geoms)
        .dst_acceleration_structure(dst)
        .scratch_data(vk::DeviceOrHostAddressKHR { device_address: scratch.address.next_multiple_of(align) })
}

impl RqDevice {
    /// Opens the device named `wanted` (vkvcm's device, so that both sides run on the same
    /// one). `Ok(Err(reason))` when it lacks ray queries (or timestamps).
    pub fn new(wanted: &str, validation: bool) -> Result<std::result::Result<RqDevice, String>> {
        // SAFETY: loading the system Vulkan loader.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| anyhow!("cannot load the Vulkan loader: {e}"))?;
        let app = vk::ApplicationInfo::default().application_name(c"rayquery_bench").api_version(vk::API_VERSION_1_2);
        let mut layers = Vec::new();
        let mut exts = Vec::new();
        if validation {
            layers.push(c"VK_LAYER_KHRONOS_validation".as_ptr());
            exts.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        let info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&exts);
        // SAFETY: pointers in `info` outlive the call.
        let instance = unsafe { entry.create_instance(&info, None) }
            .context("vkCreateInstance failed (with --validation: is VK_LAYER_KHRONOS_validation installed?)")?;
        let messages: Box<Messages> = Box::default();
        let debug = if validation {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let dinfo = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(on_message))
                .user_data(&*messages as *const Messages as *mut c_void);
            // SAFETY: `messages` is boxed and outlives the messenger (destroyed in Drop).
            let m = unsafe { loader.create_debug_utils_messenger(&dinfo, None) }?;
            Some((loader, m))
        } else {
            None
        };
        let fail = |instance: &ash::Instance,
                    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>| {
            // SAFETY: nothing else was created from the instance.
            unsafe {
                if let Some((l, m)) = debug {
                    l.destroy_debug_utils_messenger(m, None);
                }
                instance.destroy_instance(None);
            }
        };
        // SAFETY: valid instance.
        let pds = unsafe { instance.enumerate_physical_devices() }.unwrap_or_default();
        let named = pds.iter().copied().find(|&pd| {
            // SAFETY: valid handle.
            cstr(&unsafe { instance.get_physical_device_properties(pd) }.device_name) == wanted
        });
        let Some(physical) = named else {
            fail(&instance, debug);
            return Ok(Err(format!("no Vulkan device named {wanted:?} for the ray-query side")));
        };
        if !ray_query_support(&instance, physical) {
            fail(&instance, debug);
            return Ok(Err(format!(
                "device {wanted:?} lacks VK_KHR_ray_query / VK_KHR_acceleration_structure / bufferDeviceAddress / timestamps"
            )));
        }
        Self::open(entry, instance, physical, debug, messages).map(Ok)
    }

    fn open(
        entry: ash::Entry,
        instance: ash::Instance,
        physical: vk::PhysicalDevice,
        debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
        messages: Box<Messages>,
    ) -> Result<RqDevice> {
        // SAFETY: valid handles throughout; create-info structs outlive their calls. On an
        // error past device creation the process exits (this is an example program), so
        // partially created objects are not unwound.
        unsafe {
            let mut drv = vk::PhysicalDeviceDriverProperties::default();
            let mut asp = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
            let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut drv).push_next(&mut asp);
            instance.get_physical_device_properties2(physical, &mut p2);
            let props = p2.properties;
            let families = instance.get_physical_device_queue_family_properties(physical);
            let family = families
                .iter()
                .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE) && f.timestamp_valid_bits > 0)
                .ok_or_else(|| anyhow!("no compute queue with timestamps"))? as u32;
            let prio = [1.0f32];
            let qinfo = [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&prio)];
            let dev_exts = [
                ash::khr::acceleration_structure::NAME.as_ptr(),
                ash::khr::ray_query::NAME.as_ptr(),
                ash::khr::deferred_host_operations::NAME.as_ptr(),
            ];
            let mut f12 = vk::PhysicalDeviceVulkan12Features::default().buffer_device_address(true);
            let mut asf = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default().acceleration_structure(true);
            let mut rqf = vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(true);
            let dinfo = vk::DeviceCreateInfo::default()
                .queue_create_infos(&qinfo)
                .enabled_extension_names(&dev_exts)
                .push_next(&mut f12)
                .push_next(&mut asf)
                .push_next(&mut rqf);
            let device = instance.create_device(physical, &dinfo, None).context("vkCreateDevice (ray query)")?;
            let accel = ash::khr::acceleration_structure::Device::new(&instance, &device);
            let queue = device.get_device_queue(family, 0);
            let mem = instance.get_physical_device_memory_properties(physical);
            let types = &mem.memory_types[..mem.memory_type_count as usize];
            let host = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
            let memory_type = types
                .iter()
                .position(|t| t.property_flags.contains(host | vk::MemoryPropertyFlags::DEVICE_LOCAL))
                .or_else(|| types.iter().position(|t| t.property_flags.contains(host)))
                .ok_or_else(|| anyhow!("no host-visible coherent memory type"))? as u32;

            let pool = device.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )?;
            let cmd = device.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1),
            )?[0];
            let fence = device.create_fence(&vk::FenceCreateInfo::default(), None)?;
            let queries = device.create_query_pool(
                &vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(4),
                None,
            )?;

            let bindings = [
                vk::DescriptorSetLayoutBinding::default()
                    .binding(0)
                    .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE),
                vk::DescriptorSetLayoutBinding::default()
                    .binding(1)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE),
                vk::DescriptorSetLayoutBinding::default()
                    .binding(2)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE),
            ];
            let set_layout = device.create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                None,
            )?;
            let push = [vk::PushConstantRange::default().stage_flags(vk::ShaderStageFlags::COMPUTE).offset(0).size(4)];
            let set_layouts = [set_layout];
            let layout = device.create_pipeline_layout(
                &vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts).push_constant_ranges(&push),
                None,
            )?;
            let ls = LOCAL_SIZE.to_string();
            // vkvcm's compiler: Vulkan 1.2, SPIR-V 1.5 (ray queries need 1.4+).
            let spirv = vkvcm::gpu::shader::compile_glsl("rayquery_bench.comp", SHADER, &[("LOCAL_SIZE", &ls)])?;
            let module = device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&spirv), None)?;
            let stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(module)
                .name(c"main");
            let pinfo = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout)];
            let pipeline = device
                .create_compute_pipelines(vk::PipelineCache::null(), &pinfo, None)
                .map_err(|(_, e)| anyhow!("creating the ray-query pipeline: {e}"))?[0];
            device.destroy_shader_module(module, None);
            let sizes = [
                vk::DescriptorPoolSize::default()
                    .ty(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
                    .descriptor_count(1),
                vk::DescriptorPoolSize::default().ty(vk::DescriptorType::STORAGE_BUFFER).descriptor_count(2),
            ];
            let descriptor_pool = device.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes),
                None,
            )?;
            let set = device.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default().descriptor_pool(descriptor_pool).set_layouts(&set_layouts),
            )?[0];
            let driver = format!("{} {}", cstr(&drv.driver_name), cstr(&drv.driver_info));
            Ok(RqDevice {
                _entry: entry,
                instance,
                debug,
                messages,
                device,
                accel,
                queue,
                pool,
                cmd,
                fence,
                queries,
                set_layout,
                layout,
                pipeline,
                descriptor_pool,
                set,
                memory_type,
                timestamp_period_ns: props.limits.timestamp_period as f64,
                scratch_align: (asp.min_acceleration_structure_scratch_offset_alignment as u64).max(1),
                name: cstr(&props.device_name),
                driver,
            })
        }
    }

    /// Validation messages so far (none without validation).
    pub fn messages(&self) -> Vec<String> {
        self.messages.lock().map(|v| v.clone()).unwrap_or_default()
    }

    fn buffer(&self, size: u64, usage: vk::BufferUsageFlags) -> Result<Buf> {
        let size = size.max(16);
        let with_address = usage.contains(vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS);
        // SAFETY: valid device; the buffer is bound to fresh memory of a suitable size.
        unsafe {
            let buffer = self.device.create_buffer(&vk::BufferCreateInfo::default().size(size).usage(usage), None)?;
            let req = self.device.get_buffer_memory_requirements(buffer);
            if req.memory_type_bits & (1 << self.memory_type) == 0 {
                bail!("buffer cannot live in the chosen memory type");
            }
            let mut flags = vk::MemoryAllocateFlagsInfo::default().flags(vk::MemoryAllocateFlags::DEVICE_ADDRESS);
            let mut ainfo =
                vk::MemoryAllocateInfo::default().allocation_size(req.size).memory_type_index(self.memory_type);
            if with_address {
                ainfo = ainfo.push_next(&mut flags);
            }
            let memory =
                self.device.allocate_memory(&ainfo, None).with_context(|| format!("allocating {size} bytes"))?;
            self.device.bind_buffer_memory(buffer, memory, 0)?;
            let ptr = self.device.map_memory(memory, 0, vk::WHOLE_SIZE, vk::MemoryMapFlags::empty())? as *mut u8;
            let address = if with_address {
                self.device.get_buffer_device_address(&vk::BufferDeviceAddressInfo::default().buffer(buffer))
            } else {
                0
            };
            Ok(Buf { buffer, memory, ptr, size, address })
        }
    }

    fn buffer_from(&self, bytes: &[u8], usage: vk::BufferUsageFlags) -> Result<Buf> {
        let b = self.buffer(bytes.len() as u64, usage)?;
        // SAFETY: the mapping is at least `bytes.len()` long and not in use by the device.
        unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), b.ptr, bytes.len()) };
        Ok(b)
    }

    fn free(&self, b: Buf) {
        // SAFETY: the device no longer uses the buffer (every submission is waited for).
        unsafe {
            self.device.destroy_buffer(b.buffer, None);
            self.device.free_memory(b.memory, None);
        }
    }

    /// Records with `f`, submits, waits; returns the wall time of submit + wait in ms and
    /// the `n` timestamps `f` wrote (ns).
    fn run(&self, n: u32, f: impl FnOnce(vk::CommandBuffer)) -> Result<(f64, Vec<f64>)> {
        // SAFETY: the command buffer is idle (every submission is waited for).
        unsafe {
            let d = &self.device;
            d.begin_command_buffer(
                self.cmd,
                &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )?;
            d.cmd_reset_query_pool(self.cmd, self.queries, 0, 4);
            f(self.cmd);
            d.end_command_buffer(self.cmd)?;
            let cmds = [self.cmd];
            let start = Instant::now();
            d.queue_submit(self.queue, &[vk::SubmitInfo::default().command_buffers(&cmds)], self.fence)?;
            d.wait_for_fences(&[self.fence], true, u64::MAX)?;
            let wall = start.elapsed().as_secs_f64() * 1e3;
            d.reset_fences(&[self.fence])?;
            let mut ts = vec![0u64; n as usize];
            if n > 0 {
                d.get_query_pool_results(
                    self.queries,
                    0,
                    &mut ts,
                    vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                )?;
            }
            Ok((wall, ts.iter().map(|&t| t as f64 * self.timestamp_period_ns).collect()))
        }
    }

    fn create_accel(
        &self,
        ty: vk::AccelerationStructureTypeKHR,
        size: u64,
    ) -> Result<(vk::AccelerationStructureKHR, Buf)> {
        let buf = self.buffer(
            size,
            vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
        )?;
        let info = vk::AccelerationStructureCreateInfoKHR::default().buffer(buf.buffer).size(size).ty(ty);
        // SAFETY: the buffer is large enough and has the storage usage.
        let a = unsafe { self.accel.create_acceleration_structure(&info, None) }?;
        Ok((a, buf))
    }

    /// Builds an opaque triangle BLAS (non-indexed vertices; primitive index = triangle
    /// index) with PREFER_FAST_TRACE and a TLAS with one identity instance of it.
    pub fn build(&self, triangles: &[Triangle]) -> Result<RqScene> {
        if triangles.is_empty() {
            bail!("the scene has no triangles");
        }
        let verts: Vec<[f32; 3]> = triangles.iter().flat_map(|t| t.p.map(|p| p.to_array())).collect();
        let input = vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR
            | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
        let vbuf = self.buffer_from(bytemuck::cast_slice(&verts), input)?;
        let tri_data = vk::AccelerationStructureGeometryTrianglesDataKHR::default()
            .vertex_format(vk::Format::R32G32B32_SFLOAT)
            .vertex_data(vk::DeviceOrHostAddressConstKHR { device_address: vbuf.address })
            .vertex_stride(12)
            .max_vertex(verts.len() as u32 - 1)
            .index_type(vk::IndexType::NONE_KHR);
        let blas_geom = [vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
            .geometry(vk::AccelerationStructureGeometryDataKHR { triangles: tri_data })
            .flags(vk::GeometryFlagsKHR::OPAQUE)];
        let n = triangles.len() as u32;
        let (blas, blas_buf, blas_scratch, blas_size) =
            self.prepare(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL, &blas_geom, n)?;
        // SAFETY: valid BLAS.
        let blas_address = unsafe {
            self.accel.get_acceleration_structure_device_address(
                &vk::AccelerationStructureDeviceAddressInfoKHR::default().acceleration_structure(blas),
            )
        };
        let instance = vk::AccelerationStructureInstanceKHR {
            transform: vk::TransformMatrixKHR { matrix: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0] },
            instance_custom_index_and_mask: vk::Packed24_8::new(0, 0xff),
            instance_shader_binding_table_record_offset_and_flags: vk::Packed24_8::new(
                0,
                vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE.as_raw() as u8,
            ),
            acceleration_structure_reference: vk::AccelerationStructureReferenceKHR { device_handle: blas_address },
        };
        // SAFETY: a plain-old-data Vulkan struct viewed as its bytes.
        let instance_bytes = unsafe {
            std::slice::from_raw_parts(
                &instance as *const vk::AccelerationStructureInstanceKHR as *const u8,
                std::mem::size_of::<vk::AccelerationStructureInstanceKHR>(),
            )
        };
        let ibuf = self.buffer_from(instance_bytes, input)?;
        let inst_data = vk::AccelerationStructureGeometryInstancesDataKHR::default()
            .array_of_pointers(false)
            .data(vk::DeviceOrHostAddressConstKHR { device_address: ibuf.address });
        let tlas_geom = [vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::INSTANCES)
            .geometry(vk::AccelerationStructureGeometryDataKHR { instances: inst_data })];
        let (tlas, tlas_buf, tlas_scratch, _) =
            self.prepare(vk::AccelerationStructureTypeKHR::TOP_LEVEL, &tlas_geom, 1)?;

        let align = self.scratch_align;
        let blas_info =
            [build_info(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL, &blas_geom, blas, &blas_scratch, align)];
        let tlas_info =
            [build_info(vk::AccelerationStructureTypeKHR::TOP_LEVEL, &tlas_geom, tlas, &tlas_scratch, align)];
        let blas_range = [vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(n)];
        let tlas_range = [vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(1)];
        let (wall, ts) = self.run(3, |cmd| {
            let d = &self.device;
            let built = [vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::ACCELERATION_STRUCTURE_WRITE_KHR)
                .dst_access_mask(vk::AccessFlags::ACCELERATION_STRUCTURE_READ_KHR)];
            let stage = vk::PipelineStageFlags::ACCELERATION_STRUCTURE_BUILD_KHR;
            // SAFETY: recording; every referenced object is alive until the wait in `run`.
            unsafe {
                d.cmd_write_timestamp(cmd, vk::PipelineStageFlags::TOP_OF_PIPE, self.queries, 0);
                self.accel.cmd_build_acceleration_structures(cmd, &blas_info, &[&blas_range]);
                d.cmd_pipeline_barrier(cmd, stage, stage, vk::DependencyFlags::empty(), &built, &[], &[]);
                d.cmd_write_timestamp(cmd, vk::PipelineStageFlags::BOTTOM_OF_PIPE, self.queries, 1);
                self.accel.cmd_build_acceleration_structures(cmd, &tlas_info, &[&tlas_range]);
                let to_shader = [vk::MemoryBarrier::default()
                    .src_access_mask(vk::AccessFlags::ACCELERATION_STRUCTURE_WRITE_KHR)
                    .dst_access_mask(vk::AccessFlags::ACCELERATION_STRUCTURE_READ_KHR)];
                d.cmd_pipeline_barrier(
                    cmd,
                    stage,
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::DependencyFlags::empty(),
                    &to_shader,
                    &[],
                    &[],
                );
                d.cmd_write_timestamp(cmd, vk::PipelineStageFlags::BOTTOM_OF_PIPE, self.queries, 2);
            }
        })?;
        // Build inputs and scratch are no longer needed.
        for b in [vbuf, ibuf, blas_scratch, tlas_scratch] {
            self.free(b);
        }
        Ok(RqScene {
            blas,
            tlas,
            buffers: vec![blas_buf, tlas_buf],
            blas_ms: (ts[1] - ts[0]) * 1e-6,
            tlas_ms: (ts[2] - ts[1]) * 1e-6,
            build_wall_ms: wall,
            blas_bytes: blas_size,
        })
    }

    /// Sizes, creates the structure and its scratch buffer.
    fn prepare(
        &self,
        ty: vk::AccelerationStructureTypeKHR,
        geoms: &[vk::AccelerationStructureGeometryKHR<'_>],
        count: u32,
    ) -> Result<(vk::AccelerationStructureKHR, Buf, Buf, u64)> {
        let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(ty)
            .flags(vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE)
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .geometries(geoms);
        let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
        // SAFETY: `info` describes `geoms`, one count per geometry.
        unsafe {
            self.accel.get_acceleration_structure_build_sizes(
                vk::AccelerationStructureBuildTypeKHR::DEVICE,
                &info,
                &[count],
                &mut sizes,
            )
        };
        let (a, buf) = self.create_accel(ty, sizes.acceleration_structure_size)?;
        let scratch = self.buffer(
            sizes.build_scratch_size + self.scratch_align,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
        )?;
        Ok((a, buf, scratch, sizes.acceleration_structure_size))
    }

    pub fn free_scene(&self, s: RqScene) {
        // SAFETY: no submission uses them any more.
        unsafe {
            self.accel.destroy_acceleration_structure(s.tlas, None);
            self.accel.destroy_acceleration_structure(s.blas, None);
        }
        for b in s.buffers {
            self.free(b);
        }
    }

    pub fn rays(&self, rays: &[BenchRay]) -> Result<RqRays> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        Ok(RqRays {
            rays: self.buffer_from(bytemuck::cast_slice(rays), storage)?,
            results: self.buffer(8 * rays.len() as u64, storage)?,
            count: rays.len() as u32,
        })
    }

    pub fn free_rays(&self, r: RqRays) {
        self.free(r.rays);
        self.free(r.results);
    }

    /// One closest-hit dispatch over `rays`; device time in ms (timestamps).
    pub fn trace(&self, scene: &RqScene, rays: &RqRays) -> Result<f64> {
        let tlas = [scene.tlas];
        let mut as_write = vk::WriteDescriptorSetAccelerationStructureKHR::default().acceleration_structures(&tlas);
        let ray_info = [vk::DescriptorBufferInfo::default().buffer(rays.rays.buffer).range(vk::WHOLE_SIZE)];
        let res_info = [vk::DescriptorBufferInfo::default().buffer(rays.results.buffer).range(vk::WHOLE_SIZE)];
        let writes = [
            vk::WriteDescriptorSet::default()
                .dst_set(self.set)
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
                .descriptor_count(1)
                .push_next(&mut as_write),
            vk::WriteDescriptorSet::default()
                .dst_set(self.set)
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&ray_info),
            vk::WriteDescriptorSet::default()
                .dst_set(self.set)
                .dst_binding(2)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&res_info),
        ];
        // SAFETY: the set is not in use (every submission is waited for).
        unsafe { self.device.update_descriptor_sets(&writes, &[]) };
        let (_, ts) = self.run(2, |cmd| {
            let d = &self.device;
            let to_host = [vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::SHADER_WRITE)
                .dst_access_mask(vk::AccessFlags::HOST_READ)];
            // SAFETY: recording; the set's resources live until the wait in `run`.
            unsafe {
                d.cmd_write_timestamp(cmd, vk::PipelineStageFlags::TOP_OF_PIPE, self.queries, 0);
                d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline);
                d.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, self.layout, 0, &[self.set], &[]);
                d.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, &rays.count.to_ne_bytes());
                d.cmd_dispatch(cmd, rays.count.div_ceil(LOCAL_SIZE), 1, 1);
                d.cmd_write_timestamp(cmd, vk::PipelineStageFlags::BOTTOM_OF_PIPE, self.queries, 1);
                d.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::PipelineStageFlags::HOST,
                    vk::DependencyFlags::empty(),
                    &to_host,
                    &[],
                    &[],
                );
            }
        })?;
        Ok((ts[1] - ts[0]) * 1e-6)
    }

    /// The last dispatch's results: (t, primitive index) per ray, `u32::MAX` for a miss.
    pub fn results(&self, rays: &RqRays) -> Vec<(f32, u32)> {
        let n = rays.count as usize;
        debug_assert!(rays.results.size >= 8 * n as u64);
        // SAFETY: the mapping holds `n` uvec2, written by a completed submission.
        let words = unsafe { std::slice::from_raw_parts(rays.results.ptr as *const [u32; 2], n) };
        words.iter().map(|w| (f32::from_bits(w[0]), w[1])).collect()
    }
}

impl Drop for RqDevice {
    fn drop(&mut self) {
        // SAFETY: objects created in `open`, destroyed once, device idle.
        unsafe {
            let d = &self.device;
            let _ = d.device_wait_idle();
            d.destroy_descriptor_pool(self.descriptor_pool, None);
            d.destroy_pipeline(self.pipeline, None);
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
            d.destroy_query_pool(self.queries, None);
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.pool, None);
            d.destroy_device(None);
            if let Some((l, m)) = self.debug.take() {
                l.destroy_debug_utils_messenger(m, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}
