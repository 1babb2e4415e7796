//! The subcommands of the `vkvcm` binary, one module each.

pub mod converge;
pub mod denoise;
pub mod diff;
pub mod display;
pub mod exit;
pub mod extras;
pub mod info;
pub mod merge;
pub mod progress;
pub mod render;
pub mod scene_args;
pub mod shard;
pub mod submission;
pub mod trace;

use anyhow::{bail, Context, Result};
use clap::Args;

/// The environment options of the commands that render a scene (docs/environment.md).
#[derive(Args, Clone, Debug)]
pub struct EnvArgs {
    /// Light the scene with `studio` (a neutral studio: a grey room with soft lights),
    /// `sky` (an analytic daylight sky with a sun, Preetham et al. 1999), an
    /// equirectangular map FILE (Radiance .hdr or OpenEXR; row 0 is the sky, the image
    /// centre looks along +Z: docs/environment.md; ./studio for a file of that name), or
    /// `none`, instead of the file's own environment; `white`: the uniform white sky of
    /// radiance 1 that the library gives a file without lights (for comparisons with
    /// renderers that default to it). Default: the file's; a file with neither punctual
    /// lights nor an environment gets the studio. Importance-sampled.
    #[arg(long, value_name = "studio|sky|white|FILE|none")]
    pub env: Option<String>,
    /// With --env: radiance scale of the map.
    #[arg(long, value_name = "S", default_value_t = 1.0, requires = "env")]
    pub env_strength: f32,
    /// With --env: turn the map about the world's +Y axis by DEG degrees (right-handed).
    #[arg(long, value_name = "DEG", default_value_t = 0.0, allow_negative_numbers = true, requires = "env")]
    pub env_rotate: f32,
    /// With --env sky: the sun's height above the horizon, in (0, 90] degrees (default 45).
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub sun_elevation: Option<f32>,
    /// With --env sky: the sun's direction in degrees from +Z towards +X (default 30).
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub sun_azimuth: Option<f32>,
    /// With --env sky: the air's turbidity, 2 (very clear) to 10 (hazy) (default 3).
    #[arg(long, value_name = "T")]
    pub turbidity: Option<f32>,
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
        let sky_options = self.sun_elevation.is_some() || self.sun_azimuth.is_some() || self.turbidity.is_some();
        if sky_options && self.env.as_deref() != Some("sky") {
            bail!("--sun-elevation, --sun-azimuth and --turbidity shape --env sky, which is not chosen");
        }
        Ok(())
    }

    /// Scene load options with the environment made or read (`camera` as `--camera`
    /// gives it; the file's default glTF scene).
    pub fn load_options(&self, camera: Option<String>) -> Result<vkvcm::scene::LoadOptions> {
        use vkvcm::scene::default_environments::{self as defaults, SkyParameters};
        let light = |map| vkvcm::scene::EnvironmentLight {
            map: std::sync::Arc::new(map),
            scale: glam::Vec3::splat(self.env_strength),
            rotation_deg: self.env_rotate,
        };
        let studio = || defaults::studio(defaults::STUDIO_SIZE.0, defaults::STUDIO_SIZE.1);
        let mut options = vkvcm::scene::LoadOptions { camera, ..Default::default() };
        match self.env.as_deref() {
            None => options.default_environment = Some(light(studio()?)),
            Some("none") => options.no_environment = true,
            // The library's own default: a uniform white sky where the file has no light.
            Some("white") => {}
            Some("studio") => options.environment = Some(light(studio()?)),
            Some("sky") => {
                let d = SkyParameters::default();
                let p = SkyParameters {
                    sun_azimuth_deg: self.sun_azimuth.unwrap_or(d.sun_azimuth_deg),
                    sun_elevation_deg: self.sun_elevation.unwrap_or(d.sun_elevation_deg),
                    turbidity: self.turbidity.unwrap_or(d.turbidity),
                };
                let map = defaults::sky(defaults::SKY_SIZE.0, defaults::SKY_SIZE.1, &p).context("--env sky")?;
                options.environment = Some(light(map));
            }
            Some(path) => {
                let map = vkvcm::scene::EnvironmentMap::load(std::path::Path::new(path)).context("--env")?;
                options.environment = Some(light(map));
            }
        }
        Ok(options)
    }
}

pub use vkvcm::gpu::GpuArgs;

/// An output path for an OpenEXR file (`-o` of render, reference, merge and denoise:
/// linear float32 with AOVs and resume data, which no 8-bit format holds): a name ending
/// in another image format's extension is refused, pointing at `--png`, rather than
/// written as EXR under a misleading name; any other name is taken as it is.
pub fn parse_exr_path(s: &str) -> std::result::Result<std::path::PathBuf, String> {
    let p = std::path::PathBuf::from(s);
    match p.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some(e @ ("png" | "jpg" | "jpeg" | "hdr" | "tif" | "tiff" | "bmp" | "webp")) => Err(format!(
            "{s:?}: -o writes OpenEXR (.exr); for a tone-mapped .{e} image add --png FILE.png (render, merge) \
             beside an .exr output"
        )),
        _ => Ok(p),
    }
}

/// The device `args` name; a failure is a device failure (exit code 4).
pub fn open_device(args: &GpuArgs) -> Result<std::sync::Arc<vkvcm::gpu::Gpu>> {
    use exit::ClassifyExt;
    vkvcm::gpu::Gpu::new(&args.options()).class(exit::Class::Device)
}

pub use vkvcm::image::write_json;
