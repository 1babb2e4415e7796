//! The subcommands of the `vkvcm` binary, one module each.

pub mod bench;
pub mod converge;
pub mod diff;
pub mod progress;
pub mod render;

use anyhow::{Context, Result};
use clap::Args;

use vkvcm::gpu::GpuOptions;

/// The options of the subcommands that open a Vulkan device.
#[derive(Args, Clone, Debug)]
pub struct GpuArgs {
    /// Vulkan device: index or name substring (see `vkvcm devices`).
    #[arg(long)]
    pub device: Option<String>,
    /// Build every kernel afresh, neither reading nor writing the kernel cache (compiled
    /// kernels kept in $VKVCM_CACHE_DIR, else $XDG_CACHE_HOME/vkvcm, else ~/.cache/vkvcm;
    /// docs/kernel-cache.md).
    #[arg(long)]
    pub no_kernel_cache: bool,
}

impl GpuArgs {
    /// The device options: these arguments over the environment's ([`GpuOptions::from_env`]).
    pub fn options(&self) -> GpuOptions {
        let opts = GpuOptions::from_env(self.device.clone());
        if self.no_kernel_cache {
            GpuOptions { kernel_cache: None, ..opts }
        } else {
            opts
        }
    }
}

/// Writes `value` as pretty JSON, atomically.
pub fn write_json<T: serde::Serialize>(p: &std::path::Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    let dir = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
    let mut f = tempfile::NamedTempFile::new_in(dir).with_context(|| format!("cannot write {}", p.display()))?;
    std::io::Write::write_all(&mut f, text.as_bytes())?;
    f.persist(p).with_context(|| format!("cannot write {}", p.display()))?;
    Ok(())
}
