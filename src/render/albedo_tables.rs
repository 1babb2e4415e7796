//! The texel buffers the kernels interpolate the lobes' directional albedos in, each a
//! fixed table (`Gpu::fixed_table`) of vec4 cells: `ggx_albedo_table` (glsl/bsdf.glsl,
//! ggx_albedo_terms) from src/render/ggx_albedo.rs, `sheen_albedo_table`
//! (glsl/lobes/sheen.glsl, sheen_albedo) from src/render/sheen_albedo.rs. Texel buffers:
//! on lavapipe they cost less than a storage buffer or a private GLSL array
//! (docs/performance.md, "Tried and not kept").

use super::ggx_albedo::{GGX_ALBEDO, GGX_ALBEDO_MU as MU, GGX_ALBEDO_R as R};
use super::sheen_albedo::{SHEEN_ALBEDO, SHEEN_ALBEDO_MU, SHEEN_ALBEDO_R};

/// `ggx_albedo_table`'s length in vec4s: a cell per pair of adjacent cosines and
/// roughness, then per pair of adjacent roughnesses a cell per cosine node (the
/// cumulative integrals, [`ggx_cumulative`]).
pub const GGX_CELLS: usize = (MU - 1) * R + MU * (R - 1);

/// Per cell (A, B) at cosine rows i and i + 1 of roughness j, (MU - 1) cells per roughness,
/// so that a bilinear lookup reads two texels (one per roughness); then per roughness
/// j < R - 1 and node i the cumulative integrals of (A, B) at roughnesses j and j + 1.
pub fn ggx_cells() -> Vec<[f32; 4]> {
    let pair = |p: [f32; 2], q: [f32; 2]| [p[0], p[1], q[0], q[1]];
    let table = (0..R).flat_map(|j| (0..MU - 1).map(move |i| pair(GGX_ALBEDO[j * MU + i], GGX_ALBEDO[j * MU + i + 1])));
    let cumulative: Vec<Vec<[f32; 2]>> = (0..R).map(|j| ggx_cumulative(&GGX_ALBEDO[j * MU..(j + 1) * MU])).collect();
    let cumulative = (0..R - 1).flat_map(|j| {
        let (lo, hi) = (cumulative[j].clone(), cumulative[j + 1].clone());
        (0..MU).map(move |i| pair(lo[i], hi[i]))
    });
    table.chain(cumulative).collect()
}

/// The cosine-weighted integrals 2 int_0^mu_i (A, B)(mu) mu dmu of one roughness's row at
/// its nodes mu_i = x_i^2, x_i = i / (MU - 1), exact for the kernels' interpolation (linear
/// in x = sqrt(mu) between nodes: 2 mu dmu = 4 x^3 dx): the diffuse lobe's sampling
/// inverts them (glsl/bsdf.glsl, sample_coupled_diffuse), and at the last node they are
/// the averages E_avg (ggx_albedo_average).
pub fn ggx_cumulative(row: &[[f32; 2]]) -> Vec<[f32; 2]> {
    let h = 1.0 / (MU - 1) as f64;
    // 4 int x^3 (x1 - x) / h dx and 4 int x^3 (x - x0) / h dx over [x0, x1].
    let weights = |x0: f64, x1: f64| {
        let p = |x: f64| x1 * x.powi(4) - 0.8 * x.powi(5);
        let q = |x: f64| 0.8 * x.powi(5) - x0 * x.powi(4);
        ((p(x1) - p(x0)) / h, (q(x1) - q(x0)) / h)
    };
    let mut sum = [0.0f64; 2];
    let mut out = vec![[0.0f32; 2]];
    for i in 0..MU - 1 {
        let (w0, w1) = weights(i as f64 * h, (i + 1) as f64 * h);
        for (k, s) in sum.iter_mut().enumerate() {
            *s += row[i][k] as f64 * w0 + row[i + 1][k] as f64 * w1;
        }
        out.push(sum.map(|s| s as f32));
    }
    out
}

/// `sheen_albedo_table`'s length in vec4s: a cell per pair of adjacent cosines and pair of
/// adjacent roughnesses.
pub const SHEEN_CELLS: usize = (SHEEN_ALBEDO_MU - 1) * (SHEEN_ALBEDO_R - 1);

/// Per cell (i, j), (MU - 1) per roughness j: E at cosines i and i + 1 of roughness j, then
/// of roughness j + 1, so that a bilinear lookup reads one texel.
pub fn sheen_cells() -> Vec<[f32; 4]> {
    let (mu, e) = (SHEEN_ALBEDO_MU, &SHEEN_ALBEDO);
    (0..SHEEN_ALBEDO_R - 1)
        .flat_map(|j| (0..mu - 1).map(move |i| (i, j)))
        .map(|(i, j)| [e[j * mu + i], e[j * mu + i + 1], e[(j + 1) * mu + i], e[(j + 1) * mu + i + 1]])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_have_their_lengths() {
        assert_eq!(ggx_cells().len(), GGX_CELLS);
        assert_eq!(sheen_cells().len(), SHEEN_CELLS);
        // Cell (1, 2) of the sheen table: E at cosines 1 and 2 of roughnesses 2 and 3.
        let c = sheen_cells()[2 * (SHEEN_ALBEDO_MU - 1) + 1];
        assert_eq!(c, [SHEEN_ALBEDO[65], SHEEN_ALBEDO[66], SHEEN_ALBEDO[97], SHEEN_ALBEDO[98]]);
    }

    #[test]
    fn cumulative_integrals_end_at_the_averages() {
        use super::super::ggx_albedo::GGX_ALBEDO_AVERAGE;
        // A row of constant (1, 0) integrates to x^4 = mu^2 at each node.
        let ones = vec![[1.0f32, 0.0]; MU];
        for (i, k) in ggx_cumulative(&ones).iter().enumerate() {
            let x = i as f32 / (MU - 1) as f32;
            assert!((k[0] - x.powi(4)).abs() < 1e-6 && k[1] == 0.0, "node {i}: {k:?}");
        }
        // The generated averages (5 decimals, tests/common/ggx.rs) are the last node's.
        for j in 0..R {
            let last = ggx_cumulative(&GGX_ALBEDO[j * MU..(j + 1) * MU])[MU - 1];
            for k in 0..2 {
                assert!((last[k] - GGX_ALBEDO_AVERAGE[j][k]).abs() < 1e-5, "roughness {j}: {last:?}");
            }
        }
    }
}
