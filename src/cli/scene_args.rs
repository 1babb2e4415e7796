//! The scene and view options of the commands that load a scene for a render (`render`,
//! `info`): which file and glTF scene, which camera and where it looks, the frame's size,
//! and the environment.

use anyhow::{bail, Context, Result};
use clap::Args;

use vkvcm::scene::{self, Scene};

#[derive(Args, Clone, Debug)]
pub struct SceneArgs {
    /// A glTF file (.gltf/.glb) or a built-in scene: gbs_s (default), glm_c, gbs_p, gbs_b.
    pub scene: Option<String>,
    /// Camera to use, by node or camera name, or `auto`: one that frames the scene
    /// (default: the file's first camera, else auto).
    #[arg(long)]
    pub camera: Option<String>,
    /// glTF files with several scenes: render the scene with this name, else with this
    /// index (default: the file's default scene, else the first).
    #[arg(long, value_name = "NAME|INDEX")]
    pub gltf_scene: Option<String>,
    /// Store every mesh as world-space triangles, also those that several nodes (or
    /// EXT_mesh_gpu_instancing) place, which are otherwise stored once and instanced:
    /// the same image, more memory (for A/B comparisons).
    #[arg(long)]
    pub flatten_instances: bool,
    /// Put the camera at X,Y,Z (the file's world coordinates); it then looks at the
    /// centre of the scene unless --look-at says otherwise, with world +Y up unless --up
    /// says otherwise.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub look_from: Option<glam::Vec3>,
    /// Point the camera at X,Y,Z (the file's world coordinates).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub look_at: Option<glam::Vec3>,
    /// The direction that is up in the image (default with --look-from / --look-at:
    /// world +Y; alone it turns the file's camera about its view).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub up: Option<glam::Vec3>,
    /// Vertical field of view in degrees.
    #[arg(long, value_name = "DEGREES")]
    pub fov: Option<f32>,
    /// Image width (default: 512 pixels on the longer side, the other following the
    /// camera's aspect ratio: a glTF camera's aspectRatio, else square; one of --width
    /// and --height alone sets the other by that ratio).
    #[arg(long = "width", value_name = "PIXELS")]
    pub width: Option<u32>,
    /// Image height (default: see --width).
    #[arg(long = "height", value_name = "PIXELS")]
    pub height: Option<u32>,
    #[command(flatten)]
    pub env: super::EnvArgs,
}

impl SceneArgs {
    /// Checks the numbers (no file is read).
    pub fn check(&self) -> Result<()> {
        if self.width == Some(0) {
            bail!("--width 0: the image width must be at least 1 pixel");
        }
        if self.height == Some(0) {
            bail!("--height 0: the image height must be at least 1 pixel");
        }
        self.env.check()
    }

    /// The scene's name as given (`default` without one).
    pub fn name(&self) -> String {
        self.scene.clone().unwrap_or_else(|| "default".into())
    }

    /// The scene with the environment and view options applied (the importer's warnings
    /// are in its report, not printed).
    pub fn load(&self) -> Result<Scene> {
        let options = scene::LoadOptions {
            scene: self.gltf_scene.clone(),
            flatten_instances: self.flatten_instances,
            ..self.env.load_options(self.camera.clone())?
        };
        let mut scene = scene::load_named_with(&self.name(), &options)?;
        scene
            .set_view(self.look_from, self.look_at, self.up, self.fov.map(f32::to_radians))
            .context("--look-from / --look-at / --up / --fov")?;
        Ok(scene)
    }

    /// The frame's size for `scene`'s camera ([`frame_size`]).
    pub fn frame_size(&self, scene: &Scene) -> (u32, u32) {
        frame_size(self.width, self.height, scene.report.camera_aspect)
    }
}

/// The frame's size: --width and --height, else 512 pixels on the longer side with the
/// camera's `aspect` (width / height; square without one), one given side setting the
/// other by it, as a glTF viewer shows a camera of that aspect ratio.
pub fn frame_size(width: Option<u32>, height: Option<u32>, aspect: Option<f32>) -> (u32, u32) {
    const LONG_SIDE: u32 = 512;
    let aspect = aspect.filter(|a| *a > 0.0 && a.is_finite()).unwrap_or(1.0) as f64;
    let side = |x: f64| (x.round() as u32).max(1);
    match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, side(w as f64 / aspect)),
        (None, Some(h)) => (side(h as f64 * aspect), h),
        (None, None) if aspect >= 1.0 => (LONG_SIDE, side(LONG_SIDE as f64 / aspect)),
        (None, None) => (side(LONG_SIDE as f64 * aspect), LONG_SIDE),
    }
}

/// `X,Y,Z` as a vector of three finite numbers.
pub fn parse_vec3(s: &str) -> std::result::Result<glam::Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|c| c.trim().parse::<f32>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|e| format!("{s:?}: {e}"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(glam::Vec3::new(x, y, z)),
        _ => Err(format!("{s:?}: expected three finite numbers X,Y,Z")),
    }
}
