//! Command batches: record dispatches (each wrapped in timestamp queries when the device
//! supports them), submit, wait, and fold the timings into a `Profile`. A batch with a
//! submission budget ([`Batch::set_budget`]) submits what it holds before the next
//! dispatch would take it past the budget, from each kernel's time per path measured by
//! the timestamps of earlier submissions, and splits passes over paths into pieces
//! ([`Batch::record_paths`]): display GPUs reset a device whose submission runs for more
//! than about two seconds (docs/robustness.md, "Watchdog resets").

use std::collections::HashMap;
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
    /// Paths (or 1) of each timed dispatch: the unit of its kernel's rate.
    timed_units: Vec<u64>,
    budget: Budget,
    /// Queue submissions so far.
    submissions: u64,
}

/// A submission's time budget and what it has learned: each kernel's nanoseconds per unit
/// (per path for [`Batch::dispatch_paths`], else per dispatch).
#[derive(Default)]
struct Budget {
    /// Nanoseconds a submission may take; `None`: no budget.
    ns: Option<f64>,
    rates: HashMap<String, f64>,
    /// Predicted nanoseconds of what is recorded.
    predicted: f64,
    /// A kernel of unknown rate was recorded: submit before the next dispatch, so that
    /// its time is measured alone.
    submit_next: bool,
    /// Timings of the submissions the budget made, for the caller's next `submit_wait`.
    held: Profile,
}

/// Paths of the first piece of a kernel whose rate is not known yet (a probe: a few
/// milliseconds of work on a laptop GPU).
const PROBE_PATHS: u32 = 1 << 16;

/// The fewest paths of a piece (smaller pieces cost more in submissions than they save).
const MIN_PIECE_PATHS: u32 = 64;

/// The default submission budget on `device_type`: half a second on GPUs, which may drive
/// a display and its watchdog; none on CPU devices, which have no watchdog.
pub fn default_submission_budget_ms(device_type: vk::PhysicalDeviceType) -> Option<f64> {
    (device_type != vk::PhysicalDeviceType::CPU).then_some(500.0)
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
                timed_units: Vec::new(),
                budget: Budget {
                    held: Profile { dispatches: Some(Vec::new()), ..Default::default() },
                    ..Default::default()
                },
                submissions: 0,
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
        self.timed_units.clear();
        self.kernels.clear();
        self.budget.predicted = 0.0;
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

    /// Keeps each submission within `ms` milliseconds of GPU time (`None`: no budget). It
    /// needs timestamp queries; without them it is ignored.
    pub fn set_budget(&mut self, ms: Option<f64>) {
        self.budget.ns = ms.filter(|&m| m > 0.0 && self.queries != vk::QueryPool::null()).map(|m| m * 1e6);
    }

    /// Whether a submission budget is in force.
    pub fn has_budget(&self) -> bool {
        self.budget.ns.is_some()
    }

    /// Queue submissions so far (those a budget made included).
    pub fn submissions(&self) -> u64 {
        self.submissions
    }

    /// Records a pass over paths `0 .. paths` in pieces of at most `max_piece` paths that
    /// keep each submission within the budget, by `kernel`'s time per path: `record(batch,
    /// first, count)` records one piece (with [`Batch::dispatch_paths`]). Without a budget,
    /// pieces of `max_piece`.
    pub fn record_paths(
        &mut self,
        kernel: &Kernel,
        paths: u32,
        max_piece: u32,
        mut record: impl FnMut(&mut Batch, u32, u32) -> Result<()>,
    ) -> Result<()> {
        let mut first = 0;
        while first < paths {
            let count = self.piece_paths(kernel.name(), paths - first)?.min(max_piece.max(1));
            record(self, first, count)?;
            first += count;
        }
        Ok(())
    }

    /// Paths of the next piece of a pass of `kernel` with `left` paths to go: what fits the
    /// room left in this submission, or else (after submitting what it holds) a whole
    /// budget's worth.
    fn piece_paths(&mut self, kernel: &str, left: u32) -> Result<u32> {
        let Some(budget) = self.budget.ns else { return Ok(left) };
        if self.budget.submit_next && self.recording {
            self.submit_held()?;
        }
        let Some(&rate) = self.budget.rates.get(kernel) else { return Ok(left.min(PROBE_PATHS)) };
        let fits = |room: f64| (room / rate.max(1e-3)).min(left as f64) as u32;
        if fits(budget - self.budget.predicted) < MIN_PIECE_PATHS.min(left) && self.recording {
            self.submit_held()?;
        }
        Ok(fits(budget - self.budget.predicted).clamp(MIN_PIECE_PATHS.min(left), left))
    }

    /// Records `kernel` over `groups` workgroups with `push` as push constants.
    pub fn dispatch(&mut self, kernel: &Kernel, groups: [u32; 3], push: &[u8]) -> Result<()> {
        self.dispatch_units(kernel, groups, push, 1)
    }

    /// [`Batch::dispatch`] of a kernel that traces `paths` paths: its time per path keeps
    /// the pieces of [`Batch::record_paths`] within the budget.
    pub fn dispatch_paths(&mut self, kernel: &Kernel, groups: [u32; 3], push: &[u8], paths: u32) -> Result<()> {
        self.dispatch_units(kernel, groups, push, paths as u64)
    }

    fn dispatch_units(&mut self, kernel: &Kernel, groups: [u32; 3], push: &[u8], units: u64) -> Result<()> {
        if push.len() as u32 > PUSH_CONSTANT_BYTES {
            bail!("kernel {}: {} push-constant bytes, at most {PUSH_CONSTANT_BYTES}", kernel.name(), push.len());
        }
        if groups.contains(&0) {
            return Ok(());
        }
        self.keep_within_budget(kernel.name(), units)?;
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
            self.timed_units.push(units);
        }
        if !self.kernels.iter().any(|k| k == kernel.name()) {
            self.kernels.push(kernel.name().to_string());
        }
        Ok(())
    }

    /// Before a dispatch of `units` of `kernel`: submits what is recorded when the dispatch
    /// would take the submission past the budget (or follows one of unknown time).
    fn keep_within_budget(&mut self, kernel: &str, units: u64) -> Result<()> {
        let Some(budget) = self.budget.ns else { return Ok(()) };
        if self.recording && self.budget.submit_next {
            self.submit_held()?;
        }
        let rate = self.budget.rates.get(kernel).copied();
        let ns = rate.map_or(0.0, |r| r * units as f64);
        let full = self.timed.len() as u32 >= MAX_TIMED;
        if self.recording && (full || self.budget.predicted + ns > budget) {
            self.submit_held()?;
        }
        self.budget.predicted += ns;
        self.budget.submit_next = rate.is_none();
        Ok(())
    }

    /// Records a fill of the whole buffer with the 32-bit `value`.
    pub fn fill(&mut self, buffer: &Buffer, value: u32) -> Result<()> {
        if self.budget.submit_next && self.recording {
            self.submit_held()?;
        }
        self.begin()?;
        self.barrier();
        // SAFETY: recording; the buffer has TRANSFER_DST usage.
        unsafe { self.gpu.device.cmd_fill_buffer(self.cmd, buffer.raw, 0, vk::WHOLE_SIZE, value) };
        Ok(())
    }

    /// Submits what was recorded, waits for it, and adds the kernel timings to `profile`
    /// (those of the submissions a budget made since the last call included).
    pub fn submit_wait(&mut self, profile: Option<&mut Profile>) -> Result<()> {
        let r = self.submit(profile.as_deref().is_some());
        let held =
            std::mem::replace(&mut self.budget.held, Profile { dispatches: Some(Vec::new()), ..Default::default() });
        if let Some(p) = profile {
            p.absorb(&held);
            if let (Some(d), Some(h)) = (&mut p.dispatches, held.dispatches) {
                d.extend(h);
            }
        }
        r
    }

    /// Submits what is recorded in the middle of a batch (the budget's split), keeping its
    /// timings for the caller's next [`Batch::submit_wait`].
    fn submit_held(&mut self) -> Result<()> {
        self.submit(true)
    }

    /// Submits what was recorded and waits for it; with `timings`, adds the kernel timings
    /// to the held profile. Each kernel's rate is updated where a budget is in force.
    fn submit(&mut self, timings: bool) -> Result<()> {
        if !self.recording {
            return Ok(());
        }
        self.recording = false;
        self.budget.submit_next = false;
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
            self.submissions += 1;
            dev.queue_submit(self.gpu.queue, &submit, self.fence).map_err(|e| fail("vkQueueSubmit", e))?;
            dev.wait_for_fences(&[self.fence], true, u64::MAX).map_err(|e| fail("waiting for the GPU", e))?;
            dev.reset_fences(&[self.fence]).map_err(|e| fail("vkResetFences", e))?;
        }
        if self.timed.is_empty() || !(timings || self.has_budget()) {
            return Ok(());
        }
        let ts = self.last_timestamps().context("reading timestamps failed")?;
        let period = self.gpu.timestamp_period_ns;
        for (i, (pass, kernel)) in self.timed.iter().enumerate() {
            let ns = ts[2 * i + 1].saturating_sub(ts[2 * i]) as f64 * period;
            if self.budget.ns.is_some() {
                // Up at once, down by halves: a piece of sky after a piece of geometry
                // must not make the next piece too long.
                let rate = ns / self.timed_units[i].max(1) as f64;
                let old = self.budget.rates.get(kernel).copied().unwrap_or(0.0);
                self.budget.rates.insert(kernel.clone(), rate.max(0.5 * old));
            }
            if !timings {
                continue;
            }
            let p = &mut self.budget.held;
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
