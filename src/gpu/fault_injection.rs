//! Fault injection for tests. With the `fault-injection` cargo feature (which `make test`
//! turns on) five environment variables, each read once per process, simulate faults;
//! without it (the product) every hook here is a no-op and no variable is read:
//!
//! * `VKVCM_TEST_FAIL_AFTER_BATCHES=N`: the (N+1)-th and every later `Batch::submit_wait`
//!   of the process, and every one-shot transfer after that, fail with
//!   `VK_ERROR_DEVICE_LOST` as a lost device would, so that tests/cli_render.rs can check
//!   what a render leaves behind when the device is lost (docs/robustness.md);
//! * `VKVCM_TEST_WITHOUT_INT64=1`: devices look as if they lacked 64-bit integers, so
//!   that tests/render_atomics.rs can run the fallbacks of docs/devices.md on lavapipe;
//! * `VKVCM_TEST_MAX_BINDING_BYTES=N`: the device binds at most N bytes per buffer, so
//!   that tests/render_addresses.rs reaches the binding limits with tiny frames;
//! * `VKVCM_TEST_MAX_TEXEL_ELEMENTS=N`: the device binds at most N texels per texel
//!   buffer (maxTexelBufferElements) and its other limits are left alone, as on
//!   SwiftShader (65536), so that tests/render_reads.rs reaches the texel limit on lavapipe;
//! * `VKVCM_TEST_SCENE_CHUNK_BYTES=N`: scene arrays read in chunks (past one binding) are
//!   split into chunks of at most N bytes, so that tests reach several chunks with tiny
//!   scenes.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

use ash::vk;

/// The environment variable that turns the simulated device loss on.
pub const FAIL_AFTER_BATCHES_VAR: &str = "VKVCM_TEST_FAIL_AFTER_BATCHES";

/// `Err(ERROR_DEVICE_LOST)` once the process has submitted the number of batches the
/// variable says; `counts_as_batch` counts this call as one (batches do, one-shot
/// transfers do not).
pub(crate) fn simulated_device_loss(counts_as_batch: bool) -> Result<(), vk::Result> {
    if !cfg!(feature = "fault-injection") {
        return Ok(());
    }
    static LIMIT: OnceLock<Option<u64>> = OnceLock::new();
    static SUBMITS: AtomicU64 = AtomicU64::new(0);
    let Some(limit) =
        *LIMIT.get_or_init(|| std::env::var(FAIL_AFTER_BATCHES_VAR).ok().and_then(|v| v.trim().parse().ok()))
    else {
        return Ok(());
    };
    let n = if counts_as_batch { SUBMITS.fetch_add(1, Ordering::SeqCst) } else { SUBMITS.load(Ordering::SeqCst) };
    if n >= limit {
        Err(vk::Result::ERROR_DEVICE_LOST)
    } else {
        Ok(())
    }
}

/// The environment variable that makes every device look as if it had neither
/// `shaderInt64` nor `shaderBufferInt64Atomics` (they are then not enabled either, so the
/// validation layer reports any kernel that still uses 64-bit integers).
pub const WITHOUT_INT64_VAR: &str = "VKVCM_TEST_WITHOUT_INT64";

/// Whether [`WITHOUT_INT64_VAR`] is set to anything but `0`.
pub(crate) fn simulated_missing_int64() -> bool {
    if !cfg!(feature = "fault-injection") {
        return false;
    }
    static SET: OnceLock<bool> = OnceLock::new();
    *SET.get_or_init(|| std::env::var(WITHOUT_INT64_VAR).is_ok_and(|v| !v.is_empty() && v != "0"))
}

/// The environment variable that caps the device's binding limits (maxStorageBufferRange
/// and maxTexelBufferElements x 16 bytes) at its value in bytes, so that tests can reach
/// the limits of docs/robustness.md with tiny frames and scenes.
pub const MAX_BINDING_BYTES_VAR: &str = "VKVCM_TEST_MAX_BINDING_BYTES";

/// `limits` with [`MAX_BINDING_BYTES_VAR`]'s cap applied.
pub(crate) fn capped_binding_limits(mut limits: vk::PhysicalDeviceLimits) -> vk::PhysicalDeviceLimits {
    if !cfg!(feature = "fault-injection") {
        return limits;
    }
    static CAP: OnceLock<Option<u64>> = OnceLock::new();
    if let Some(cap) =
        *CAP.get_or_init(|| std::env::var(MAX_BINDING_BYTES_VAR).ok().and_then(|v| v.trim().parse::<u64>().ok()))
    {
        let cap = cap.min(u32::MAX as u64) as u32;
        limits.max_storage_buffer_range = limits.max_storage_buffer_range.min(cap);
        limits.max_texel_buffer_elements = limits.max_texel_buffer_elements.min(cap / 16);
    }
    static TEXELS: OnceLock<Option<u32>> = OnceLock::new();
    if let Some(texels) =
        *TEXELS.get_or_init(|| std::env::var(MAX_TEXEL_ELEMENTS_VAR).ok().and_then(|v| v.trim().parse::<u32>().ok()))
    {
        limits.max_texel_buffer_elements = limits.max_texel_buffer_elements.min(texels);
    }
    limits
}

/// The environment variable that caps maxTexelBufferElements alone at its value in texels.
pub const MAX_TEXEL_ELEMENTS_VAR: &str = "VKVCM_TEST_MAX_TEXEL_ELEMENTS";

/// The environment variable that caps the chunk of scene arrays read in chunks
/// (src/render/sizes.rs, `scene_chunk_bytes`).
pub const SCENE_CHUNK_BYTES_VAR: &str = "VKVCM_TEST_SCENE_CHUNK_BYTES";

/// [`SCENE_CHUNK_BYTES_VAR`]'s cap in bytes (no cap: `u64::MAX`).
pub(crate) fn scene_chunk_cap() -> u64 {
    if !cfg!(feature = "fault-injection") {
        return u64::MAX;
    }
    static CAP: OnceLock<Option<u64>> = OnceLock::new();
    CAP.get_or_init(|| std::env::var(SCENE_CHUNK_BYTES_VAR).ok().and_then(|v| v.trim().parse().ok()))
        .unwrap_or(u64::MAX)
}
