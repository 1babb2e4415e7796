//! `render --shard K/N` (one shard of a render split over machines) and `render --devices`
//! (a render split over this machine's devices): docs/distributed.md.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::{anyhow, bail, Context, Result};
use clap::Args;

use super::exit::{Class, ClassifyExt};
use vkvcm::gpu::GpuOptions;
use vkvcm::image::{self, Image};
use vkvcm::render::merge;
use vkvcm::render::saved::{self, Provenance, ShardOf};
use vkvcm::render::shard::Shard;
use vkvcm::render::{devices, Budget, RenderSettings};
use vkvcm::scene::Scene;

/// The render options that split a render (flattened into `render`'s arguments).
#[derive(Args, Clone, Debug, Default)]
pub struct ShardArgs {
    /// Render shard K of N (K from 0 to N-1) of the render of --iterations I: the global
    /// iterations K*I/N to (K+1)*I/N - 1, with the random numbers and merge radius they
    /// have in the whole render. `vkvcm merge` adds the N shards' files into the bits of
    /// the whole render (docs/distributed.md).
    #[arg(long, value_name = "K/N", value_parser = parse_shard)]
    pub shard: Option<Shard>,
    /// Render on several Vulkan devices of this machine at once (`all`, or indices as
    /// `vkvcm devices` lists them, e.g. 0,2), each taking the next block of iterations as
    /// it finishes one, and add their films exactly (docs/distributed.md).
    #[arg(
        long,
        value_name = "all|I,J,...",
        conflicts_with_all = ["shard", "device", "time", "resume", "checkpoint_every", "profile", "profile_json", "profile_trace"]
    )]
    pub devices: Option<String>,
}

pub(super) fn parse_shard(s: &str) -> std::result::Result<Shard, String> {
    Shard::parse(s).map_err(|e| format!("{e:#}"))
}

impl ShardArgs {
    /// With --shard: `settings` with the shard's iterations as its budget, and which
    /// shard of which render it is. Needs --iterations (a time budget is no fixed split).
    pub fn apply(&self, iterations: Option<u64>, settings: &mut RenderSettings) -> Result<Option<ShardOf>> {
        let Some(shard) = self.shard else { return Ok(None) };
        let Some(total) = iterations else {
            bail!("--shard {shard} needs --iterations: the shards of a render split a fixed number of iterations");
        };
        if total < shard.count as u64 {
            bail!("--shard {shard}: --iterations {total} is fewer than {} shards (each needs one)", shard.count);
        }
        settings.budget = Budget::Iterations(shard.range(total).end - shard.range(total).start);
        Ok(Some(ShardOf { shard, total }))
    }
}

/// The devices `--devices` names (`all`: every usable one), as options to open each.
fn device_options(list: &str, base: &GpuOptions) -> Result<Vec<GpuOptions>> {
    let found = vkvcm::gpu::list_devices().class(Class::Device)?;
    let indices: Vec<usize> = if list.trim() == "all" {
        found.iter().filter(|d| d.missing_required().is_empty()).map(|d| d.index).collect()
    } else {
        let mut v = Vec::new();
        for part in list.split(',') {
            let i: usize =
                part.trim().parse().map_err(|_| anyhow!("--devices {list}: {part:?} is not a device index"))?;
            if !found.iter().any(|d| d.index == i) {
                bail!("--devices {list}: there is no device {i} (`vkvcm devices` lists them)");
            }
            if v.contains(&i) {
                bail!("--devices {list}: device {i} is named twice");
            }
            v.push(i);
        }
        v
    };
    if indices.is_empty() {
        return Err(anyhow!("--devices {list}: no usable Vulkan device")).class(Class::Device);
    }
    Ok(indices.into_iter().map(|i| GpuOptions { device: Some(i.to_string()), ..base.clone() }).collect())
}

/// Where `render --devices` writes, and how it reports.
pub struct DevicesOutput<'a> {
    pub path: &'a Path,
    pub png: Option<&'a Path>,
    pub exposure: f32,
    pub quiet: bool,
    /// Set by Ctrl-C: the devices stop after their current block.
    pub cancel: &'a AtomicBool,
}

/// `render --devices`: the render on every device named, merged, written as one render.
pub fn render_on_devices(
    list: &str,
    gpu: &GpuOptions,
    scene: &Scene,
    settings: &RenderSettings,
    provenance: &mut Provenance,
    o: &DevicesOutput,
) -> Result<Option<Class>> {
    let opts = device_options(list, gpu).class(Class::Usage)?;
    if !o.quiet {
        let Budget::Iterations(total) = settings.budget else { unreachable!("--devices conflicts with --time") };
        eprintln!(
            "rendering on {} device(s), blocks of {} iterations from a shared queue",
            opts.len(),
            devices::block_size(total, opts.len())
        );
    }
    let (out, shares) =
        super::exit::memory_if_out_of_memory(devices::render_on_devices(&opts, scene, settings, Some(o.cancel)))
            .with_context(|| {
                format!("rendering {} with {} on several devices", scene.name, settings.algorithm.name())
            })?;
    if out.iterations == 0 {
        eprintln!("interrupted before the first iteration finished: nothing written");
        return Ok(Some(Class::Interrupted));
    }
    provenance.device = shares.iter().map(|s| s.device.clone()).collect::<Vec<_>>().join(", ");
    saved::write_render_exr(o.path, &out, settings, provenance)?;
    if !o.quiet {
        for s in &shares {
            eprintln!("  {}: {} iterations in {} block(s), {:.2} s", s.device, s.iterations, s.blocks, s.seconds);
        }
        eprintln!("{} iterations; wrote {}", out.iterations, o.path.display());
    }
    if out.rejected_samples > 0 {
        eprintln!("warning: {} sample(s) were NaN, infinite or negative and were rejected", out.rejected_samples);
    }
    if let Some(p) = o.png {
        let img = Image { width: out.width, height: out.height, data: out.pixels.clone() };
        image::write_png(p, &img, o.exposure)?;
    }
    Ok(o.cancel.load(Ordering::SeqCst).then_some(Class::Interrupted))
}

/// The shards `paths` merged, read one at a time (the merge holds the running sums and
/// one shard's). An unreadable, truncated or foreign file is a usage error naming it; a
/// refusal exits 3 for another scene, 2 otherwise.
/// `incomplete_hint` follows the refusal of an incomplete set (what the user may do).
pub(super) fn merge_files(paths: &[PathBuf], partial: bool, incomplete_hint: &str) -> Result<merge::Merged> {
    let refused = |r: merge::Refusal| {
        let class = if r.scene { Class::Scene } else { Class::Usage };
        let message = if r.incomplete { format!("{} ({incomplete_hint})", r.message) } else { r.message };
        anyhow::Error::new(super::exit::Classified(class, anyhow::anyhow!("{message}")))
    };
    let mut merger: Option<merge::Merger> = None;
    for p in paths {
        let s =
            saved::read_render_exr(p).with_context(|| format!("cannot merge {}", p.display())).class(Class::Usage)?;
        match &mut merger {
            None => merger = Some(merge::Merger::new(p.clone(), s, partial).map_err(refused)?),
            Some(m) => m.add(p, &s).map_err(refused)?,
        }
    }
    let Some(m) = merger else { bail!("no files to merge") };
    m.finish().map_err(refused)
}
