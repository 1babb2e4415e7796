//! In-place exclusive prefix sum of the first `n` `u32`s of a buffer, on the GPU, for any
//! `n` >= 1 the buffer range allows (sums wrap modulo 2^32): a building block of the grid
//! build and of the light-vertex cache, recorded into the pass that uses it. A multi-level
//! scan (glsl/exclusive_scan.comp): each level scans blocks of [`SCAN_BLOCK`] elements in
//! shared memory and writes the block totals to the next level, until one block remains;
//! then the scanned totals are added back down. No subgroup operations (any subgroup
//! width).

use std::sync::Arc;

use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};

use crate::gpu::{fold_groups, Batch, Bind, Buffer, Gpu, Kernel};
use crate::render::sizes::BufferSize;
use crate::render::variants::{workgroup_defines, WORKGROUP_SIZE};

/// Elements each invocation of exclusive_scan.comp scans (`PER_THREAD`).
const ELEMENTS_PER_INVOCATION: u32 = 4;
/// Elements per block (one workgroup).
pub const SCAN_BLOCK: u32 = WORKGROUP_SIZE * ELEMENTS_PER_INVOCATION;

/// Push constants of exclusive_scan.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct ScanPush {
    n: u32,
    offset: u32,
    sums_offset: u32,
    _pad: u32,
}

/// One level of the scan: `n` elements at element `offset` (of the target buffer for
/// level 0, of the scratch buffer above).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Level {
    pub n: u32,
    pub offset: u32,
}

/// The levels of a scan of `n` elements and the size of its scratch buffer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScanPlan {
    /// levels[0] is the input; each next level holds the previous one's block totals;
    /// the last holds one element (the grand total, never scanned).
    pub levels: Vec<Level>,
    /// The block totals of every level above the input.
    pub scratch: BufferSize,
}

impl ScanPlan {
    /// The scan of `n` (>= 1) elements, with its scratch buffer called `scratch_name`.
    pub fn new(n: u32, scratch_name: &'static str) -> ScanPlan {
        let mut levels = vec![Level { n: n.max(1), offset: 0 }];
        let mut scratch_len = 0u32;
        loop {
            let next = levels.last().unwrap().n.div_ceil(SCAN_BLOCK);
            levels.push(Level { n: next, offset: scratch_len });
            scratch_len += next;
            if next == 1 {
                break;
            }
        }
        ScanPlan { levels, scratch: BufferSize::new(scratch_name, scratch_len as u64 * 4) }
    }
}

/// The scan of one buffer, prepared once (kernels and scratch).
pub struct ExclusiveScan {
    scan_target: Kernel,
    add_target: Kernel,
    scan_scratch: Kernel,
    add_scratch: Kernel,
    levels: Vec<Level>,
    scratch: Buffer,
}

impl ExclusiveScan {
    /// Prepares the scan of `data[0..n]` with the plan of [`ScanPlan::new`].
    pub fn new(gpu: &Arc<Gpu>, data: &Buffer, n: u32) -> Result<ExclusiveScan> {
        if n == 0 {
            bail!("exclusive scan of zero elements");
        }
        Self::with_plan(gpu, data, &ScanPlan::new(n, "scan_scratch"))
    }

    /// Prepares the scan that `plan` describes over `data`.
    pub fn with_plan(gpu: &Arc<Gpu>, data: &Buffer, plan: &ScanPlan) -> Result<ExclusiveScan> {
        let n = plan.levels[0].n;
        if data.size() < 4 * n as u64 {
            bail!("exclusive scan of {n} elements but buffer {:?} holds {} bytes", data.name(), data.size());
        }
        let scratch = plan.scratch.zeroed(gpu)?;
        let kernel = |add: bool, target: &Buffer| {
            let defines =
                workgroup_defines().flag("ADD", add).value("PER_THREAD", format!("{ELEMENTS_PER_INVOCATION}u"));
            gpu.kernel(
                "exclusive_scan.comp",
                &defines.pairs(),
                &[Bind::u32("scan_data", target), Bind::u32("scan_block_sums", &scratch)],
            )
        };
        Ok(ExclusiveScan {
            scan_target: kernel(false, data)?,
            add_target: kernel(true, data)?,
            scan_scratch: kernel(false, &scratch)?,
            add_scratch: kernel(true, &scratch)?,
            levels: plan.levels.clone(),
            scratch,
        })
    }

    /// Number of elements scanned.
    pub fn len(&self) -> u32 {
        self.levels[0].n
    }

    /// Always false (a scan has at least one element).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The scratch buffer of the block totals (for buffer listings).
    pub fn buffers(&self) -> Vec<&Buffer> {
        vec![&self.scratch]
    }

    /// Records the scan's dispatches (2 L - 1 for L levels of blocks) into the current
    /// pass of `batch`.
    pub fn record(&self, batch: &mut Batch) -> Result<()> {
        let scanned = self.levels.len() - 1;
        let push = |k: usize| ScanPush {
            n: self.levels[k].n,
            offset: self.levels[k].offset,
            sums_offset: self.levels[k + 1].offset,
            _pad: 0,
        };
        // One workgroup per block of SCAN_BLOCK elements.
        let groups = |k: usize| fold_groups(self.levels[k].n.div_ceil(SCAN_BLOCK));
        for k in 0..scanned {
            let kernel = if k == 0 { &self.scan_target } else { &self.scan_scratch };
            batch.dispatch(kernel, groups(k), bytemuck::bytes_of(&push(k)))?;
        }
        // The top scanned level is a single block, already final.
        for k in (0..scanned.saturating_sub(1)).rev() {
            let kernel = if k == 0 { &self.add_target } else { &self.add_scratch };
            batch.dispatch(kernel, groups(k), bytemuck::bytes_of(&push(k)))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_shrink_to_one_block() {
        let p = ScanPlan::new(1, "s");
        assert_eq!(p.levels, [Level { n: 1, offset: 0 }, Level { n: 1, offset: 0 }]);
        let p = ScanPlan::new(SCAN_BLOCK * SCAN_BLOCK + 1, "s");
        let ns: Vec<u32> = p.levels.iter().map(|l| l.n).collect();
        assert_eq!(ns, [SCAN_BLOCK * SCAN_BLOCK + 1, SCAN_BLOCK + 1, 2, 1]);
        assert_eq!(p.scratch.bytes, 4 * (SCAN_BLOCK as u64 + 1 + 2 + 1));
    }

    #[test]
    fn push_layout() {
        assert_eq!(std::mem::size_of::<ScanPush>(), 16);
    }
}
