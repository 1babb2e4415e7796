//! One render on several devices of one machine (`render --devices`, docs/distributed.md):
//! each device renders blocks of global iterations taken from a shared queue, and their
//! films' fixed-point sums are added exactly (src/render/film.rs).
//!
//! Balance: the iterations are cut into blocks of `ceil(I / (8 D))` for D devices; a
//! device takes the next block as soon as it has finished one, so a faster device takes
//! more blocks, and the last block to finish is at most 1/(8 D) of the render. The queue
//! opens when every device has built its kernels (SwiftShader's take seconds): start-up
//! is not mistaken for speed, and every device takes at least one block when there are
//! D blocks or more. Which
//! device renders which iteration does not change the sums: with identical devices the
//! image is that of one device bit for bit; different implementations round differently
//! (the same estimator, tests/shards_devices.rs).

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Barrier, Mutex};

use anyhow::{anyhow, bail, Context, Result};

use super::film::Rejected;
use super::{Budget, RenderOutput, RenderSettings, Renderer};
use crate::gpu::{Gpu, GpuOptions};
use crate::scene::Scene;

/// What one device rendered.
#[derive(Clone, Debug)]
pub struct DeviceShare {
    pub device: String,
    pub iterations: u64,
    pub blocks: u64,
    pub seconds: f64,
}

/// Blocks of iterations a render of `total` iterations on `devices` devices is cut into.
pub fn block_size(total: u64, devices: usize) -> u64 {
    total.div_ceil(8 * devices.max(1) as u64).max(1)
}

/// A device's film after its blocks.
struct DeviceResult {
    out: RenderOutput,
    share: DeviceShare,
    validation: Vec<String>,
}

/// Renders `settings` (an iteration budget) on the devices `devices` at once. Returns
/// the merged output (its seconds: the longest device's) and each device's share; fails
/// when a device fails or its validation layer (when on) reported anything.
pub fn render_on_devices(
    devices: &[GpuOptions],
    scene: &Scene,
    settings: &RenderSettings,
    cancel: Option<&AtomicBool>,
) -> Result<(RenderOutput, Vec<DeviceShare>)> {
    let Budget::Iterations(total) = settings.budget else {
        bail!("rendering on several devices needs an iteration budget");
    };
    let b = block_size(total, devices.len());
    let next_block = AtomicU64::new(0);
    let stop = AtomicBool::new(false);
    let ready = Barrier::new(devices.len());
    let first_error: Mutex<Option<anyhow::Error>> = Mutex::new(None);
    let results: Vec<Option<DeviceResult>> = std::thread::scope(|scope| {
        let handles: Vec<_> = devices
            .iter()
            .map(|opts| {
                let queue = Queue { total, b, next_block: &next_block, stop: &stop, ready: &ready, cancel };
                let first_error = &first_error;
                scope.spawn(move || {
                    let r = device_blocks(opts, scene, settings, &queue);
                    r.map_err(|e| {
                        queue.stop.store(true, Ordering::SeqCst);
                        first_error.lock().unwrap().get_or_insert(e);
                    })
                    .ok()
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap_or(None)).collect()
    });
    if let Some(e) = first_error.into_inner().unwrap() {
        return Err(e);
    }
    let mut results: Vec<DeviceResult> = results.into_iter().map(|r| r.expect("no error, so a result")).collect();
    let messages: Vec<String> = results.iter().flat_map(|r| r.validation.clone()).collect();
    if !messages.is_empty() {
        bail!("{} Vulkan validation message(s):\n{}", messages.len(), messages.join("\n"));
    }
    let shares: Vec<DeviceShare> = results.iter().map(|r| r.share.clone()).collect();
    let mut merged = results.remove(0).out;
    for r in results {
        merged.sums.add(&r.out.sums)?;
        merged.held.union(&r.out.held).map_err(|e| anyhow!("two devices rendered one iteration: {e}"))?;
        let rejected = Rejected {
            samples: merged.rejected_samples + r.out.rejected_samples,
            overflow_splats: merged.overflow_splats + r.out.overflow_splats,
            overflow_samples: merged.overflow_samples + r.out.overflow_samples,
        };
        (merged.rejected_samples, merged.overflow_splats, merged.overflow_samples) =
            (rejected.samples, rejected.overflow_splats, rejected.overflow_samples);
        merged.seconds = merged.seconds.max(r.out.seconds);
        merged.interrupted |= r.out.interrupted;
    }
    merged.iterations = merged.held.len();
    merged.pixels = merged.sums.mean(merged.iterations);
    (merged.sum, merged.sum_sq) = merged.sums.reals();
    Ok((merged, shares))
}

/// The blocks of iterations `0..total`, `b` each, that the devices share.
struct Queue<'a> {
    total: u64,
    b: u64,
    next_block: &'a AtomicU64,
    /// Set when a device failed: the others stop.
    stop: &'a AtomicBool,
    /// Every device waits here once prepared (or failed), before the first block.
    ready: &'a Barrier,
    cancel: Option<&'a AtomicBool>,
}

/// One device's loop: once every device is prepared, take the next block until none is
/// left (or a device failed, or `cancel`), render it at its global indices.
fn device_blocks(opts: &GpuOptions, scene: &Scene, settings: &RenderSettings, q: &Queue) -> Result<DeviceResult> {
    let what = opts.device.clone().unwrap_or_else(|| "the default device".into());
    let prepared = Gpu::new(opts).with_context(|| format!("opening device {what}")).and_then(|gpu| {
        let r = Renderer::new(&gpu, scene, settings)
            .with_context(|| format!("preparing the render on {}", gpu.info.name))?;
        Ok((gpu, r))
    });
    if prepared.is_err() {
        q.stop.store(true, Ordering::SeqCst);
    }
    q.ready.wait();
    let (gpu, mut r) = prepared?;
    let messages = gpu.validation_messages();
    let name = gpu.info.name.clone();
    let mut blocks = 0;
    loop {
        if q.stop.load(Ordering::SeqCst) || q.cancel.is_some_and(|c| c.load(Ordering::SeqCst)) {
            break;
        }
        let start = q.next_block.fetch_add(1, Ordering::SeqCst).saturating_mul(q.b);
        if start >= q.total {
            break;
        }
        let end = (start + q.b).min(q.total);
        r.start_at(start);
        r.run(Budget::Iterations(end - start), q.cancel, &mut |_| {})
            .with_context(|| format!("iterations {start}-{} on {name}", end - 1))?;
        blocks += 1;
    }
    let out = r.output().with_context(|| format!("reading the film of {name} back"))?;
    drop(r);
    let share = DeviceShare { device: name, iterations: out.iterations, blocks, seconds: out.seconds };
    drop(gpu);
    let validation = messages.list();
    Ok(DeviceResult { out, share, validation })
}
