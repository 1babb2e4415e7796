//! An environment map in the form glsl/environment.glsl reads: texels with the sampling
//! pdf of their cell, and a piecewise-constant 2D distribution (a marginal CDF over rows
//! of cells, a conditional CDF per row; pbrt-v4's `PiecewiseConstant2D`, Pharr et al.,
//! "Physically Based Rendering", 4th ed., A.5.6).
//!
//! Cell (i, j), i < W, j < H - 1, is the bilinear patch between texels (i, j) and
//! (i + 1 mod W, j + 1); its weight is the mean luminance of its four texels times
//! sin(theta) at its centre, so it is positive wherever the bilinear radiance is, and its
//! pdf in (u, v) is weight / (sum of weights * cell area). The CPU functions [`pdf_uv`]
//! and [`sample_uv`] mirror the GLSL for tests.

use crate::scene::environment::{luminance, EnvironmentMap};

/// The two buffers of an environment map.
pub struct EnvironmentTables {
    /// `(r, g, b, pdf_uv of cell (i, j))` per texel, row-major; the last row's pdf is 0.
    pub texels: Vec<[f32; 4]>,
    /// `H` entries of the marginal CDF over the `H - 1` rows of cells, then per row
    /// `W + 1` entries of its conditional CDF; each starts at 0 and ends at 1.
    pub distribution: Vec<f32>,
}

fn cell_weight(map: &EnvironmentMap, i: u32, j: u32) -> f64 {
    let i1 = (i + 1) % map.width;
    let mean = [map.texel(i, j), map.texel(i1, j), map.texel(i, j + 1), map.texel(i1, j + 1)]
        .iter()
        .map(|&t| luminance(t) as f64)
        .sum::<f64>()
        * 0.25;
    let theta = (j as f64 + 0.5) / (map.height - 1) as f64 * std::f64::consts::PI;
    mean * theta.sin()
}

/// A CDF over `weights` (n + 1 entries, 0 to 1); uniform where every weight is 0. Sums in
/// f64 so that the last entries of long rows keep their resolution.
fn cdf(weights: &[f64]) -> (Vec<f32>, f64) {
    let total: f64 = weights.iter().sum();
    let n = weights.len();
    let mut out = Vec::with_capacity(n + 1);
    out.push(0.0);
    let mut acc = 0.0;
    for (k, w) in weights.iter().enumerate() {
        acc += w;
        out.push(if total > 0.0 { (acc / total) as f32 } else { (k + 1) as f32 / n as f32 });
    }
    *out.last_mut().unwrap() = 1.0;
    (out, total)
}

impl EnvironmentTables {
    pub fn new(map: &EnvironmentMap) -> EnvironmentTables {
        let (w, h) = (map.width, map.height);
        let rows = h - 1;
        let weights: Vec<Vec<f64>> = (0..rows).map(|j| (0..w).map(|i| cell_weight(map, i, j)).collect()).collect();
        let row_sums: Vec<f64> = weights.iter().map(|r| r.iter().sum()).collect();
        let (marginal, total) = cdf(&row_sums);
        let mut distribution = marginal;
        for r in &weights {
            distribution.extend(cdf(r).0);
        }
        // pdf_uv = weight / (total * cell area), cell area = 1 / (W (H - 1)).
        let cells = w as f64 * rows as f64;
        let mut texels: Vec<[f32; 4]> = map.texels.iter().map(|t| [t[0], t[1], t[2], 0.0]).collect();
        if total > 0.0 {
            for j in 0..rows {
                for i in 0..w {
                    texels[(j * w + i) as usize][3] = (weights[j as usize][i as usize] / total * cells) as f32;
                }
            }
        }
        EnvironmentTables { texels, distribution }
    }

    /// The pdf in (u, v) of cell (i, j) (what the GLSL reads from texel (i, j)'s alpha).
    pub fn pdf_uv(&self, width: u32, i: u32, j: u32) -> f32 {
        self.texels[(j * width + i) as usize][3]
    }

    /// The (u, v) that the GLSL's env_sample draws from the random pair `rnd`
    /// (x: column, y: row), and its cell.
    pub fn sample_uv(&self, width: u32, height: u32, rnd: [f32; 2]) -> ([f32; 2], [u32; 2]) {
        let rows = height - 1;
        let find = |first: usize, n: u32, x: f32| -> u32 {
            let (mut lo, mut hi) = (0u32, n - 1);
            while lo < hi {
                let mid = (lo + hi) / 2;
                if self.distribution[first + mid as usize + 1] > x {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            lo
        };
        let j = find(0, rows, rnd[1]);
        let (r0, r1) = (self.distribution[j as usize], self.distribution[j as usize + 1]);
        let ty = ((rnd[1] - r0) / (r1 - r0).max(1e-30)).clamp(0.0, 1.0);
        let row = (height + j * (width + 1)) as usize;
        let i = find(row, width, rnd[0]);
        let (c0, c1) = (self.distribution[row + i as usize], self.distribution[row + i as usize + 1]);
        let tx = ((rnd[0] - c0) / (c1 - c0).max(1e-30)).clamp(0.0, 1.0);
        let u = (i as f32 + 0.5 + tx) / width as f32;
        let v = (j as f32 + ty) / rows as f32;
        ([u - u.floor(), v], [i, j])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gradient_with_spot() -> EnvironmentMap {
        let (w, h) = (16u32, 9u32);
        let mut t = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let spot = if (x, y) == (5, 2) { 500.0 } else { 0.0 };
                t.push([0.1 + y as f32 * 0.05 + spot, 0.2, 0.3 + x as f32 * 0.01]);
            }
        }
        EnvironmentMap::new("test", w, h, t).unwrap()
    }

    /// The cell pdfs integrate to 1 over the unit square (each cell has area 1/(W(H-1))).
    #[test]
    fn pdf_integrates_to_one() {
        let m = gradient_with_spot();
        let t = EnvironmentTables::new(&m);
        let area = 1.0 / (m.width as f64 * (m.height - 1) as f64);
        let sum: f64 = (0..m.height - 1)
            .flat_map(|j| (0..m.width).map(move |i| (i, j)))
            .map(|(i, j)| t.pdf_uv(m.width, i, j) as f64 * area)
            .sum();
        assert!((sum - 1.0).abs() < 1e-5, "integral {sum}");
    }

    /// Drawn cells follow the pdf: a chi-square-free check, each cell's frequency within
    /// 5 standard deviations of its probability over 200k stratified draws.
    #[test]
    fn samples_follow_the_pdf() {
        let m = gradient_with_spot();
        let t = EnvironmentTables::new(&m);
        let n = 400u32;
        let mut counts = vec![0u32; (m.width * (m.height - 1)) as usize];
        for a in 0..n {
            for b in 0..n / 2 {
                let rnd = [(a as f32 + 0.5) / n as f32, (b as f32 + 0.5) / (n / 2) as f32];
                let (uv, [i, j]) = t.sample_uv(m.width, m.height, rnd);
                assert!((0.0..1.0).contains(&uv[0]) && (0.0..=1.0).contains(&uv[1]));
                counts[(j * m.width + i) as usize] += 1;
            }
        }
        let total = (n * n / 2) as f64;
        let area = 1.0 / (m.width as f64 * (m.height - 1) as f64);
        for j in 0..m.height - 1 {
            for i in 0..m.width {
                let p = t.pdf_uv(m.width, i, j) as f64 * area;
                let f = counts[(j * m.width + i) as usize] as f64 / total;
                let sd = (p * (1.0 - p) / total).sqrt().max(1e-6);
                assert!((f - p).abs() < 5.0 * sd + 1e-5, "cell ({i}, {j}): frequency {f} vs probability {p}");
            }
        }
    }

    /// A black map samples uniformly (the distribution never divides by zero).
    #[test]
    fn black_map_is_uniform() {
        let m = EnvironmentMap::constant(4, 3, [0.0; 3]);
        let t = EnvironmentTables::new(&m);
        assert!(t.distribution.iter().all(|x| x.is_finite()));
        assert!(t.texels.iter().all(|x| x[3] == 0.0));
    }
}
