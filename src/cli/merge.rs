//! `vkvcm merge`: the shards of a split render (`render --shard K/N`) added into the
//! whole render (docs/distributed.md).

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use super::exit::{Class, ClassifyExt};
use vkvcm::image::{self, Image};
use vkvcm::render::{merge, saved};

#[derive(Args)]
pub struct MergeArgs {
    /// The shards' EXR files, in any order.
    #[arg(required = true, value_name = "SHARD.exr")]
    pub inputs: Vec<PathBuf>,
    /// The merged render's EXR (resumable like a render's).
    #[arg(long, short = 'o')]
    pub output: PathBuf,
    /// Also write a tone-mapped sRGB PNG.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Exposure scale for the PNG.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    /// Merge the shards given even when some are missing or unfinished: the output holds
    /// fewer iterations (it says which are missing, also in its vkvcm:missing attribute).
    #[arg(long)]
    pub partial: bool,
    /// Print only warnings and errors.
    #[arg(long, short = 'q')]
    pub quiet: bool,
}

pub fn merge_cmd(a: MergeArgs) -> Result<()> {
    super::render::check_writable(&a.output).context("--output")?;
    if let Some(p) = &a.png {
        super::render::check_writable(p).context("--png")?;
    }
    let mut files = Vec::with_capacity(a.inputs.len());
    for p in &a.inputs {
        let s =
            saved::read_render_exr(p).with_context(|| format!("cannot merge {}", p.display())).class(Class::Usage)?;
        files.push((p.clone(), s));
    }
    let m = merge::merge(&files, a.partial).map_err(|r| {
        let class = if r.scene { Class::Scene } else { Class::Usage };
        anyhow::Error::new(super::exit::Classified(class, anyhow::anyhow!("{}", r.message)))
    })?;
    drop(files);
    saved::write_sums_exr(&a.output, m.width, m.height, &m.sums, m.iterations(), &m.metadata, Vec::new())?;
    let missing = m.missing();
    if !missing.is_empty() {
        eprintln!(
            "warning: partial merge: {} holds {} of the render's {} iterations; missing: {missing}",
            a.output.display(),
            m.iterations(),
            m.total
        );
    }
    if !a.quiet {
        eprintln!("merged {} file(s), {} iterations, into {}", a.inputs.len(), m.iterations(), a.output.display());
    }
    if m.rejected.samples > 0 {
        eprintln!("warning: {} sample(s) were NaN, infinite or negative and were rejected", m.rejected.samples);
    }
    if m.rejected.overflow_samples > 0 {
        eprintln!(
            "warning: {} sample(s) were above the film's range (2^32) and were rejected",
            m.rejected.overflow_samples
        );
    }
    if let Some(p) = &a.png {
        let img = Image { width: m.width, height: m.height, data: m.sums.mean(m.iterations()) };
        image::write_png(p, &img, a.exposure)?;
        if !a.quiet {
            eprintln!("wrote {}", p.display());
        }
    }
    Ok(())
}
