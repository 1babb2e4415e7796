//! Fault injection for tests — not a feature. Two environment variables, each read once
//! per process:
//!
//! * `VKVCM_TEST_FAIL_AFTER_BATCHES=N`: the (N+1)-th and every later `Batch::submit_wait`
//!   of the process, and every one-shot transfer after that, fail with
//!   `VK_ERROR_DEVICE_LOST` as a lost device would, so that tests/cli_render.rs can check
//!   what a render leaves behind when the device is lost (docs/robustness.md);
//! * `VKVCM_TEST_WITHOUT_INT64=1`: devices look as if they lacked 64-bit integers, so
//!   that tests/render_atomics.rs can run the fallbacks of docs/devices.md on lavapipe.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

use ash::vk;

/// The environment variable that turns the simulated device loss on.
pub const FAIL_AFTER_BATCHES_VAR: &str = "VKVCM_TEST_FAIL_AFTER_BATCHES";

/// `Err(ERROR_DEVICE_LOST)` once the process has submitted the number of batches the
/// variable says; `counts_as_batch` counts this call as one (batches do, one-shot
/// transfers do not).
pub(crate) fn simulated_device_loss(counts_as_batch: bool) -> Result<(), vk::Result> {
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
    static SET: OnceLock<bool> = OnceLock::new();
    *SET.get_or_init(|| std::env::var(WITHOUT_INT64_VAR).is_ok_and(|v| !v.is_empty() && v != "0"))
}
