//! Compute kernels: pipeline, layout and one descriptor set of buffers (storage buffers,
//! or uniform texel buffers for data a kernel only reads), created once and reused for
//! every dispatch.

use std::sync::Arc;

use anyhow::{bail, Context, Result};
use ash::vk;

use super::{Buffer, Gpu};

/// Push-constant bytes every kernel may use (the Vulkan guaranteed minimum).
pub const PUSH_CONSTANT_BYTES: u32 = 128;

/// How a kernel sees the buffer at one binding.
#[derive(Clone, Copy)]
pub enum Binding<'a> {
    /// A storage buffer (GLSL `buffer`).
    Storage(&'a Buffer),
    /// A read-only uniform texel buffer of `R32G32B32A32_UINT` texels (GLSL
    /// `utextureBuffer`, 16 bytes per texel; the buffer's size must be a multiple of 16).
    /// On lavapipe a divergent texel fetch is one 16-byte load per lane where a storage
    /// buffer load is a bounds-checked branch per lane and component
    /// (docs/performance.md, "Fourth round (texel-buffer reads)").
    Texel(&'a Buffer),
    /// The same with `R32_UINT` texels (`utextureBuffer`, one `uint` per texel).
    TexelU32(&'a Buffer),
}

impl<'a> Binding<'a> {
    fn buffer(&self) -> &'a Buffer {
        match *self {
            Binding::Storage(b) | Binding::Texel(b) | Binding::TexelU32(b) => b,
        }
    }

    fn descriptor_type(&self) -> vk::DescriptorType {
        match self {
            Binding::Storage(_) => vk::DescriptorType::STORAGE_BUFFER,
            Binding::Texel(_) | Binding::TexelU32(_) => vk::DescriptorType::UNIFORM_TEXEL_BUFFER,
        }
    }

    /// The texel format and size in bytes, for texel buffers.
    fn texel(&self) -> Option<(vk::Format, u64)> {
        match self {
            Binding::Storage(_) => None,
            Binding::Texel(_) => Some((vk::Format::R32G32B32A32_UINT, 16)),
            Binding::TexelU32(_) => Some((vk::Format::R32_UINT, 4)),
        }
    }
}

/// A compute pipeline with buffers at bindings 0..n.
pub struct Kernel {
    gpu: Arc<Gpu>,
    name: String,
    pub(crate) pipeline: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    pub(crate) set: vk::DescriptorSet,
    /// The views of the texel-buffer bindings (null for storage buffers), destroyed with
    /// the kernel.
    views: Vec<vk::BufferView>,
}

impl Gpu {
    /// Builds the kernel `name` (a .comp file under glsl/) with `defines`, binding
    /// `buffers` as storage buffers to bindings 0, 1, ... in order.
    pub fn kernel(self: &Arc<Self>, name: &str, defines: &[(&str, &str)], buffers: &[&Buffer]) -> Result<Kernel> {
        let bindings: Vec<Binding> = buffers.iter().map(|b| Binding::Storage(b)).collect();
        self.kernel_with(name, defines, &bindings)
    }

    /// Builds the kernel `name` with `defines`, binding `bindings` to bindings 0, 1, ...
    /// in order, each as the kind of descriptor it names.
    pub fn kernel_with(self: &Arc<Self>, name: &str, defines: &[(&str, &str)], bindings: &[Binding]) -> Result<Kernel> {
        check_bindings(&self.limits, bindings).with_context(|| format!("kernel {name}"))?;
        let module = self.shaders.module(&self.device, name, defines)?;
        let dev = &self.device;
        let binding_info: Vec<_> = bindings
            .iter()
            .enumerate()
            .map(|(i, b)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i as u32)
                    .descriptor_type(b.descriptor_type())
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
                name: name.to_string(),
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
                .create_compute_pipelines(vk::PipelineCache::null(), &info, None)
                .map_err(|(_, e)| e)
                .with_context(|| format!("cannot create the pipeline of kernel {name}"))?[0];
            if !bindings.is_empty() {
                let sizes: Vec<_> = [vk::DescriptorType::STORAGE_BUFFER, vk::DescriptorType::UNIFORM_TEXEL_BUFFER]
                    .into_iter()
                    .map(|ty| (ty, bindings.iter().filter(|b| b.descriptor_type() == ty).count() as u32))
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
                k.bind(bindings)?;
            }
            Ok(k)
        }
    }
}

impl Kernel {
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The same kernel under another name in profiles and messages (one shader used by
    /// two stages, see `profile::stage_of`).
    pub fn labelled(mut self, name: &str) -> Kernel {
        self.name = name.to_string();
        self
    }

    /// Points the descriptor set at `bindings` (once, at creation: the set layout fixes
    /// each binding's kind), checked by [`check_bindings`].
    fn bind(&mut self, bindings: &[Binding]) -> Result<()> {
        for b in bindings {
            if let Some((format, _)) = b.texel() {
                let info =
                    vk::BufferViewCreateInfo::default().buffer(b.buffer().raw).format(format).range(vk::WHOLE_SIZE);
                // SAFETY: valid buffer created with UNIFORM_TEXEL_BUFFER usage; the view is
                // destroyed with the kernel.
                let view = unsafe { self.gpu.device.create_buffer_view(&info, None) }
                    .with_context(|| format!("cannot create a texel view of buffer {:?}", b.buffer().name()))?;
                self.views.push(view);
            } else {
                self.views.push(vk::BufferView::null());
            }
        }
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = bindings
            .iter()
            .map(|b| [vk::DescriptorBufferInfo::default().buffer(b.buffer().raw).range(vk::WHOLE_SIZE)])
            .collect();
        let writes: Vec<_> = bindings
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let w = vk::WriteDescriptorSet::default()
                    .dst_set(self.set)
                    .dst_binding(i as u32)
                    .descriptor_type(b.descriptor_type());
                match b {
                    Binding::Storage(_) => w.buffer_info(&infos[i]),
                    _ => w.texel_buffer_view(std::slice::from_ref(&self.views[i])),
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
fn check_bindings(limits: &vk::PhysicalDeviceLimits, bindings: &[Binding]) -> Result<()> {
    for b in bindings {
        let buf = b.buffer();
        let (max, what) = match b.texel() {
            None => (limits.max_storage_buffer_range as u64, "bytes (maxStorageBufferRange)"),
            Some((_, texel)) => {
                if buf.size() % texel != 0 {
                    bail!(
                        "buffer {:?} ({} bytes) is read as {texel}-byte texels but is not a whole number of them",
                        buf.name(),
                        buf.size()
                    );
                }
                (limits.max_texel_buffer_elements as u64 * texel, "bytes as texels (maxTexelBufferElements)")
            }
        };
        if buf.size() > max {
            bail!(
                "buffer {:?} needs {} bytes but this device binds at most {max} {what}; use a smaller image or scene",
                buf.name(),
                buf.size(),
            );
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
