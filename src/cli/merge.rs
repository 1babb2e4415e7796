//! `vkvcm merge`: the shards of a split render (`render --shard K/N`) added into the
//! whole render, or those of a reference (`reference --shard K/N`) into the reference
//! (docs/distributed.md).

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use super::exit::{Class, ClassifyExt};
use vkvcm::image::{self, Image};
use vkvcm::render::{merge, reference, saved};

#[derive(Args)]
pub struct MergeArgs {
    /// The shards' EXR files, in any order: all of a render, or all of a reference.
    #[arg(required = true, value_name = "SHARD.exr")]
    pub inputs: Vec<PathBuf>,
    /// The merged render's EXR (resumable like a render's), or the reference's (the
    /// file `vkvcm reference` writes).
    #[arg(long, short = 'o', value_parser = super::parse_exr_path)]
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
    let m = super::shard::merge_files(&a.inputs, a.partial, "use --partial to merge what there is")?;
    if m.half_b.is_some() {
        return write_reference(&a, m);
    }
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

/// The reference of merged reference shards, written as `vkvcm reference` writes it.
fn write_reference(a: &MergeArgs, m: merge::Merged) -> Result<()> {
    let (missing, total) = (m.missing(), m.total);
    let (r, meta) = reference::from_merged(m).class(Class::Usage)?;
    image::write_exr(&a.output, &r.image, &meta)?;
    if !missing.is_empty() {
        eprintln!(
            "warning: partial merge: {} holds {} of each half's {total} iterations; missing: {missing}",
            a.output.display(),
            r.iterations / 2
        );
    }
    if !a.quiet {
        eprintln!("merged {} reference shard(s) into {}", a.inputs.len(), a.output.display());
    }
    super::converge::report_reference(&a.output, &r);
    if let Some(p) = &a.png {
        image::write_png(p, &r.image, a.exposure)?;
        if !a.quiet {
            eprintln!("wrote {}", p.display());
        }
    }
    Ok(())
}
