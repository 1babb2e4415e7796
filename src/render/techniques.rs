//! The light-transport techniques an estimator combines: they decide its passes, its
//! kernel variants (src/render/variants.rs), its plan of sizes (src/render/plan.rs) and
//! its MIS factors. Each estimator states its own (src/render/estimators/).

/// The light-transport techniques an estimator uses; they decide its passes and kernel
/// variants (src/render/variants.rs) and its MIS factors.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Techniques {
    /// Light subpaths are traced each iteration (lt, bpt, ppm, bpm, vcm).
    pub light_subpaths: bool,
    /// Their non-delta vertices are stored for the camera pass (bpt, ppm, bpm, vcm).
    pub store_vertices: bool,
    /// Light vertices connect to the camera, splatting onto any pixel (lt, bpt, vcm).
    pub connect_to_camera: bool,
    /// Camera vertices connect to lights (next-event estimation) and to light vertices,
    /// with MIS (bpt, vcm; SmallVCM's "vertex connection").
    pub vertex_connection: bool,
    /// Camera vertices merge with light vertices within the radius (ppm, bpm, vcm).
    pub vertex_merging: bool,
    /// Merging only at the first non-specular camera vertex, weight 1 (ppm).
    pub merge_first_vertex_only: bool,
    /// Light tracing without MIS, which also splats directly seen emitters (lt).
    pub light_trace_only: bool,
}

impl Techniques {
    /// No light subpaths: the camera-only estimators (pt, el).
    pub const NONE: Techniques = Techniques {
        light_subpaths: false,
        store_vertices: false,
        connect_to_camera: false,
        vertex_connection: false,
        vertex_merging: false,
        merge_first_vertex_only: false,
        light_trace_only: false,
    };
}
