//! vkvcm's BVH traversal against the driver's own VK_KHR_ray_query (issue #8): the same
//! triangles and the same rays as `vkvcm-bench traverse`, closest hit, interleaved.
//!
//! ```text
//! cargo run --release --example rayquery_bench -- [--scenes cornell,spheres,displaced]
//!     [--rays 1048576] [--rounds 3] [--validation] [--device NAME] [--show-differences N]
//! ```
//!
//! Per scene it builds vkvcm's BVH (CPU, timed) and the driver's BLAS (opaque triangles,
//! PREFER_FAST_TRACE) + TLAS (one instance) (device timestamps); per ray set (camera,
//! random) one warm-up dispatch of each, then `--rounds` rounds of one timed dispatch of
//! each (GPU timestamps), alternating which goes first. Mrays/s are from the median
//! time; the ratio vkvcm / ray query is the median of the per-round ratios, with their
//! range. Every ray's ray-query hit is checked against the CPU traversal of vkvcm's BVH.
//! Exits 0 with a "skipped:" line when the device has no ray queries; exits 1 when
//! validation is on and the layer said anything. This is an example, not a dependency
//! of the renderer: vkvcm itself never uses ray tracing extensions.

mod compare;
mod rq;

use clap::Parser;

#[derive(Parser, Debug)]
#[command(about = "vkvcm BVH traversal vs the driver's VK_KHR_ray_query on the same rays")]
struct Args {
    /// Comma-separated scenes of `vkvcm-bench traverse`.
    #[arg(long, default_value = "cornell,spheres,displaced")]
    scenes: String,
    /// Rays per set (camera: a square-ish image of this many pixels).
    #[arg(long, default_value_t = 1 << 20)]
    rays: u32,
    /// Timed rounds per ray set (median).
    #[arg(long, default_value_t = 3)]
    rounds: u32,
    /// Turn VK_LAYER_KHRONOS_validation on for both devices; any message fails the run.
    #[arg(long)]
    validation: bool,
    /// Device index or name substring (default: vkvcm's choice).
    #[arg(long)]
    device: Option<String>,
    /// Describe the first N rays per set whose closest-hit distances differ.
    #[arg(long, default_value_t = 0)]
    show_differences: usize,
}

fn main() {
    let args = Args::parse();
    if args.rays == 0 {
        eprintln!("rayquery_bench: --rays must be at least 1");
        std::process::exit(2);
    }
    let opts = compare::Options {
        scenes: args.scenes.split(',').map(|s| s.trim().to_string()).filter(|s| !s.is_empty()).collect(),
        rays: args.rays,
        rounds: args.rounds.max(1),
        validation: args.validation,
        device: args.device,
        show_differences: args.show_differences,
    };
    let report = match compare::run(&opts) {
        Ok(Ok(r)) => r,
        Ok(Err(why)) => {
            println!("skipped: {why}");
            return;
        }
        Err(e) => {
            eprintln!("rayquery_bench: {e:#}");
            std::process::exit(1);
        }
    };
    print!("{}", format_report(&report, &opts));
    for row in &report.rows {
        for d in &row.differences {
            println!("{} {}: {d}", row.scene, row.rays);
        }
    }
    if !report.validation_messages.is_empty() {
        for m in &report.validation_messages {
            eprintln!("validation: {m}");
        }
        eprintln!("rayquery_bench: {} validation message(s)", report.validation_messages.len());
        std::process::exit(1);
    }
}

fn format_report(r: &compare::Report, opts: &compare::Options) -> String {
    let mut s = format!(
        "device {} ({}); {} rays per set, {} rounds{}\n\n",
        r.device,
        r.driver,
        opts.rays,
        opts.rounds,
        if opts.validation { ", validation on" } else { "" }
    );
    s += "| scene | triangles | vkvcm BVH build s | BLAS build s (TLAS) | BLAS+TLAS submit wall s | BLAS MiB | vkvcm BVH MiB |\n|---|---|---|---|---|---|---|\n";
    for b in &r.builds {
        s += &format!(
            "| {} | {} | {:.3} | {:.3} ({:.4}) | {:.3} | {:.1} | {:.1} |\n",
            b.scene,
            b.triangles,
            b.vkvcm_build_s,
            b.blas_s,
            b.tlas_s,
            b.rq_build_wall_s,
            b.blas_bytes as f64 / (1 << 20) as f64,
            b.vkvcm_bytes as f64 / (1 << 20) as f64
        );
    }
    s += "\n| scene | rays | vkvcm Mrays/s | ray query Mrays/s | vkvcm / ray query (range) | hit % | t differs > 1e-4 | other triangle | vkvcm GPU != CPU |\n|---|---|---|---|---|---|---|---|---|\n";
    for row in &r.rows {
        let ratios = row.ratios();
        let lo = ratios.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = ratios.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let frac = |k: u32| format!("{k} ({:.4}%)", 100.0 * k as f64 / row.count as f64);
        s += &format!(
            "| {} | {} | {:.2} | {:.2} | {:.2} ({:.2}-{:.2}) | {:.1} | {} | {} | {} |\n",
            row.scene,
            row.rays,
            row.vkvcm_mrays(),
            row.rq_mrays(),
            row.median_ratio(),
            lo,
            hi,
            100.0 * row.hit_fraction,
            frac(row.t_differ),
            frac(row.prim_differ),
            row.vkvcm_gpu_cpu_differ
        );
    }
    s
}
