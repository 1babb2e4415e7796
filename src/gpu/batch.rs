//! Command batches: record dispatches (each wrapped in timestamp queries when the device
//! supports them), submit, wait, and fold the timings into a `Profile`.

use std::sync::Arc;

use anyhow::{anyhow, bail, Context, Result};
use ash::vk;

use super::{fault_injection, Buffer, DispatchEvent, Gpu, Kernel, Profile, PUSH_CONSTANT_BYTES};

/// The pass of dispatches recorded before any [`Batch::begin_pass`].
pub const UNNAMED_PASS: &str = "other";

/// Most timed dispatches per batch.
const MAX_TIMED: u32 = 256;

/// A Vulkan error as a short phrase with its code, for messages that say what was being
/// done: "device lost (VK_ERROR_DEVICE_LOST)".
pub(crate) fn vk_error_text(e: vk::Result) -> String {
    let what = match e {
        vk::Result::ERROR_DEVICE_LOST => "device lost",
        vk::Result::ERROR_OUT_OF_DEVICE_MEMORY => "out of device memory",
        vk::Result::ERROR_OUT_OF_HOST_MEMORY => "out of host memory",
        _ => return format!("{e:?} ({e})"),
    };
    format!("{what} (VK_{e:?})")
}

/// A reusable command buffer. Every dispatch is preceded by a compute->compute memory
/// barrier, so consecutive kernels see each other's writes.
pub struct Batch {
    gpu: Arc<Gpu>,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    queries: vk::QueryPool,
    /// The (pass, kernel) of each timed dispatch, in recording order.
    timed: Vec<(String, String)>,
    /// The workgroups and iteration of each timed dispatch (for traces).
    timed_groups: Vec<([u32; 3], Option<u64>)>,
    /// The iteration the next dispatches belong to ([`Batch::set_iteration`]).
    iteration: Option<u64>,
    /// The pass that the next dispatches belong to ([`Batch::begin_pass`]).
    pass: String,
    /// Kernels recorded since the last submit, each once, for error messages.
    kernels: Vec<String>,
    recording: bool,
}

impl Gpu {
    pub fn batch(self: &Arc<Self>) -> Result<Batch> {
        let dev = &self.device;
        // SAFETY: objects owned by the Batch, destroyed in Drop (null handles are no-ops).
        unsafe {
            let mut b = Batch {
                gpu: self.clone(),
                pool: vk::CommandPool::null(),
                cmd: vk::CommandBuffer::null(),
                fence: vk::Fence::null(),
                queries: vk::QueryPool::null(),
                timed: Vec::new(),
                timed_groups: Vec::new(),
                iteration: None,
                pass: UNNAMED_PASS.to_string(),
                kernels: Vec::new(),
                recording: false,
            };
            b.pool = dev.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(self.queue_family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )?;
            b.cmd = dev.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default().command_pool(b.pool).command_buffer_count(1),
            )?[0];
            b.fence = dev.create_fence(&vk::FenceCreateInfo::default(), None)?;
            if self.timestamps {
                b.queries = dev.create_query_pool(
                    &vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(2 * MAX_TIMED),
                    None,
                )?;
            }
            Ok(b)
        }
    }
}

impl Batch {
    fn begin(&mut self) -> Result<()> {
        if self.recording {
            return Ok(());
        }
        let dev = &self.gpu.device;
        // SAFETY: the command buffer is not pending (submit_wait waits).
        unsafe {
            dev.reset_command_buffer(self.cmd, vk::CommandBufferResetFlags::empty())?;
            dev.begin_command_buffer(
                self.cmd,
                &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )?;
            if self.queries != vk::QueryPool::null() {
                dev.cmd_reset_query_pool(self.cmd, self.queries, 0, 2 * MAX_TIMED);
            }
        }
        self.timed.clear();
        self.timed_groups.clear();
        self.kernels.clear();
        self.recording = true;
        Ok(())
    }

    fn barrier(&self) {
        let mb = [vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(
                vk::AccessFlags::SHADER_READ
                    | vk::AccessFlags::SHADER_WRITE
                    | vk::AccessFlags::TRANSFER_READ
                    | vk::AccessFlags::TRANSFER_WRITE,
            )];
        // SAFETY: recording state.
        unsafe {
            self.gpu.device.cmd_pipeline_barrier(
                self.cmd,
                vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
                vk::DependencyFlags::empty(),
                &mb,
                &[],
                &[],
            )
        };
    }

    /// Names the pass that the following dispatches belong to: profiles report their
    /// time under this name (until the next call).
    pub fn begin_pass(&mut self, name: &str) {
        name.clone_into(&mut self.pass);
    }

    /// Names the iteration that the following dispatches belong to (traces show it).
    pub fn set_iteration(&mut self, iteration: u64) {
        self.iteration = Some(iteration);
    }

    /// Records `kernel` over `groups` workgroups with `push` as push constants.
    pub fn dispatch(&mut self, kernel: &Kernel, groups: [u32; 3], push: &[u8]) -> Result<()> {
        if push.len() as u32 > PUSH_CONSTANT_BYTES {
            bail!("kernel {}: {} push-constant bytes, at most {PUSH_CONSTANT_BYTES}", kernel.name(), push.len());
        }
        if groups.contains(&0) {
            return Ok(());
        }
        self.begin()?;
        self.barrier();
        let dev = &self.gpu.device;
        let timed = self.queries != vk::QueryPool::null() && (self.timed.len() as u32) < MAX_TIMED;
        let q = 2 * self.timed.len() as u32;
        // SAFETY: recording; the kernel's objects outlive the submission (caller keeps it).
        unsafe {
            if timed {
                dev.cmd_write_timestamp(self.cmd, vk::PipelineStageFlags::TOP_OF_PIPE, self.queries, q);
            }
            dev.cmd_bind_pipeline(self.cmd, vk::PipelineBindPoint::COMPUTE, kernel.pipeline);
            if kernel.set != vk::DescriptorSet::null() {
                dev.cmd_bind_descriptor_sets(
                    self.cmd,
                    vk::PipelineBindPoint::COMPUTE,
                    kernel.layout,
                    0,
                    &[kernel.set],
                    &[],
                );
            }
            if !push.is_empty() {
                let mut padded = [0u8; PUSH_CONSTANT_BYTES as usize];
                padded[..push.len()].copy_from_slice(push);
                dev.cmd_push_constants(self.cmd, kernel.layout, vk::ShaderStageFlags::COMPUTE, 0, &padded);
            }
            self.gpu.debug.begin_label(self.cmd, &self.pass, kernel.name());
            dev.cmd_dispatch(self.cmd, groups[0], groups[1], groups[2]);
            self.gpu.debug.end_label(self.cmd);
            if timed {
                dev.cmd_write_timestamp(self.cmd, vk::PipelineStageFlags::BOTTOM_OF_PIPE, self.queries, q + 1);
            }
        }
        if timed {
            self.timed.push((self.pass.clone(), kernel.name().to_string()));
            self.timed_groups.push((groups, self.iteration));
        }
        if !self.kernels.iter().any(|k| k == kernel.name()) {
            self.kernels.push(kernel.name().to_string());
        }
        Ok(())
    }

    /// Records a fill of the whole buffer with the 32-bit `value`.
    pub fn fill(&mut self, buffer: &Buffer, value: u32) -> Result<()> {
        self.begin()?;
        self.barrier();
        // SAFETY: recording; the buffer has TRANSFER_DST usage.
        unsafe { self.gpu.device.cmd_fill_buffer(self.cmd, buffer.raw, 0, vk::WHOLE_SIZE, value) };
        Ok(())
    }

    /// Submits what was recorded, waits for it, and adds the kernel timings to `profile`.
    pub fn submit_wait(&mut self, profile: Option<&mut Profile>) -> Result<()> {
        if !self.recording {
            return Ok(());
        }
        self.recording = false;
        let dev = &self.gpu.device;
        let kernels = if self.kernels.is_empty() { "transfers".to_string() } else { self.kernels.join(", ") };
        let fail = |step: &str, e: vk::Result| anyhow!("{step} of a batch ({kernels}): {}", vk_error_text(e));
        let submitted_us;
        // SAFETY: recorded command buffer; fence unsignalled (reset after each wait).
        unsafe {
            dev.end_command_buffer(self.cmd).map_err(|e| fail("recording", e))?;
            let cmds = [self.cmd];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            fault_injection::simulated_device_loss(true).map_err(|e| fail("vkQueueSubmit", e))?;
            submitted_us = super::profile::trace_clock_us();
            dev.queue_submit(self.gpu.queue, &submit, self.fence).map_err(|e| fail("vkQueueSubmit", e))?;
            dev.wait_for_fences(&[self.fence], true, u64::MAX).map_err(|e| fail("waiting for the GPU", e))?;
            dev.reset_fences(&[self.fence]).map_err(|e| fail("vkResetFences", e))?;
        }
        if let Some(p) = profile {
            if !self.timed.is_empty() {
                let mut ts = vec![0u64; 2 * self.timed.len()];
                // SAFETY: the queries were written by the completed submission.
                unsafe {
                    dev.get_query_pool_results(
                        self.queries,
                        0,
                        &mut ts,
                        vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                    )
                }
                .context("reading timestamps failed")?;
                let period = self.gpu.timestamp_period_ns;
                for (i, (pass, kernel)) in self.timed.iter().enumerate() {
                    let ns = ts[2 * i + 1].saturating_sub(ts[2 * i]) as f64 * period;
                    p.add(pass, kernel, ns);
                    if let Some(d) = &mut p.dispatches {
                        // GPU ticks have their own epoch: the batch starts at its submission
                        // on the host clock, so batches follow each other on the trace.
                        let (groups, iteration) = self.timed_groups[i];
                        d.push(DispatchEvent {
                            pass: pass.clone(),
                            kernel: kernel.clone(),
                            groups,
                            iteration,
                            start_us: submitted_us + ts[2 * i].saturating_sub(ts[0]) as f64 * period * 1e-3,
                            duration_us: ns * 1e-3,
                        });
                    }
                }
            }
        }
        Ok(())
    }

    /// Raw timestamp values of the last submission (ticks), for monotonicity tests.
    pub fn last_timestamps(&self) -> Result<Vec<u64>> {
        if self.timed.is_empty() {
            return Ok(Vec::new());
        }
        let mut ts = vec![0u64; 2 * self.timed.len()];
        // SAFETY: queries of a completed submission.
        unsafe {
            self.gpu.device.get_query_pool_results(
                self.queries,
                0,
                &mut ts,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }?;
        Ok(ts)
    }
}

impl Drop for Batch {
    fn drop(&mut self) {
        let dev = &self.gpu.device;
        // SAFETY: nothing pending (submit_wait waits); null handles are no-ops.
        unsafe {
            dev.destroy_query_pool(self.queries, None);
            dev.destroy_fence(self.fence, None);
            dev.destroy_command_pool(self.pool, None);
        }
    }
}
