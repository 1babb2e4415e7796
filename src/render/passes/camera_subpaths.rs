//! The camera-subpaths pass: one camera subpath per pixel and iteration, which adds the
//! pixel's value to the film. Three kernels, one per kind of estimator:
//! glsl/el.comp (the eye-light preview, one ray per pixel), glsl/pt.comp (path tracing)
//! and glsl/camera_subpath.comp (bpt, ppm, bpm, vcm: connections to the light vertices of
//! this iteration and merges with them, as the techniques ask, then the pixel's splats).
//! pt and camera_subpath trace `paths_per_invocation` paths per invocation (path
//! regeneration, src/render/regen.rs).

use anyhow::Result;

use super::hash_grid::HashGrid;
use super::{PassContext, PassInfo};
use crate::gpu::{Batch, Bind, Defines, Kernel};
use crate::render::aov::AovKernel;
use crate::render::gpu_types::GpuPush;
use crate::render::light_vertex_store::LightVertexStore;
use crate::render::reads::Reads;
use crate::render::regen;
use crate::render::settings::Connect;
use crate::render::techniques::Techniques;
use crate::render::variants::kernel_switches;

/// The name profiles report.
pub const NAME: &str = "camera subpaths";

kernel_switches! {
    /// What glsl/camera_subpath.comp is compiled with: the camera side of the estimator's
    /// [`Techniques`] under the same names, where its connections go and how it reads.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub struct CameraKernel {
        /// Next-event estimation and vertex connections, with MIS.
        pub vertex_connection: bool,
        /// Merging with the light vertices in the radius.
        pub vertex_merging: bool,
        /// Merging at the first non-specular vertex only, weight 1 (ppm).
        pub merge_first_vertex_only: bool,
        /// Light vertices each camera vertex connects to, drawn from all light subpaths
        /// (`--connect cache`); 0: to those of light subpath p = this pixel (`--connect path`).
        pub cache_connections: u32,
        /// The light-vertex store and the hash grid are read as texel buffers.
        pub store_texel_reads: bool,
        /// Owen-scrambled Sobol samples (else independent random numbers).
        pub sobol: bool,
    }
}

impl CameraKernel {
    pub fn new(t: Techniques, connect: Connect, reads: Reads, sobol: bool) -> CameraKernel {
        CameraKernel {
            vertex_connection: t.vertex_connection,
            vertex_merging: t.vertex_merging,
            merge_first_vertex_only: t.merge_first_vertex_only,
            cache_connections: match connect {
                Connect::Path => 0,
                Connect::Cache(n) => n,
            },
            store_texel_reads: reads == Reads::Texel,
            sobol,
        }
    }
}

kernel_switches! {
    /// What glsl/pt.comp is compiled with.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub struct PtKernel {
        /// Next-event estimation with MIS (else BSDF sampling only).
        pub nee: bool,
        /// Owen-scrambled Sobol samples (else independent random numbers).
        pub sobol: bool,
    }
}

/// The pass.
pub struct CameraSubpaths {
    kernel: Kernel,
    pixels: u32,
    /// Paths per invocation (1 for el).
    paths_per_invocation: u32,
    /// The kernel traces pixels `first_path ..` (pt, camera_subpath): it may be split.
    pieces: bool,
    detail: String,
}

impl CameraSubpaths {
    /// el.comp: |cos| at the first hit, one pixel per invocation.
    pub fn eye_light(b: &PassContext) -> Result<CameraSubpaths> {
        let binds = camera_binds(b);
        let kernel = b.gpu.kernel("el.comp", &camera_defines(b).pairs(), &binds)?;
        Ok(CameraSubpaths {
            kernel,
            pixels: b.pixels,
            paths_per_invocation: 1,
            pieces: false,
            detail: "el.comp: first hit, |cos| with the shading normal; film".into(),
        })
    }

    /// pt.comp in `variant`.
    pub fn path_tracer(b: &PassContext, variant: PtKernel) -> Result<CameraSubpaths> {
        let binds = camera_binds(b);
        let defines = camera_defines(b).with(&variant.defines());
        let kernel = b.gpu.kernel("pt.comp", &defines.pairs(), &binds)?;
        let what = if variant.nee { "BSDF sampling + next-event estimation, MIS" } else { "BSDF sampling only" };
        Ok(CameraSubpaths {
            kernel,
            pixels: b.pixels,
            paths_per_invocation: b.paths_per_invocation,
            pieces: true,
            detail: format!("pt.comp: {what}; film"),
        })
    }

    /// camera_subpath.comp in `variant`, reading the light-vertex `store` and the hash
    /// `grid` (merging).
    pub fn bidirectional(
        b: &PassContext,
        store: &LightVertexStore,
        grid: Option<&HashGrid>,
        variant: CameraKernel,
    ) -> Result<CameraSubpaths> {
        let defines: Defines = camera_defines(b).with(&variant.defines());
        let mut binds = camera_binds(b);
        binds.extend(store.binds());
        if let Some(g) = grid {
            binds.extend([Bind::u32("grid_start", &g.cell_start), Bind::vec4("grid_points", &g.cell_points)]);
        }
        let kernel = b.gpu.kernel("camera_subpath.comp", &defines.pairs(), &binds)?;
        Ok(CameraSubpaths {
            kernel,
            pixels: b.pixels,
            paths_per_invocation: b.paths_per_invocation,
            pieces: true,
            detail: format!("camera_subpath.comp: {}", describe(variant)),
        })
    }

    /// Pixels (camera subpaths per iteration).
    pub fn pixels(&self) -> u32 {
        self.pixels
    }

    /// Records the pass for the iteration of `push`: its pixels in pieces that keep each
    /// submission within the batch's budget (el.comp, one short ray per pixel, in one).
    pub fn record(&self, batch: &mut Batch, push: &GpuPush) -> Result<()> {
        batch.begin_pass(NAME);
        let k = self.paths_per_invocation;
        if !self.pieces {
            let groups = self.kernel.groups_for(regen::invocations(self.pixels, k));
            return batch.dispatch(&self.kernel, groups, bytemuck::bytes_of(push));
        }
        batch.record_paths(&self.kernel, self.pixels, u32::MAX, |batch, first, count| {
            let p = GpuPush { first_path: first, count, ..*push };
            let groups = self.kernel.groups_for(regen::invocations(count, k));
            batch.dispatch_paths(&self.kernel, groups, bytemuck::bytes_of(&p), count)
        })
    }

    pub fn info(&self) -> PassInfo {
        PassInfo { name: NAME, detail: self.detail.clone() }
    }
}

/// What every camera kernel is compiled with: the scene's part and the AOV switch.
fn camera_defines(b: &PassContext) -> Defines {
    b.scene.variant.defines().with(&AovKernel { aov: b.film.aov.is_some() }.defines())
}

/// What every camera kernel binds: the scene, the film and the AOV sums when asked for.
fn camera_binds<'a>(b: &PassContext<'a>) -> Vec<Bind<'a>> {
    let mut binds = b.scene.binds();
    binds.extend(b.film.binds());
    binds.extend(b.film.aov.as_ref().map(|a| a.bind()));
    binds
}

fn describe(v: CameraKernel) -> String {
    let mut parts = Vec::new();
    if v.vertex_connection {
        parts.push(match v.cache_connections {
            0 => "NEE + connections to light subpath p = this pixel".to_string(),
            n => format!("NEE + {n} connection(s) per vertex to the light-vertex cache"),
        });
    }
    if v.merge_first_vertex_only {
        parts.push("merging at the first non-specular vertex".into());
    } else if v.vertex_merging {
        parts.push("merging at every vertex".into());
    }
    let mis = if v.merge_first_vertex_only { "" } else { ", MIS" };
    format!("{}{mis}; splats -> film", parts.join(" + "))
}
