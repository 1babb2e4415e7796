//! `render --shard K/N` (one shard of a render split over machines) and `render --devices`
//! (a render split over this machine's devices): docs/distributed.md.

use anyhow::{bail, Result};
use clap::Args;

use vkvcm::render::saved::ShardOf;
use vkvcm::render::shard::Shard;
use vkvcm::render::{Budget, RenderSettings};

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
    #[arg(long, value_name = "all|I,J,...", conflicts_with = "shard")]
    pub devices: Option<String>,
}

fn parse_shard(s: &str) -> std::result::Result<Shard, String> {
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
