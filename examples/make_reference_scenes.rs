//! Writes the four reference scenes (SmallVCM's Cornell box configurations) to `scenes/`
//! (or to the folder given as the first argument).
//!
//! `cargo run --example make_reference_scenes [-- OUT_DIR]`

use std::path::PathBuf;

fn main() -> anyhow::Result<()> {
    let dir = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes"));
    for path in vkvcm::scene::reference::write_reference_scenes(&dir)? {
        let scene = vkvcm::scene::load(&path)?;
        println!(
            "{}: {} triangles, {} spheres, {} materials, {} lights",
            path.display(),
            scene.triangles.len(),
            scene.spheres.len(),
            scene.materials.len(),
            scene.lights.len()
        );
    }
    Ok(())
}
