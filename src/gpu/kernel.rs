//! Compute kernels: pipeline, layout and one descriptor set, created once and reused for
//! every dispatch. A kernel's bindings and workgroup size are read from its SPIR-V
//! (src/gpu/reflect.rs) and its buffers are bound by those names: the GLSL declares a
//! buffer once, without a binding number (shaderc assigns them), and the Rust side names
//! the buffer it binds there.

use std::sync::Arc;

use anyhow::{bail, Context, Result};
use ash::vk;

use super::reflect::{KernelInterface, ReflectedBinding};
use super::{Buffer, Gpu};

/// Push-constant bytes every kernel may use (the Vulkan guaranteed minimum).
pub const PUSH_CONSTANT_BYTES: u32 = 128;

/// How a buffer's bytes are seen when the kernel declares its binding as a uniform texel
/// buffer (`utextureBuffer`); storage-buffer bindings ignore it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Texels {
    /// `R32G32B32A32_UINT`: one `uvec4` per 16 bytes (the buffer's size must be a multiple
    /// of 16).
    Vec4,
    /// `R32_UINT`: one `uint` per 4 bytes.
    U32,
}

impl Texels {
    fn format_and_size(self) -> (vk::Format, u64) {
        match self {
            Texels::Vec4 => (vk::Format::R32G32B32A32_UINT, 16),
            Texels::U32 => (vk::Format::R32_UINT, 4),
        }
    }
}

/// A buffer for the kernel binding named `name`.
#[derive(Clone, Copy)]
pub struct Bind<'a> {
    pub name: &'a str,
    pub buffer: &'a Buffer,
    /// How a texel-buffer binding of that name reads it.
    pub texels: Texels,
}

impl<'a> Bind<'a> {
    /// `buffer` at the binding `name`; as a texel buffer it is read as `uvec4` texels.
    pub fn vec4(name: &'a str, buffer: &'a Buffer) -> Bind<'a> {
        Bind { name, buffer, texels: Texels::Vec4 }
    }

    /// `buffer` at the binding `name`; as a texel buffer it is read as `uint` texels.
    pub fn u32(name: &'a str, buffer: &'a Buffer) -> Bind<'a> {
        Bind { name, buffer, texels: Texels::U32 }
    }

    /// `buffer` at the binding of the buffer's own name, read as `uvec4` texels.
    pub fn own(buffer: &'a Buffer) -> Bind<'a> {
        Bind::vec4(buffer.name(), buffer)
    }

    /// `buffer` at the binding of the buffer's own name, read as `uint` texels.
    pub fn own_u32(buffer: &'a Buffer) -> Bind<'a> {
        Bind::u32(buffer.name(), buffer)
    }
}

/// A kernel's `#define`s.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Defines(Vec<(String, String)>);

impl Defines {
    pub fn new() -> Defines {
        Defines::default()
    }

    /// `name` as 1 or 0.
    pub fn flag(mut self, name: &str, on: bool) -> Defines {
        self.0.push((name.to_string(), if on { "1" } else { "0" }.to_string()));
        self
    }

    /// `name` as `value`.
    pub fn value(mut self, name: &str, value: impl ToString) -> Defines {
        self.0.push((name.to_string(), value.to_string()));
        self
    }

    /// These defines followed by `other`'s.
    pub fn with(mut self, other: &Defines) -> Defines {
        self.0.extend(other.0.iter().cloned());
        self
    }

    /// As [`Gpu::kernel`] takes them.
    pub fn pairs(&self) -> Vec<(&str, &str)> {
        self.0.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect()
    }

    /// `(name, value)` in the order they were added.
    pub fn list(&self) -> &[(String, String)] {
        &self.0
    }
}

/// A compute pipeline with its buffers bound.
pub struct Kernel {
    gpu: Arc<Gpu>,
    name: String,
    local_size: [u32; 3],
    pub(crate) pipeline: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    pub(crate) set: vk::DescriptorSet,
    /// The views of the texel-buffer bindings, destroyed with the kernel.
    views: Vec<vk::BufferView>,
}

impl Gpu {
    /// Builds the kernel `source` (a .comp file under glsl/) with `defines`. Every binding
    /// the compiled kernel declares takes the buffer of the same name in `bindings`, as
    /// the kind of descriptor the kernel declares (storage or texel buffer); `bindings`
    /// may hold buffers the kernel does not declare (a variant that compiles a binding
    /// out), and a declared binding without a buffer is an error. A kernel that needs a
    /// feature the device lacks (64-bit integers or atomics) is refused before any
    /// Vulkan object is created for it.
    pub fn kernel(self: &Arc<Self>, source: &str, defines: &[(&str, &str)], bindings: &[Bind]) -> Result<Kernel> {
        let (module, interface) = self.shaders.module(&self.device, source, defines, &|f| self.has(f))?;
        let chosen = choose(source, &interface, bindings)?;
        check_bindings(&self.limits, &chosen).with_context(|| format!("kernel {source}"))?;
        let dev = &self.device;
        let binding_info: Vec<_> = chosen
            .iter()
            .map(|(r, _)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(r.binding)
                    .descriptor_type(r.descriptor_type)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        // SAFETY: plain object creation; every object is owned by the returned Kernel,
        // which is built before any fallible step that could leak (errors below are
        // returned after wrapping the partial Kernel, whose Drop destroys nulls safely).
        unsafe {
            let set_layout = dev.create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default().bindings(&binding_info),
                None,
            )?;
            let mut k = Kernel {
                gpu: self.clone(),
                name: source.to_string(),
                local_size: interface.local_size,
                pipeline: vk::Pipeline::null(),
                layout: vk::PipelineLayout::null(),
                set_layout,
                pool: vk::DescriptorPool::null(),
                set: vk::DescriptorSet::null(),
                views: Vec::new(),
            };
            let set_layouts = [set_layout];
            let push =
                [vk::PushConstantRange::default().stage_flags(vk::ShaderStageFlags::COMPUTE).size(PUSH_CONSTANT_BYTES)];
            k.layout = dev.create_pipeline_layout(
                &vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts).push_constant_ranges(&push),
                None,
            )?;
            let stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(module)
                .name(c"main");
            let info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(k.layout)];
            k.pipeline = dev
                .create_compute_pipelines(self.pipelines.handle(), &info, None)
                .map_err(|(_, e)| e)
                .with_context(|| format!("cannot create the pipeline of kernel {source}"))?[0];
            self.pipelines.note_created();
            self.debug.name(k.pipeline, source);
            if !chosen.is_empty() {
                let sizes: Vec<_> = [vk::DescriptorType::STORAGE_BUFFER, vk::DescriptorType::UNIFORM_TEXEL_BUFFER]
                    .into_iter()
                    .map(|ty| (ty, chosen.iter().filter(|(r, _)| r.descriptor_type == ty).count() as u32))
                    .filter(|&(_, n)| n > 0)
                    .map(|(ty, n)| vk::DescriptorPoolSize::default().ty(ty).descriptor_count(n))
                    .collect();
                k.pool = dev.create_descriptor_pool(
                    &vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes),
                    None,
                )?;
                k.set = dev.allocate_descriptor_sets(
                    &vk::DescriptorSetAllocateInfo::default().descriptor_pool(k.pool).set_layouts(&set_layouts),
                )?[0];
                k.bind(&chosen)?;
            }
            Ok(k)
        }
    }
}

/// The buffer of each binding `interface` declares, by name.
fn choose<'a>(
    source: &str,
    interface: &'a KernelInterface,
    bindings: &[Bind<'a>],
) -> Result<Vec<(&'a ReflectedBinding, Bind<'a>)>> {
    for (i, b) in bindings.iter().enumerate() {
        if bindings[..i].iter().any(|o| o.name == b.name) {
            bail!("kernel {source}: two buffers given for binding {:?}", b.name);
        }
    }
    interface
        .bindings
        .iter()
        .map(|r| match bindings.iter().find(|b| b.name == r.name) {
            Some(b) => Ok((r, *b)),
            None => {
                let given: Vec<&str> = bindings.iter().map(|b| b.name).collect();
                bail!(
                    "kernel {source} declares binding {:?} but no buffer of that name was given (given: {given:?})",
                    r.name
                )
            }
        })
        .collect()
}

impl Kernel {
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The workgroup size the kernel declares (`local_size_x, y, z`).
    pub fn local_size(&self) -> [u32; 3] {
        self.local_size
    }

    /// Workgroups covering `n` invocations of a 1-D problem with this kernel's
    /// `local_size_x`, folded into 2-D past the per-dimension limit
    /// ([`super::groups_2d`]).
    pub fn groups_for(&self, n: u32) -> [u32; 3] {
        super::groups_2d(n, self.local_size[0])
    }

    /// Points the descriptor set at the chosen buffers (once, at creation: the set layout
    /// fixes each binding's kind), checked by [`check_bindings`].
    fn bind(&mut self, chosen: &[(&ReflectedBinding, Bind)]) -> Result<()> {
        for (r, b) in chosen {
            if r.descriptor_type == vk::DescriptorType::UNIFORM_TEXEL_BUFFER {
                let (format, _) = b.texels.format_and_size();
                let info =
                    vk::BufferViewCreateInfo::default().buffer(b.buffer.raw).format(format).range(vk::WHOLE_SIZE);
                // SAFETY: valid buffer created with UNIFORM_TEXEL_BUFFER usage; the view is
                // destroyed with the kernel.
                let view = unsafe { self.gpu.device.create_buffer_view(&info, None) }
                    .with_context(|| format!("cannot create a texel view of buffer {:?}", b.buffer.name()))?;
                self.views.push(view);
            } else {
                self.views.push(vk::BufferView::null());
            }
        }
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = chosen
            .iter()
            .map(|(_, b)| [vk::DescriptorBufferInfo::default().buffer(b.buffer.raw).range(vk::WHOLE_SIZE)])
            .collect();
        let writes: Vec<_> = chosen
            .iter()
            .enumerate()
            .map(|(i, (r, _))| {
                let w = vk::WriteDescriptorSet::default()
                    .dst_set(self.set)
                    .dst_binding(r.binding)
                    .descriptor_type(r.descriptor_type);
                if r.descriptor_type == vk::DescriptorType::STORAGE_BUFFER {
                    w.buffer_info(&infos[i])
                } else {
                    w.texel_buffer_view(std::slice::from_ref(&self.views[i]))
                }
            })
            .collect();
        // SAFETY: the set was just allocated and is not in use.
        unsafe { self.gpu.device.update_descriptor_sets(&writes, &[]) };
        Ok(())
    }
}

/// Refuses a binding the device cannot bind: a storage buffer over
/// maxStorageBufferRange, a texel buffer over maxTexelBufferElements or not a whole
/// number of texels.
fn check_bindings(limits: &vk::PhysicalDeviceLimits, chosen: &[(&ReflectedBinding, Bind)]) -> Result<()> {
    let count = |ty: vk::DescriptorType| chosen.iter().filter(|(r, _)| r.descriptor_type == ty).count() as u32;
    let storage = count(vk::DescriptorType::STORAGE_BUFFER);
    if storage > limits.max_per_stage_descriptor_storage_buffers {
        bail!(
            "it binds {storage} storage buffers but this device allows {} per shader stage \
             (maxPerStageDescriptorStorageBuffers); --reads texel binds fewer",
            limits.max_per_stage_descriptor_storage_buffers
        );
    }
    let texel = count(vk::DescriptorType::UNIFORM_TEXEL_BUFFER);
    if texel > limits.max_per_stage_descriptor_sampled_images {
        bail!(
            "it binds {texel} texel buffers but this device allows {} per shader stage \
             (maxPerStageDescriptorSampledImages); use --reads storage",
            limits.max_per_stage_descriptor_sampled_images
        );
    }
    for (r, b) in chosen {
        let buf = b.buffer;
        if buf.is_fixed_table() {
            continue;
        }
        let (max, what) = if r.descriptor_type == vk::DescriptorType::STORAGE_BUFFER {
            (limits.max_storage_buffer_range as u64, "bytes (maxStorageBufferRange); use a smaller image or scene")
        } else {
            let (_, texel) = b.texels.format_and_size();
            if buf.size() % texel != 0 {
                bail!(
                    "buffer {:?} ({} bytes) is read as {texel}-byte texels but is not a whole number of them",
                    buf.name(),
                    buf.size()
                );
            }
            (
                limits.max_texel_buffer_elements as u64 * texel,
                "bytes as texels (maxTexelBufferElements); --reads storage reads it from a storage buffer",
            )
        };
        if buf.size() > max {
            bail!("buffer {:?} needs {} bytes but this device binds at most {max} {what}", buf.name(), buf.size(),);
        }
    }
    Ok(())
}

impl Drop for Kernel {
    fn drop(&mut self) {
        let dev = &self.gpu.device;
        // SAFETY: batches wait for completion, so nothing uses these objects; destroying
        // null handles is a no-op.
        unsafe {
            for &v in &self.views {
                dev.destroy_buffer_view(v, None);
            }
            dev.destroy_descriptor_pool(self.pool, None);
            dev.destroy_pipeline(self.pipeline, None);
            dev.destroy_pipeline_layout(self.layout, None);
            dev.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
