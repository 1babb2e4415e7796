//! Render options that add to what a render gives besides its image: AOV layers in the
//! EXR (`--aov`, src/render/aov.rs) and the image shown live in tev (`--display`,
//! src/cli/display.rs).

use clap::Args;
use vkvcm::render::aov::AovSet;

#[derive(Args, Clone, Debug, Default)]
pub struct ExtrasArgs {
    /// Also write AOV layers into the output EXR: a comma-separated list of `albedo`
    /// (albedo.R/G/B), `normal` (N.X/Y/Z: world-space shading normal), `depth` (Z: distance
    /// from the camera), `position` (P.X/Y/Z: world position), or `all`. Albedo and normal
    /// are those of the first non-specular surface, through mirrors and glass, averaged
    /// over the pixel's samples (Intel Open Image Denoise's conventions: docs/aov.md).
    /// Not with lt, which traces no camera paths.
    #[arg(long, value_name = "LIST", value_parser = parse_aov_set)]
    pub aov: Option<AovSet>,
    /// Stream the image to a running tev listening on HOST:PORT (tev's default is
    /// 127.0.0.1:14158) while rendering, from a thread of its own; the image shown is named
    /// after the output EXR.
    #[arg(long, value_name = "HOST:PORT")]
    pub display: Option<String>,
    /// With --display: send the image at most every SECONDS (the final one always).
    #[arg(long, value_name = "SECONDS", default_value_t = 2.0, requires = "display")]
    pub display_every: f64,
}

fn parse_aov_set(s: &str) -> Result<AovSet, String> {
    s.parse().map_err(|e: anyhow::Error| e.to_string())
}

impl ExtrasArgs {
    /// The --display thread, started, showing the image under the output's file name.
    pub fn start_display(
        &self,
        output: &std::path::Path,
        width: u32,
        height: u32,
    ) -> anyhow::Result<Option<super::display::Display>> {
        let Some(address) = &self.display else { return Ok(None) };
        if !(self.display_every >= 0.0 && self.display_every.is_finite()) {
            anyhow::bail!("--display-every {}: must be a non-negative number of seconds", self.display_every);
        }
        let name = output.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "vkvcm".into());
        super::display::Display::start(address, &name, width, height, self.display_every).map(Some)
    }

    /// The AOV layers asked for (none by default).
    pub fn aov_set(&self) -> AovSet {
        self.aov.unwrap_or_default()
    }
}
