//! Render options that add to what a render gives besides its image: AOV layers in the
//! EXR (`--aov`, src/render/aov.rs).

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
}

fn parse_aov_set(s: &str) -> Result<AovSet, String> {
    s.parse().map_err(|e: anyhow::Error| e.to_string())
}

impl ExtrasArgs {
    /// The AOV layers asked for (none by default).
    pub fn aov_set(&self) -> AovSet {
        self.aov.unwrap_or_default()
    }
}
