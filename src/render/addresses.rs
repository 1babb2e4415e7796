//! Buffer device addresses of the frame's large buffers: the film, the splat sums, the
//! light-vertex store with its offsets and the light kernel's scratch slots, and the hash
//! grid's keys and entries ([`GpuAddresses`]).
//!
//! A buffer bound through a descriptor is limited to `maxStorageBufferRange` (128 MiB on
//! lavapipe), which a 4K film (96 bytes per pixel) exceeds. A buffer reached through its
//! device address (Vulkan 1.2 `bufferDeviceAddress`, GLSL `GL_EXT_buffer_reference`) is
//! limited only by `maxMemoryAllocationSize` and memory. On devices with the feature the
//! kernels reach these buffers through the addresses held in one small storage buffer,
//! `frame_addresses` ([`GpuAddresses`], glsl/addresses.glsl), written once per render;
//! elsewhere they bind them as storage buffers, with the binding limit (DEVICE_ADDRESSES,
//! src/render/variants.rs). Both read and write the same bytes in the same order: the
//! image is bit-identical (tests/render_addresses.rs).

use std::cell::Cell;
use std::sync::Arc;

use anyhow::Result;

use super::gpu_types::GpuAddresses;
use crate::gpu::{Bind, Buffer, Gpu, BUFFER_DEVICE_ADDRESS};

/// The binding that holds the addresses.
pub const BINDING: &str = "frame_addresses";

/// The addresses buffer and what it holds.
pub struct FrameAddresses {
    buffer: Buffer,
    values: Cell<GpuAddresses>,
    enabled: bool,
}

impl FrameAddresses {
    pub fn new(gpu: &Arc<Gpu>) -> Result<FrameAddresses> {
        Ok(FrameAddresses {
            buffer: gpu.buffer_zeroed::<GpuAddresses>(BINDING, 1)?,
            values: Cell::new(GpuAddresses::default()),
            enabled: gpu.has(BUFFER_DEVICE_ADDRESS),
        })
    }

    /// Whether the kernels reach the frame's large buffers by address.
    pub fn enabled(&self) -> bool {
        self.enabled
    }

    /// Records `buffer`'s address in the field `field` selects (nothing without device
    /// addresses). Called when the buffer is created, before any kernel runs.
    pub fn set(&self, field: fn(&mut GpuAddresses) -> &mut [u32; 2], buffer: &Buffer) -> Result<()> {
        if !self.enabled {
            return Ok(());
        }
        let a = buffer.device_address()?;
        let mut v = self.values.get();
        *field(&mut v) = [a as u32, (a >> 32) as u32];
        self.values.set(v);
        self.buffer.write(&[v])
    }

    /// The binding `frame_addresses`.
    pub fn bind(&self) -> Bind<'_> {
        Bind::own(&self.buffer)
    }
}
