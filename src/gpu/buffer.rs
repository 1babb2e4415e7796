//! Device buffers (storage and uniform texel buffers) owned through gpu-allocator; Drop
//! frees them.

use std::sync::Arc;

use anyhow::{anyhow, bail, Result};
use ash::vk;
use bytemuck::Pod;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::batch::vk_error_text;
use super::Gpu;

/// A device buffer usable as a storage buffer, a uniform texel buffer and a transfer
/// source/destination.
pub struct Buffer {
    gpu: Arc<Gpu>,
    pub(crate) raw: vk::Buffer,
    allocation: Option<Allocation>,
    /// Size in bytes as requested (the Vulkan buffer is at least 16 bytes).
    size: u64,
    name: String,
    /// A constant table within every device's binding limits ([`Gpu::fixed_table`]).
    fixed_table: bool,
}

/// Vulkan's least maxTexelBufferElements (the specification's required limits).
const MIN_TEXEL_BUFFER_ELEMENTS: u64 = 65536;

impl Gpu {
    fn raw_buffer(self: &Arc<Self>, name: &str, size: u64, location: MemoryLocation) -> Result<Buffer> {
        let alloc_size = size.max(16);
        let mut usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST;
        if self.has(super::BUFFER_DEVICE_ADDRESS) {
            usage |= vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
        }
        let info =
            vk::BufferCreateInfo::default().size(alloc_size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid device and create info.
        let raw = unsafe { self.device.create_buffer(&info, None) }
            .map_err(|e| anyhow!("cannot create buffer {name:?} ({size} bytes): {}", vk_error_text(e)))?;
        // SAFETY: `raw` was just created.
        let requirements = unsafe { self.device.get_buffer_memory_requirements(raw) };
        let alloc = self.allocator.lock().map_err(|_| anyhow!("allocator poisoned"))?.allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match alloc {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: not bound, not in use.
                unsafe { self.device.destroy_buffer(raw, None) };
                bail!("out of device memory for buffer {name:?} ({size} bytes): {e}");
            }
        };
        // SAFETY: memory from the allocator matches the requirements.
        if let Err(e) = unsafe { self.device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) } {
            // SAFETY: not bound, not in use.
            unsafe { self.device.destroy_buffer(raw, None) };
            let _ = self.allocator.lock().map(|mut a| a.free(allocation));
            bail!("cannot bind memory to buffer {name:?} ({size} bytes): {}", vk_error_text(e));
        }
        self.debug.name(raw, name);
        Ok(Buffer {
            gpu: self.clone(),
            raw,
            allocation: Some(allocation),
            size,
            name: name.to_string(),
            fixed_table: false,
        })
    }

    /// A zero-filled storage buffer of `count` elements of `T`.
    pub fn buffer_zeroed<T: Pod>(self: &Arc<Self>, name: &str, count: usize) -> Result<Buffer> {
        self.buffer_zeroed_bytes(name, (count * std::mem::size_of::<T>()) as u64)
    }

    /// A zero-filled storage buffer of `bytes` bytes.
    pub fn buffer_zeroed_bytes(self: &Arc<Self>, name: &str, bytes: u64) -> Result<Buffer> {
        let b = self.raw_buffer(name, bytes, MemoryLocation::GpuOnly)?;
        b.fill_zero()?;
        Ok(b)
    }

    /// A storage buffer holding `data`.
    pub fn buffer_from_slice<T: Pod>(self: &Arc<Self>, name: &str, data: &[T]) -> Result<Buffer> {
        let b = self.raw_buffer(name, std::mem::size_of_val(data) as u64, MemoryLocation::GpuOnly)?;
        b.write(data)?;
        Ok(b)
    }

    /// A buffer holding the constant table `data`, read as 16-byte texels, no larger than
    /// Vulkan's least maxTexelBufferElements (65,536): every device binds it, so the
    /// kernels' binding-limit check skips it (and with it the limits that
    /// src/gpu/fault_injection.rs caps for tests, which are the frame's and scene's).
    pub fn fixed_table<T: Pod>(self: &Arc<Self>, name: &str, data: &[T]) -> Result<Buffer> {
        let bytes = std::mem::size_of_val(data) as u64;
        if bytes > MIN_TEXEL_BUFFER_ELEMENTS * 16 {
            bail!("table {name:?} ({bytes} bytes) is larger than every device binds as texels");
        }
        let mut b = self.buffer_from_slice(name, data)?;
        b.fixed_table = true;
        Ok(b)
    }

    /// Records `f` into a one-time command buffer, submits it and waits.
    pub(crate) fn one_shot(&self, f: impl FnOnce(vk::CommandBuffer)) -> Result<()> {
        let dev = &self.device;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(self.queue_family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: standard command-buffer lifecycle; everything is destroyed before return.
        unsafe {
            let pool = dev.create_command_pool(&pool_info, None)?;
            let result = (|| -> Result<()> {
                let cmd = dev.allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1),
                )?[0];
                dev.begin_command_buffer(
                    cmd,
                    &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                )?;
                f(cmd);
                dev.end_command_buffer(cmd)?;
                let cmds = [cmd];
                let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
                let fail = |step: &str, e: vk::Result| anyhow!("{step} of a buffer transfer: {}", vk_error_text(e));
                super::fault_injection::simulated_device_loss(false).map_err(|e| fail("vkQueueSubmit", e))?;
                dev.queue_submit(self.queue, &submit, vk::Fence::null()).map_err(|e| fail("vkQueueSubmit", e))?;
                dev.queue_wait_idle(self.queue).map_err(|e| fail("waiting for the GPU", e))?;
                Ok(())
            })();
            dev.destroy_command_pool(pool, None);
            result
        }
    }
}

impl Buffer {
    pub fn size(&self) -> u64 {
        self.size
    }

    /// Made by [`Gpu::fixed_table`].
    pub fn is_fixed_table(&self) -> bool {
        self.fixed_table
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// The buffer's device address (GLSL's `buffer_reference`), on a device with
    /// buffer device addresses.
    pub fn device_address(&self) -> Result<u64> {
        if !self.gpu.has(super::BUFFER_DEVICE_ADDRESS) {
            bail!("buffer {:?}: the device has no buffer device addresses", self.name);
        }
        // SAFETY: the buffer was created with SHADER_DEVICE_ADDRESS usage and bound to
        // memory allocated with the device-address flag (gpu-allocator's setting).
        Ok(unsafe {
            self.gpu.device.get_buffer_device_address(&vk::BufferDeviceAddressInfo::default().buffer(self.raw))
        })
    }

    fn mapped(&self) -> Option<*mut u8> {
        self.allocation.as_ref()?.mapped_ptr().map(|p| p.as_ptr() as *mut u8)
    }

    /// Sets every byte to zero.
    pub fn fill_zero(&self) -> Result<()> {
        let raw = self.raw;
        let dev = self.gpu.device.clone();
        self.gpu.one_shot(|cmd| {
            // SAFETY: whole-buffer fill of a buffer with TRANSFER_DST usage.
            unsafe { dev.cmd_fill_buffer(cmd, raw, 0, vk::WHOLE_SIZE, 0) }
        })
    }

    /// Copies `data` to the start of the buffer. The device must not be using it.
    pub fn write<T: Pod>(&self, data: &[T]) -> Result<()> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        if bytes.len() as u64 > self.size {
            bail!("write of {} bytes into buffer {:?} of {} bytes", bytes.len(), self.name, self.size);
        }
        if bytes.is_empty() {
            return Ok(());
        }
        if let Some(p) = self.mapped() {
            // SAFETY: host-visible coherent mapping of at least `size` bytes; the device
            // is not accessing the buffer (documented precondition).
            unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), p, bytes.len()) };
            return Ok(());
        }
        let staging = self.gpu.raw_buffer("staging-upload", bytes.len() as u64, MemoryLocation::CpuToGpu)?;
        let p = staging.mapped().ok_or_else(|| anyhow!("staging buffer not mapped"))?;
        // SAFETY: as above, for the staging buffer.
        unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), p, bytes.len()) };
        let (dev, src, dst, n) = (self.gpu.device.clone(), staging.raw, self.raw, bytes.len() as u64);
        self.gpu.one_shot(|cmd| {
            // SAFETY: both buffers are valid for `n` bytes.
            unsafe { dev.cmd_copy_buffer(cmd, src, dst, &[vk::BufferCopy::default().size(n)]) }
        })
    }

    /// Reads the whole buffer as elements of `T`. The device must have finished writing.
    pub fn read<T: Pod>(&self) -> Result<Vec<T>> {
        let n = self.size as usize / std::mem::size_of::<T>();
        let mut out = vec![T::zeroed(); n];
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut out);
        if bytes.is_empty() {
            return Ok(out);
        }
        if let Some(p) = self.mapped() {
            // SAFETY: host-visible coherent mapping; the device is idle on this buffer.
            unsafe { std::ptr::copy_nonoverlapping(p, bytes.as_mut_ptr(), bytes.len()) };
            return Ok(out);
        }
        let staging = self.gpu.raw_buffer("staging-download", bytes.len() as u64, MemoryLocation::GpuToCpu)?;
        let (dev, src, dst, len) = (self.gpu.device.clone(), self.raw, staging.raw, bytes.len() as u64);
        self.gpu.one_shot(|cmd| {
            // SAFETY: both buffers are valid for `len` bytes.
            unsafe { dev.cmd_copy_buffer(cmd, src, dst, &[vk::BufferCopy::default().size(len)]) }
        })?;
        let p = staging.mapped().ok_or_else(|| anyhow!("staging buffer not mapped"))?;
        // SAFETY: the copy completed (one_shot waits).
        unsafe { std::ptr::copy_nonoverlapping(p, bytes.as_mut_ptr(), bytes.len()) };
        Ok(out)
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        // SAFETY: owners guarantee the device no longer uses the buffer (batches wait).
        unsafe { self.gpu.device.destroy_buffer(self.raw, None) };
        if let Some(a) = self.allocation.take() {
            if let Ok(mut al) = self.gpu.allocator.lock() {
                let _ = al.free(a);
            }
        }
    }
}
