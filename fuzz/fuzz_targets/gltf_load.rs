//! cargo-fuzz target: the glTF/GLB importer on arbitrary bytes must return Ok or a
//! one-line error, never panic. Run with scripts/fuzz.sh (seeded with tests/malformed/).
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;
use vkvcm::scene::{self, LoadOptions};

/// A folder with a small file `x` so that relative buffer URIs can resolve.
fn scene_path() -> &'static PathBuf {
    static P: OnceLock<PathBuf> = OnceLock::new();
    P.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("vkvcm-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("x"), [0u8; 64]).unwrap();
        dir.join("fuzz.gltf")
    })
}

fuzz_target!(|data: &[u8]| {
    match scene::load_gltf_bytes(data, scene_path(), &LoadOptions::default()) {
        Ok(s) => {
            if scene::check_renderable(&s).is_ok() {
                vkvcm::bvh::build(&s.triangles, &s.spheres);
            }
        }
        Err(e) => assert!(!format!("{e:#}").contains('\n'), "multi-line error"),
    }
});
