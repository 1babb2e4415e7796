//! The GPU hash grid (the grid-build pass, src/render/passes/hash_grid.rs, glsl/hash_grid*.{glsl,comp}) on
//! lavapipe (or VKVCM_TEST_DEVICE), validation on: the built structure against a CPU
//! counting sort, radius queries through hash_grid.glsl against CPU brute force, the
//! multi-level scan against a CPU scan, and (ignored by default) the build's speed.

mod common;

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Instant;

use common::with_gpu;
use rand::{Rng, SeedableRng};
use vkvcm::gpu::{groups_for, Bind, Buffer, Gpu, Profile};
use vkvcm::render::passes::exclusive_scan::ExclusiveScan;
use vkvcm::render::passes::hash_grid::HashGrid;

type Rng32 = rand_pcg::Pcg32;

// ---- CPU reference: the same f32 arithmetic as hash_grid.glsl ----

fn cpu_cell(p: [f32; 3], origin: [f32; 3], radius: f32) -> [i32; 3] {
    let inv = 1.0f32 / (2.0f32 * radius);
    let lim = 1_073_741_824.0f32;
    std::array::from_fn(|i| ((p[i] - origin[i]) * inv).floor().clamp(-lim, lim) as i32)
}

fn cpu_bucket(c: [i32; 3], num_buckets: u32) -> u32 {
    ((c[0] as u32).wrapping_mul(73_856_093)
        ^ (c[1] as u32).wrapping_mul(19_349_663)
        ^ (c[2] as u32).wrapping_mul(83_492_791))
        % num_buckets
}

fn dist2(p: [f32; 3], q: [f32; 3]) -> f32 {
    let d = [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
}

/// A light-vertex store as the light pass leaves it (src/render/passes/light_subpaths.rs):
/// light path p's vertices are `offsets[p] .. offsets[p + 1]`, position in lv_a[2 i].xyz;
/// past the total, up to the store's capacity, entries hold NaN or plausible garbage
/// (what an earlier iteration left: must be skipped).
struct Store {
    light_paths: u32,
    capacity: u64,
    lv_a: Vec<[f32; 4]>,
    offsets: Vec<u32>,
}

impl Store {
    /// The store of light paths with `counts[p]` vertices each, at `position(p, k)`, and
    /// `tail` garbage entries after them from `garbage(i)`.
    fn new(
        counts: &[u32],
        mut position: impl FnMut(u32, u32) -> [f32; 3],
        tail: u32,
        mut garbage: impl FnMut(u32) -> [f32; 3],
    ) -> Store {
        let mut offsets = vec![0u32];
        let mut lv_a = Vec::new();
        for (p, &n) in counts.iter().enumerate() {
            for k in 0..n {
                let q = position(p as u32, k);
                lv_a.extend([[q[0], q[1], q[2], 0.5], [0.25, 0.5, 0.75, f32::NAN]]);
            }
            offsets.push(offsets.last().unwrap() + n);
        }
        for i in 0..tail {
            let q = garbage(i);
            lv_a.extend([[q[0], q[1], q[2], 0.5], [f32::NAN; 4]]);
        }
        let capacity = (lv_a.len() / 2).max(1) as u64;
        lv_a.resize(2 * capacity as usize, [f32::NAN; 4]);
        Store { light_paths: counts.len() as u32, capacity, lv_a, offsets }
    }

    fn pos(&self, i: u32) -> [f32; 3] {
        let a = self.lv_a[2 * i as usize];
        [a[0], a[1], a[2]]
    }

    /// The stored vertices' indices.
    fn valid_slots(&self) -> Vec<u32> {
        (0..self.offsets[self.light_paths as usize]).collect()
    }

    fn upload(&self, gpu: &Arc<Gpu>) -> (Buffer, Buffer) {
        (gpu.buffer_from_slice("lv_a", &self.lv_a).unwrap(), gpu.buffer_from_slice("offsets", &self.offsets).unwrap())
    }

    fn grid(&self, gpu: &Arc<Gpu>, lv_a: &Buffer, offsets: &Buffer, num_buckets: u32) -> HashGrid {
        HashGrid::new(gpu, lv_a, offsets, self.light_paths, self.capacity, num_buckets).unwrap()
    }
}

/// Random store: path counts (0 to `slots`) include zeros and full paths; positions are
/// uniform in a box, exactly on cell boundaries (multiples of 2r from the origin on some
/// axes), or in one dense cell; the garbage after the stored vertices is NaN or a
/// plausible position.
fn random_store(rng: &mut Rng32, origin: [f32; 3], radius: f32, light_paths: u32, slots: u32) -> Store {
    let cell = 2.0 * radius;
    let cluster_cell = [rng.random_range(0..20), rng.random_range(0..20), rng.random_range(0..20)];
    let counts: Vec<u32> =
        (0..light_paths).map(|_| if rng.random_bool(0.2) { 0 } else { rng.random_range(0..=slots) }).collect();
    let mut positions = Vec::new();
    for _ in counts.iter().flat_map(|&n| 0..n) {
        positions.push(match rng.random_range(0..10) {
            0..6 => std::array::from_fn(|i| origin[i] + rng.random_range(-0.1..1.2f32)),
            6..8 => std::array::from_fn(|i| {
                if rng.random_bool(0.6) {
                    origin[i] + cell * rng.random_range(-2..40) as f32
                } else {
                    origin[i] + rng.random_range(0.0..1.0f32)
                }
            }),
            _ => std::array::from_fn(|i| origin[i] + cell * (cluster_cell[i] as f32 + rng.random_range(0.0..1.0f32))),
        });
    }
    let garbage: Vec<[f32; 3]> = (0..light_paths)
        .map(|_| {
            if rng.random_bool(0.5) {
                [f32::NAN; 3]
            } else {
                std::array::from_fn(|i| origin[i] + rng.random_range(0.0..1.0f32))
            }
        })
        .collect();
    let mut next = positions.into_iter();
    Store::new(&counts, |_, _| next.next().unwrap(), light_paths, |i| garbage[i as usize])
}

/// The grid after a build: cell_start, the vertex indices of cell_points
/// (cell_points[i].w), and cell_points.
type Built = (Vec<u32>, Vec<u32>, Vec<[u32; 4]>);

fn build(gpu: &Arc<Gpu>, grid: &HashGrid, radius: f32, origin: [f32; 3]) -> Built {
    let mut batch = gpu.batch().unwrap();
    grid.record_build(&mut batch, radius, origin).unwrap();
    batch.submit_wait(None).unwrap();
    let points: Vec<[u32; 4]> = grid.cell_points.read().unwrap();
    (grid.cell_start.read().unwrap(), points.iter().map(|p| p[3]).collect(), points)
}

/// cell_points[i] = (position bits, slot) of its slot, for every used entry (the camera
/// kernel reads positions from there, not from the store).
fn check_points(store: &Store, start: &[u32], idx: &[u32], points: &[[u32; 4]]) {
    let used = *start.last().unwrap() as usize;
    for (i, (&s, pt)) in idx[..used].iter().zip(&points[..used]).enumerate() {
        let p = store.pos(s);
        assert_eq!(*pt, [p[0].to_bits(), p[1].to_bits(), p[2].to_bits(), s], "cell_points[{i}] (slot {s})");
    }
}

/// (a): cell_start is the exclusive scan of the CPU bucket sizes; every valid slot is
/// listed exactly once, in its CPU bucket; buckets ascending; cell_points matches.
fn check_structure(store: &Store, num_buckets: u32, radius: f32, origin: [f32; 3], built: &Built) {
    let (start, idx, points) = built;
    check_points(store, start, idx, points);
    let valid = store.valid_slots();
    let mut counts = vec![0u32; num_buckets as usize];
    let mut bucket_of = HashMap::new();
    for &s in &valid {
        let b = cpu_bucket(cpu_cell(store.pos(s), origin, radius), num_buckets);
        counts[b as usize] += 1;
        bucket_of.insert(s, b);
    }
    assert_eq!(start.len(), num_buckets as usize + 1);
    let mut acc = 0u32;
    for b in 0..num_buckets as usize {
        assert_eq!(start[b], acc, "cell_start[{b}]");
        acc += counts[b];
    }
    assert_eq!(start[num_buckets as usize], valid.len() as u32, "total");
    for b in 0..num_buckets {
        let list = &idx[start[b as usize] as usize..start[b as usize + 1] as usize];
        for w in list.windows(2) {
            assert!(w[0] < w[1], "bucket {b} not strictly ascending: {list:?}");
        }
        for s in list {
            assert_eq!(bucket_of.get(s), Some(&b), "slot {s} listed in bucket {b}");
        }
    }
    // Counts match per bucket, lists are duplicate-free and hold only valid slots of that
    // bucket: so every valid slot appears exactly once.
}

#[test]
fn build_matches_cpu_counting_sort_and_is_deterministic() {
    with_gpu(|gpu| {
        let mut rng = Rng32::seed_from_u64(0x5eed_0001);
        // (radius, origin): a power of two (boundary points exact) and arbitrary values.
        let cases = [(0.03125f32, [-0.5f32, 0.25, -1.0]), (0.0137f32, [0.1234f32, -0.77, 0.5012])];
        for (case, &(radius, origin)) in cases.iter().enumerate() {
            let light_paths = rng.random_range(500..3000);
            let slots = rng.random_range(1..=9);
            let store = random_store(&mut rng, origin, radius, light_paths, slots);
            let (lv_a, offsets) = store.upload(gpu);
            // Default table size, a small prime (many collisions), one bucket, and many.
            for num_buckets in [light_paths, 97, 1, 1 << 20] {
                let grid = store.grid(gpu, &lv_a, &offsets, num_buckets);
                assert_eq!(grid.num_buckets(), num_buckets);
                let built = build(gpu, &grid, radius, origin);
                check_structure(&store, num_buckets, radius, origin, &built);
                let start = &built.0;
                let biggest = (0..num_buckets as usize).map(|b| start[b + 1] - start[b]).max().unwrap();
                eprintln!(
                    "case {case}: {light_paths} paths x {slots} slots, {} vertices, {num_buckets} buckets, largest bucket {biggest}",
                    start[num_buckets as usize]
                );
                // Rebuild after a build at another radius (stale state must not leak in).
                let _ = build(gpu, &grid, radius * 3.0, origin);
                let (start2, idx2, points2) = build(gpu, &grid, radius, origin);
                assert_eq!(*start, start2);
                let n = start[num_buckets as usize] as usize;
                assert_eq!(built.1[..n], idx2[..n], "second build differs");
                assert_eq!(built.2[..n], points2[..n], "second build's points differ");
            }
        }
    });
}

#[test]
fn build_handles_empty_and_full_stores() {
    with_gpu(|gpu| {
        let mut rng = Rng32::seed_from_u64(3);
        let (radius, origin) = (0.05f32, [0.0f32; 3]);
        for fill in [0u32, 4] {
            let counts = vec![fill; 300];
            let uniform = |_, _| std::array::from_fn(|_| rng.random_range(0.0..1.0f32));
            let store = Store::new(&counts, uniform, 0, |_| [f32::NAN; 3]);
            let (lv_a, offsets) = store.upload(gpu);
            let grid = store.grid(gpu, &lv_a, &offsets, 300);
            let built = build(gpu, &grid, radius, origin);
            check_structure(&store, 300, radius, origin, &built);
            assert_eq!(built.0[300], 300 * fill);
        }
    });
}

#[test]
fn new_and_build_reject_bad_arguments() {
    with_gpu(|gpu| {
        let lv_a = gpu.buffer_zeroed::<[f32; 4]>("lv_a", 2 * 40).unwrap();
        let offsets = gpu.buffer_zeroed::<u32>("offsets", 11).unwrap();
        assert!(HashGrid::new(gpu, &lv_a, &offsets, 0, 40, 10).is_err());
        assert!(HashGrid::new(gpu, &lv_a, &offsets, 10, 40, 0).is_err());
        assert!(HashGrid::new(gpu, &lv_a, &offsets, 10, 0, 10).is_err());
        let e = HashGrid::new(gpu, &lv_a, &offsets, 10, 41, 10).err().unwrap().to_string();
        assert!(e.contains("lv_a"), "{e}");
        let e = HashGrid::new(gpu, &lv_a, &offsets, 11, 40, 10).err().unwrap().to_string();
        assert!(e.contains("offsets"), "{e}");
        let e = HashGrid::new(gpu, &lv_a, &offsets, 10, 40, u32::MAX - 1).err().unwrap().to_string();
        assert!(e.contains("maxStorageBufferRange"), "{e}");
        let grid = HashGrid::new(gpu, &lv_a, &offsets, 10, 40, 10).unwrap();
        let mut batch = gpu.batch().unwrap();
        assert!(grid.record_build(&mut batch, 0.0, [0.0; 3]).is_err());
        assert!(grid.record_build(&mut batch, f32::NAN, [0.0; 3]).is_err());
        assert!(grid.record_build(&mut batch, 0.1, [f32::INFINITY, 0.0, 0.0]).is_err());
    });
}

/// The sort pass on its own with adversarial input (the build's atomics often deliver a
/// bucket nearly in order on lavapipe): random permutations, descending runs, bucket
/// sizes 0..=40 across the sorting networks' limits (4, 16) and the insertion-sort limit
/// (32), and a few large (heapsort) ones.
#[test]
fn sort_pass_sorts_every_bucket() {
    with_gpu(|gpu| {
        let mut rng = Rng32::seed_from_u64(0x5eed_0005);
        let mut sizes: Vec<u32> = (0..5000).map(|_| rng.random_range(0..=40)).collect();
        sizes.extend([31, 32, 33, 64, 1000, 4097]);
        let nb = sizes.len() as u32;
        let total: u32 = sizes.iter().sum();
        let mut values: Vec<u32> = (0..total).map(|i| i * 3 + 7).collect();
        // Shuffle globally, then make some buckets descending.
        for i in (1..values.len()).rev() {
            values.swap(i, rng.random_range(0..=i));
        }
        let mut start = vec![0u32];
        for &n in &sizes {
            start.push(start.last().unwrap() + n);
        }
        for b in 0..nb as usize {
            if b % 3 == 0 {
                values[start[b] as usize..start[b + 1] as usize].sort_unstable_by(|a, b| b.cmp(a));
            }
        }
        let sb = gpu.buffer_from_slice("start", &start).unwrap();
        // Entry of slot s: (position (s, s / 2, -s) as bits, s); the pass must move the
        // position with its slot.
        let entry = |s: u32| {
            let p = [s as f32, s as f32 * 0.5, -(s as f32)];
            [p[0].to_bits(), p[1].to_bits(), p[2].to_bits(), s]
        };
        let input: Vec<[u32; 4]> = values.iter().map(|&s| entry(s)).collect();
        let pb = gpu.buffer_from_slice("points", &input).unwrap();
        let k = gpu
            .kernel(
                "hash_grid_sort.comp",
                &[("WORKGROUP_SIZE", "64"), ("DEVICE_ADDRESSES", "0")],
                &[Bind::u32("grid_start", &sb), Bind::vec4("grid_points", &pb)],
            )
            .unwrap();
        // BuildPush: origin, radius, light paths, capacity, buckets, pad.
        let push: [u32; 8] = [0, 0, 0, 0, 1, 1, nb, 0];
        let mut batch = gpu.batch().unwrap();
        batch.dispatch(&k, [groups_for(nb, 64), 1, 1], bytemuck::cast_slice(&push)).unwrap();
        batch.submit_wait(None).unwrap();
        let points: Vec<[u32; 4]> = pb.read().unwrap();
        for (i, pt) in points.iter().enumerate() {
            assert_eq!(*pt, entry(pt[3]), "points[{i}]");
        }
        for b in 0..nb as usize {
            let r = start[b] as usize..start[b + 1] as usize;
            let mut want = values[r.clone()].to_vec();
            want.sort_unstable();
            let got: Vec<u32> = points[r].iter().map(|p| p[3]).collect();
            assert_eq!(got, want, "bucket {b} of {} entries", sizes[b]);
        }
    });
}

/// Query points: random in and around the box, on cell faces/edges/corners and centres,
/// at and near vertices (distances around r), in the dense cell.
fn query_points(rng: &mut Rng32, store: &Store, origin: [f32; 3], radius: f32) -> Vec<[f32; 4]> {
    let cell = 2.0 * radius;
    let valid = store.valid_slots();
    let mut q = Vec::new();
    for i in 0..3000 {
        let p: [f32; 3] = match i % 5 {
            0 => std::array::from_fn(|a| origin[a] + rng.random_range(-0.2..1.3f32)),
            1 => std::array::from_fn(|a| {
                let k = rng.random_range(-2..40) as f32;
                match rng.random_range(0..3) {
                    0 => origin[a] + cell * k,
                    1 => origin[a] + cell * k + radius,
                    _ => origin[a] + rng.random_range(0.0..1.0f32),
                }
            }),
            2 => store.pos(valid[rng.random_range(0..valid.len())]),
            _ => {
                // At distance ~r (0.8r..1.2r) from a vertex, in a random direction.
                let v = store.pos(valid[rng.random_range(0..valid.len())]);
                let d: [f32; 3] = std::array::from_fn(|_| rng.random_range(-1.0..1.0f32));
                let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(1e-3);
                let s = radius * rng.random_range(0.8..1.2f32) / len;
                std::array::from_fn(|a| v[a] + d[a] * s)
            }
        };
        q.push([p[0], p[1], p[2], 0.0]);
    }
    q
}

#[test]
fn queries_find_exactly_the_vertices_within_radius() {
    with_gpu(|gpu| {
        let mut rng = Rng32::seed_from_u64(0x5eed_0002);
        let cases = [(0.03125f32, [-0.5f32, 0.25, -1.0]), (0.0137f32, [0.1234f32, -0.77, 0.5012])];
        let mut total_ties = 0;
        let mut total_found = 0usize;
        for &(radius, origin) in &cases {
            let light_paths = rng.random_range(1000..3000);
            let slots = rng.random_range(2..=9);
            let store = random_store(&mut rng, origin, radius, light_paths, slots);
            let (lv_a, offsets) = store.upload(gpu);
            let queries = query_points(&mut rng, &store, origin, radius);
            let nq = queries.len() as u32;
            // CPU brute force first, to size the output.
            let valid = store.valid_slots();
            let r2 = radius * radius;
            let want: Vec<Vec<u32>> = queries
                .iter()
                .map(|q| {
                    let q = [q[0], q[1], q[2]];
                    valid.iter().copied().filter(|&s| dist2(store.pos(s), q) <= r2).collect()
                })
                .collect();
            let max_out = want.iter().map(Vec::len).max().unwrap() as u32 + 64;
            let qbuf = gpu.buffer_from_slice("queries", &queries).unwrap();
            let count = gpu.buffer_zeroed::<u32>("count", nq as usize).unwrap();
            let slots_out = gpu.buffer_zeroed::<u32>("slots", (nq * max_out) as usize).unwrap();
            let stats = gpu.buffer_zeroed::<[u32; 2]>("stats", nq as usize).unwrap();
            for num_buckets in [light_paths, 7, 1] {
                let grid = store.grid(gpu, &lv_a, &offsets, num_buckets);
                let k = gpu
                    .kernel(
                        "tests/hash_grid_query.comp",
                        &[],
                        &[
                            Bind::u32("grid_start", &grid.cell_start),
                            Bind::vec4("grid_points", &grid.cell_points),
                            Bind::vec4("queries", &qbuf),
                            Bind::vec4("out_count", &count),
                            Bind::vec4("out_slots", &slots_out),
                            Bind::vec4("out_stats", &stats),
                        ],
                    )
                    .unwrap();
                let mut push = Vec::new();
                push.extend_from_slice(bytemuck::cast_slice(&origin));
                push.extend_from_slice(bytemuck::bytes_of(&radius));
                push.extend_from_slice(bytemuck::cast_slice(&[num_buckets, nq, max_out]));
                let mut batch = gpu.batch().unwrap();
                grid.record_build(&mut batch, radius, origin).unwrap();
                batch.dispatch(&k, [groups_for(nq, 64), 1, 1], &push).unwrap();
                batch.submit_wait(None).unwrap();
                let got_count: Vec<u32> = count.read().unwrap();
                let got_slots: Vec<u32> = slots_out.read().unwrap();
                let got_stats: Vec<[u32; 2]> = stats.read().unwrap();
                for qi in 0..nq as usize {
                    let q = [queries[qi][0], queries[qi][1], queries[qi][2]];
                    let n = got_count[qi] as usize;
                    assert!(n <= max_out as usize);
                    let [visited, tested] = got_stats[qi];
                    assert!((1..=8.min(num_buckets)).contains(&visited), "query {qi}: {visited} buckets visited");
                    assert!(tested as usize >= n);
                    let mut got = got_slots[qi * max_out as usize..][..n].to_vec();
                    got.sort_unstable();
                    for w in got.windows(2) {
                        assert!(w[0] != w[1], "query {qi}: slot {} found twice (bucket visited twice?)", w[0]);
                    }
                    let mut expect = want[qi].clone();
                    expect.sort_unstable();
                    if got != expect {
                        // Only ties at distance r within float rounding may differ.
                        let diff = got
                            .iter()
                            .filter(|s| expect.binary_search(s).is_err())
                            .chain(expect.iter().filter(|s| got.binary_search(s).is_err()));
                        for &s in diff {
                            let d2 = dist2(store.pos(s), q);
                            assert!(
                                (d2 - r2).abs() <= 1e-5 * r2,
                                "query {qi} at {q:?} (r {radius}, {num_buckets} buckets): slot {s} at {:?}, d^2 {d2} vs r^2 {r2}: \
                                 GPU found {} vertices, CPU {}",
                                store.pos(s),
                                got.len(),
                                expect.len()
                            );
                            total_ties += 1;
                        }
                    }
                    total_found += n;
                }
            }
        }
        eprintln!("{total_found} vertices found in all queries; {total_ties} differ only by rounding at distance r");
        assert!(total_found > 10_000, "queries found too little to be a test: {total_found}");
    });
}

fn check_scan(gpu: &Arc<Gpu>, rng: &mut Rng32, n: u32, extra: u32, full_range: bool) {
    let data: Vec<u32> =
        (0..n + extra).map(|_| if full_range { rng.random() } else { rng.random_range(0..16) }).collect();
    let buf = gpu.buffer_from_slice("scan", &data).unwrap();
    let scan = ExclusiveScan::new(gpu, &buf, n).unwrap();
    assert_eq!(scan.len(), n);
    let mut batch = gpu.batch().unwrap();
    scan.record(&mut batch).unwrap();
    batch.submit_wait(None).unwrap();
    let got: Vec<u32> = buf.read().unwrap();
    let mut acc = 0u32;
    for i in 0..n as usize {
        assert_eq!(got[i], acc, "scan of {n}: element {i}");
        acc = acc.wrapping_add(data[i]);
    }
    assert_eq!(got[n as usize..], data[n as usize..], "scan of {n} wrote past its range");
    // Scanning again scans the scanned data (the recorded batch is reusable).
    scan.record(&mut batch).unwrap();
    batch.submit_wait(None).unwrap();
    let again: Vec<u32> = buf.read().unwrap();
    let mut acc = 0u32;
    for i in 0..n as usize {
        assert_eq!(again[i], acc, "second scan of {n}: element {i}");
        acc = acc.wrapping_add(got[i]);
    }
}

#[test]
fn scan_matches_cpu_on_edge_sizes() {
    with_gpu(|gpu| {
        let mut rng = Rng32::seed_from_u64(0x5eed_0003);
        for n in [1u32, 2, 63, 64, 65, 255, 256, 257, 4095, 4096, 4097, 65_536, 65_537, (1 << 20) + 3] {
            check_scan(gpu, &mut rng, n, if n % 2 == 1 { 5 } else { 0 }, false);
        }
        // Wrapping sums modulo 2^32.
        check_scan(gpu, &mut rng, 100_000, 3, true);
        assert!(ExclusiveScan::new(gpu, &gpu.buffer_zeroed::<u32>("z", 4).unwrap(), 5).is_err());
        assert!(ExclusiveScan::new(gpu, &gpu.buffer_zeroed::<u32>("z", 4).unwrap(), 0).is_err());
    });
}

#[test]
fn scan_handles_four_million_buckets() {
    with_gpu(|gpu| {
        // 2^22 buckets + the total: three levels of blocks.
        let mut rng = Rng32::seed_from_u64(0x5eed_0004);
        check_scan(gpu, &mut rng, (1 << 22) + 1, 0, false);
    });
}

/// User + system CPU seconds of this process, all threads (lavapipe's workers included),
/// from /proc/self/stat; NaN where that does not exist.
fn process_cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = &stat[stat.rfind(')').unwrap_or(0) + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = f[11].parse::<f64>().unwrap_or(f64::NAN) + f[12].parse::<f64>().unwrap_or(f64::NAN);
    ticks / 100.0 // USER_HZ, 100 on Linux
}

/// Build speed for about a million light vertices, SmallVCM-like: 2^18 light paths (a
/// 512x512 image), 9 slots, 1..7 vertices per path, on the faces of a 2x2x2 box, radius
/// 0.003 x the bounding-sphere radius. Run with
/// `cargo test --test hash_grid -- --ignored --nocapture build_speed` (GPU time does not
/// depend on the Rust profile).
#[test]
#[ignore = "timing; run explicitly"]
fn build_speed_one_million_vertices() {
    with_gpu(|gpu| {
        let mut rng = Rng32::seed_from_u64(9);
        let (light_paths, slots) = (1u32 << 18, 9u32);
        let radius = 0.003 * 3f32.sqrt();
        let origin = [-1.0f32; 3];
        let counts: Vec<u32> = (0..light_paths).map(|_| rng.random_range(1..=7)).collect();
        let on_box_face = |_, _| {
            let axis = rng.random_range(0..3);
            let mut pos: [f32; 3] = std::array::from_fn(|_| rng.random_range(-1.0..1.0f32));
            pos[axis] = if rng.random_bool(0.5) { -1.0 } else { 1.0 };
            pos
        };
        let store = Store::new(&counts, on_box_face, 0, |_| [f32::NAN; 3]);
        let vertices = store.capacity;
        let (lv_a, offsets) = store.upload(gpu);
        let grid = store.grid(gpu, &lv_a, &offsets, light_paths);
        let mut batch = gpu.batch().unwrap();
        grid.record_build(&mut batch, radius, origin).unwrap(); // warm-up (pipeline compiles)
        batch.submit_wait(None).unwrap();
        // Minimum over runs of each pass (robust to other load on the machine).
        let runs = 15;
        let min_ms = |profiles: &[Profile], name: &str| {
            profiles
                .iter()
                .map(|p| p.kernels.iter().filter(|k| k.kernel == name).map(|k| k.total_ms).sum::<f64>())
                .fold(f64::INFINITY, f64::min)
        };
        let mut builds = Vec::new();
        let mut walls = Vec::new();
        let cpu0 = process_cpu_seconds();
        for _ in 0..runs {
            let mut p = Profile::default();
            let t = Instant::now();
            grid.record_build(&mut batch, radius, origin).unwrap();
            batch.submit_wait(Some(&mut p)).unwrap();
            walls.push(t.elapsed().as_secs_f64() * 1e3);
            builds.push(p);
        }
        let cpu_ms = (process_cpu_seconds() - cpu0) * 1e3 / runs as f64;
        let build_total = builds.iter().map(|p| p.total_ms()).fold(f64::INFINITY, f64::min);
        let wall = walls.iter().copied().fold(f64::INFINITY, f64::min);
        let m = vertices as f64 / 1e6;
        eprintln!("{}", builds[0].table());
        eprintln!(
            "per build (min of {runs}): count {:.2} ms, scan {:.2} ms, scatter {:.2} ms, sort {:.2} ms",
            min_ms(&builds, "hash_grid_count.comp"),
            min_ms(&builds, "exclusive_scan.comp"),
            min_ms(&builds, "hash_grid_scatter.comp"),
            min_ms(&builds, "hash_grid_sort.comp"),
        );
        eprintln!(
            "hash-grid build: {vertices} vertices ({light_paths} paths x {slots} slots, {} buckets) on {}: \
             {build_total:.2} ms in kernels ({:.2} ms per million vertices), {wall:.2} ms per submit incl. fills \
             (min of {runs}); {cpu_ms:.1} CPU-ms per build (mean, all threads)",
            grid.num_buckets(),
            gpu.info.name,
            build_total / m
        );
    });
}
