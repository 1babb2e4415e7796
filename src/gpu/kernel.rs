//! Compute kernels: pipeline, layout and one descriptor set of storage buffers, created
//! once and reused for every dispatch.

use std::sync::Arc;

use anyhow::{bail, Context, Result};
use ash::vk;

use super::{Buffer, Gpu};

/// Push-constant bytes every kernel may use (the Vulkan guaranteed minimum).
pub const PUSH_CONSTANT_BYTES: u32 = 128;

/// A compute pipeline whose bindings 0..n are storage buffers.
pub struct Kernel {
    gpu: Arc<Gpu>,
    name: String,
    pub(crate) pipeline: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    pub(crate) set: vk::DescriptorSet,
    bindings: usize,
}

impl Gpu {
    /// Builds the kernel `name` (a .comp file under glsl/) with `defines`, binding
    /// `buffers` to bindings 0, 1, ... in order.
    pub fn kernel(self: &Arc<Self>, name: &str, defines: &[(&str, &str)], buffers: &[&Buffer]) -> Result<Kernel> {
        let module = self.shaders.module(&self.device, name, defines)?;
        let dev = &self.device;
        let binding_info: Vec<_> = (0..buffers.len() as u32)
            .map(|i| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
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
                bindings: buffers.len(),
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
            if !buffers.is_empty() {
                let sizes = [vk::DescriptorPoolSize::default()
                    .ty(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(buffers.len() as u32)];
                k.pool = dev.create_descriptor_pool(
                    &vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes),
                    None,
                )?;
                k.set = dev.allocate_descriptor_sets(
                    &vk::DescriptorSetAllocateInfo::default().descriptor_pool(k.pool).set_layouts(&set_layouts),
                )?[0];
                k.bind(buffers)?;
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

    /// Re-points the bindings at other buffers (same count). Not while a batch that
    /// uses this kernel is in flight.
    pub fn bind(&self, buffers: &[&Buffer]) -> Result<()> {
        if buffers.len() != self.bindings {
            bail!("kernel {} has {} bindings, got {} buffers", self.name, self.bindings, buffers.len());
        }
        let max = self.gpu.limits.max_storage_buffer_range as u64;
        for b in buffers {
            if b.size() > max {
                bail!(
                    "buffer {:?} needs {} bytes but this device binds at most {} bytes (maxStorageBufferRange); use a smaller image or scene",
                    b.name(),
                    b.size(),
                    max
                );
            }
        }
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> =
            buffers.iter().map(|b| [vk::DescriptorBufferInfo::default().buffer(b.raw).range(vk::WHOLE_SIZE)]).collect();
        let writes: Vec<_> = infos
            .iter()
            .enumerate()
            .map(|(i, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(self.set)
                    .dst_binding(i as u32)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(info)
            })
            .collect();
        // SAFETY: the set is not in use by a pending batch (documented precondition).
        unsafe { self.gpu.device.update_descriptor_sets(&writes, &[]) };
        Ok(())
    }
}

impl Drop for Kernel {
    fn drop(&mut self) {
        let dev = &self.gpu.device;
        // SAFETY: batches wait for completion, so nothing uses these objects; destroying
        // null handles is a no-op.
        unsafe {
            dev.destroy_descriptor_pool(self.pool, None);
            dev.destroy_pipeline(self.pipeline, None);
            dev.destroy_pipeline_layout(self.layout, None);
            dev.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
