//! The texel buffers the kernels interpolate the lobes' directional albedos in, each a
//! fixed table (`Gpu::fixed_table`) of vec4 cells: `ggx_albedo_table` (glsl/bsdf.glsl,
//! ggx_albedo_terms) from src/render/ggx_albedo.rs, `sheen_albedo_table`
//! (glsl/lobes/sheen.glsl, sheen_albedo) from src/render/sheen_albedo.rs. Texel buffers:
//! on lavapipe they cost less than a storage buffer or a private GLSL array
//! (docs/performance.md, "Tried and not kept").

use super::ggx_albedo::{GGX_ALBEDO, GGX_ALBEDO_AVERAGE, GGX_ALBEDO_MU as MU, GGX_ALBEDO_R as R};
use super::sheen_albedo::{SHEEN_ALBEDO, SHEEN_ALBEDO_MU, SHEEN_ALBEDO_R};

/// `ggx_albedo_table`'s length in vec4s: a cell per pair of adjacent cosines and
/// roughness, then a cell per pair of adjacent roughnesses' averages.
pub const GGX_CELLS: usize = (MU - 1) * R + R - 1;

/// Per cell (A, B) at cosine rows i and i + 1 of roughness j, (MU - 1) cells per roughness,
/// so that a bilinear lookup reads two texels (one per roughness); then the (A, B)
/// averages at roughnesses j and j + 1.
pub fn ggx_cells() -> Vec<[f32; 4]> {
    let pair = |p: [f32; 2], q: [f32; 2]| [p[0], p[1], q[0], q[1]];
    let table = (0..R).flat_map(|j| (0..MU - 1).map(move |i| pair(GGX_ALBEDO[j * MU + i], GGX_ALBEDO[j * MU + i + 1])));
    let averages = (0..R - 1).map(|j| pair(GGX_ALBEDO_AVERAGE[j], GGX_ALBEDO_AVERAGE[j + 1]));
    table.chain(averages).collect()
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
}
