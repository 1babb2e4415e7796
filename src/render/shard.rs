//! Shards: a render of I iterations split into N fixed, disjoint sets of global iteration
//! indices, each rendered anywhere and merged exactly (docs/distributed.md).
//!
//! An iteration's random numbers, merge radius and MIS factors follow from its global
//! index alone, and the film's fixed-point sums add exactly (src/render/film.rs), so the
//! merge of every shard is bit for bit the render of all I iterations on one device.
//! [`IterationSet`] is the set of global indices a film holds; [`Shard`] picks one.

use std::fmt;
use std::ops::Range;

use anyhow::{anyhow, bail, Result};

/// Shard `index` of `count` (`--shard K/N`): the `index`-th of `count` contiguous blocks
/// of iterations, as equal as whole iterations allow.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    /// The one shard of an unsplit render.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// `K/N` with 0 <= K < N.
    pub fn parse(s: &str) -> Result<Shard> {
        let (k, n) = s.split_once('/').ok_or_else(|| anyhow!("{s:?}: expected K/N, e.g. 0/4"))?;
        let k: u32 = k.trim().parse().map_err(|_| anyhow!("{s:?}: {k:?} is not a shard index"))?;
        let n: u32 = n.trim().parse().map_err(|_| anyhow!("{s:?}: {n:?} is not a shard count"))?;
        if n == 0 {
            bail!("{s:?}: the shard count must be at least 1");
        }
        if k >= n {
            bail!("{s:?}: the shard index must be below the count (0 to {})", n - 1);
        }
        Ok(Shard { index: k, count: n })
    }

    /// The global iteration indices of this shard of a render of `total` iterations:
    /// `[K I / N, (K + 1) I / N)`.
    pub fn range(self, total: u64) -> Range<u64> {
        let at = |k: u32| (total as u128 * k as u128 / self.count as u128) as u64;
        at(self.index)..at(self.index + 1)
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// A set of global iteration indices, as sorted, disjoint, non-adjacent ranges. Written
/// as `0-3,8-9` (inclusive ends); empty as `none`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct IterationSet {
    ranges: Vec<Range<u64>>,
}

impl IterationSet {
    pub fn new() -> IterationSet {
        IterationSet::default()
    }

    /// The iterations `r`.
    pub fn of(r: Range<u64>) -> IterationSet {
        let mut s = IterationSet::new();
        s.insert(r).expect("an empty set overlaps nothing");
        s
    }

    pub fn ranges(&self) -> &[Range<u64>] {
        &self.ranges
    }

    /// How many iterations.
    pub fn len(&self) -> u64 {
        self.ranges.iter().map(|r| r.end - r.start).sum()
    }

    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// One past the highest index (0 when empty).
    pub fn end(&self) -> u64 {
        self.ranges.last().map_or(0, |r| r.end)
    }

    /// Adds `r`; fails, naming the first shared index, if some of it is in the set.
    pub fn insert(&mut self, r: Range<u64>) -> Result<()> {
        if r.is_empty() {
            return Ok(());
        }
        if let Some(o) = self.ranges.iter().find(|o| o.start < r.end && r.start < o.end) {
            bail!("iteration {} is in both", o.start.max(r.start));
        }
        let at = self.ranges.partition_point(|o| o.start < r.start);
        self.ranges.insert(at, r);
        // Join adjacent ranges, so that equal sets compare equal.
        let mut joined: Vec<Range<u64>> = Vec::with_capacity(self.ranges.len());
        for r in self.ranges.drain(..) {
            match joined.last_mut() {
                Some(last) if last.end == r.start => last.end = r.end,
                _ => joined.push(r),
            }
        }
        self.ranges = joined;
        Ok(())
    }

    /// Adds every iteration of `other`; fails if the sets share one.
    pub fn union(&mut self, other: &IterationSet) -> Result<()> {
        for r in &other.ranges {
            self.insert(r.clone())?;
        }
        Ok(())
    }

    /// The iterations of `0..total` not in the set.
    pub fn missing(&self, total: u64) -> IterationSet {
        let mut m = IterationSet::new();
        let mut at = 0;
        for r in &self.ranges {
            if r.start > at {
                m.ranges.push(at..r.start.min(total));
            }
            at = at.max(r.end);
        }
        if at < total {
            m.ranges.push(at..total);
        }
        m.ranges.retain(|r| !r.is_empty());
        m
    }

    /// Parses what [`fmt::Display`] writes.
    pub fn parse(s: &str) -> Result<IterationSet> {
        let mut set = IterationSet::new();
        if s.trim() == "none" {
            return Ok(set);
        }
        for part in s.split(',') {
            let (a, b) = part.split_once('-').unwrap_or((part, part));
            let n = |x: &str| x.trim().parse::<u64>().map_err(|_| anyhow!("{s:?}: {part:?} is not a range A-B"));
            let (a, b) = (n(a)?, n(b)?);
            if b < a {
                bail!("{s:?}: {part:?} ends before it starts");
            }
            set.insert(a..b + 1).map_err(|e| anyhow!("{s:?}: {e}"))?;
        }
        Ok(set)
    }
}

impl fmt::Display for IterationSet {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        if self.ranges.is_empty() {
            return write!(f, "none");
        }
        let parts: Vec<String> = self
            .ranges
            .iter()
            .map(|r| if r.end - r.start == 1 { r.start.to_string() } else { format!("{}-{}", r.start, r.end - 1) })
            .collect();
        write!(f, "{}", parts.join(","))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cover_every_iteration_once() {
        for total in [1u64, 7, 16, 1000] {
            for n in [1u32, 2, 3, 7] {
                let mut all = IterationSet::new();
                for k in 0..n {
                    all.insert(Shard { index: k, count: n }.range(total)).unwrap();
                }
                assert_eq!(all, IterationSet::of(0..total), "{total} iterations in {n} shards");
            }
        }
    }

    #[test]
    fn sets_join_refuse_overlaps_and_round_trip() {
        let mut s = IterationSet::of(4..6);
        s.insert(0..2).unwrap();
        s.insert(2..4).unwrap();
        assert_eq!(s.to_string(), "0-5");
        assert!(s.insert(5..9).is_err());
        s.insert(8..9).unwrap();
        assert_eq!(s.to_string(), "0-5,8");
        assert_eq!(IterationSet::parse("0-5,8").unwrap(), s);
        assert_eq!(s.missing(11).to_string(), "6-7,9-10");
        assert_eq!(IterationSet::new().to_string(), "none");
        assert!(IterationSet::parse("none").unwrap().is_empty());
        assert!(Shard::parse("2/2").is_err() && Shard::parse("1/0").is_err() && Shard::parse("x").is_err());
        assert_eq!(Shard::parse("1/3").unwrap(), Shard { index: 1, count: 3 });
    }
}
