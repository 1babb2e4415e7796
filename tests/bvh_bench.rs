//! The traversal benchmark as an ignored test (the same code as `vkvcm-bench traverse`):
//!
//! ```text
//! VKVCM_BENCH_SCENES=cornell,spheres,displaced \
//!     cargo test --release --test bvh_bench -- --ignored --nocapture
//! ```
//!
//! `VKVCM_BENCH_LOCAL_SIZE` sets the workgroup size, `VKVCM_BENCH_REPEATS` the timed
//! dispatches, `VKVCM_BENCH_CT` / `_BINS` / `_LEAF` the SAH build options. Validation is off (it would time the layer, not the traversal).

use vkvcm::gpu::{Gpu, GpuOptions};
use vkvcm_tools::bench::traverse::{bench_scene, bench_traverse, TraverseBenchOptions};

#[test]
#[ignore = "benchmark: run explicitly with --ignored --release"]
fn bench_traverse_scenes() {
    let scenes = std::env::var("VKVCM_BENCH_SCENES").unwrap_or_else(|_| "cornell".into());
    let mut opts = TraverseBenchOptions::default();
    // SAH experiments: traversal cost (intersection cost is 1), bins, largest leaf.
    if let Ok(s) = std::env::var("VKVCM_BENCH_CT") {
        opts.build.traversal_cost = s.parse().expect("VKVCM_BENCH_CT");
    }
    if let Ok(s) = std::env::var("VKVCM_BENCH_BINS") {
        opts.build.bins = s.parse().expect("VKVCM_BENCH_BINS");
    }
    if let Ok(s) = std::env::var("VKVCM_BENCH_LEAF") {
        opts.build.max_leaf = s.parse().expect("VKVCM_BENCH_LEAF");
    }
    if let Ok(s) = std::env::var("VKVCM_BENCH_REPEATS") {
        opts.repeats = s.parse().expect("VKVCM_BENCH_REPEATS");
    }
    if let Ok(s) = std::env::var("VKVCM_BENCH_LOCAL_SIZE") {
        opts.local_size = s.parse().expect("VKVCM_BENCH_LOCAL_SIZE");
    }
    let gpu_opts = GpuOptions::from_env(std::env::var("VKVCM_TEST_DEVICE").ok());
    let gpu = Gpu::new(&GpuOptions { kernel_cache: None, ..gpu_opts }).unwrap(); // not the user's cache
    for name in scenes.split(',') {
        let scene = bench_scene(name).unwrap_or_else(|| panic!("unknown scene {name}"));
        let report = bench_traverse(&gpu, &scene, &opts).unwrap();
        println!("{report}");
        for s in &report.sets {
            assert_eq!(s.mismatches, 0, "GPU and CPU traversal disagree on {name}");
        }
    }
}
