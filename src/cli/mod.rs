//! The subcommands of the `vkvcm` binary, one module each.

pub mod converge;
pub mod diff;
pub mod exit;
pub mod info;
pub mod progress;
pub mod render;
pub mod trace;

use anyhow::{bail, Context, Result};
use clap::Args;

use vkvcm::gpu::GpuOptions;

/// The environment-map options of the commands that render a scene (docs/environment.md).
#[derive(Args, Clone, Debug)]
pub struct EnvArgs {
    /// Light the scene with an equirectangular environment map (Radiance .hdr or OpenEXR;
    /// row 0 is the sky, the image centre looks along +Z: docs/environment.md) instead of
    /// the file's background or the default white sky. Importance-sampled.
    #[arg(long, value_name = "FILE")]
    pub env: Option<std::path::PathBuf>,
    /// With --env: radiance scale of the map.
    #[arg(long, value_name = "S", default_value_t = 1.0, requires = "env")]
    pub env_strength: f32,
    /// With --env: turn the map about the world's +Y axis by DEG degrees (right-handed).
    #[arg(long, value_name = "DEG", default_value_t = 0.0, allow_negative_numbers = true, requires = "env")]
    pub env_rotate: f32,
}

impl EnvArgs {
    /// Checks the numbers (no file is read).
    pub fn check(&self) -> Result<()> {
        if !(self.env_strength >= 0.0 && self.env_strength.is_finite()) {
            bail!("--env-strength {}: must be a non-negative number", self.env_strength);
        }
        if !self.env_rotate.is_finite() {
            bail!("--env-rotate {}: must be a number of degrees", self.env_rotate);
        }
        Ok(())
    }

    /// Scene load options with the map read (`camera` as `--camera` gives it; the file's
    /// default glTF scene).
    pub fn load_options(&self, camera: Option<String>) -> Result<vkvcm::scene::LoadOptions> {
        let environment = match &self.env {
            Some(path) => Some(vkvcm::scene::EnvironmentLight {
                map: std::sync::Arc::new(vkvcm::scene::EnvironmentMap::load(path).context("--env")?),
                scale: glam::Vec3::splat(self.env_strength),
                rotation_deg: self.env_rotate,
            }),
            None => None,
        };
        Ok(vkvcm::scene::LoadOptions { camera, environment, ..Default::default() })
    }
}

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

    /// The device these options name; a failure is a device failure (exit code 4).
    pub fn open(&self) -> Result<std::sync::Arc<vkvcm::gpu::Gpu>> {
        use exit::ClassifyExt;
        vkvcm::gpu::Gpu::new(&self.options()).class(exit::Class::Device)
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
