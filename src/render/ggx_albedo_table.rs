//! The texel buffer `ggx_albedo_table` the kernels interpolate the GGX lobe's albedo in
//! (glsl/bsdf.glsl, ggx_albedo_terms), from the tables of src/render/ggx_albedo.rs.

use super::ggx_albedo::{GGX_ALBEDO, GGX_ALBEDO_AVERAGE, GGX_ALBEDO_MU as MU, GGX_ALBEDO_R as R};

/// The buffer's length in vec4s: a cell per pair of adjacent cosines and roughness, then a
/// cell per pair of adjacent roughnesses' averages.
pub const CELLS: usize = (MU - 1) * R + R - 1;

/// Per cell (A, B) at cosine rows i and i + 1 of roughness j, (MU - 1) cells per roughness,
/// so that a bilinear lookup reads two texels (one per roughness); then the (A, B)
/// averages at roughnesses j and j + 1.
pub fn cells() -> Vec<[f32; 4]> {
    let pair = |p: [f32; 2], q: [f32; 2]| [p[0], p[1], q[0], q[1]];
    let table = (0..R).flat_map(|j| (0..MU - 1).map(move |i| pair(GGX_ALBEDO[j * MU + i], GGX_ALBEDO[j * MU + i + 1])));
    let averages = (0..R - 1).map(|j| pair(GGX_ALBEDO_AVERAGE[j], GGX_ALBEDO_AVERAGE[j + 1]));
    table.chain(averages).collect()
}
