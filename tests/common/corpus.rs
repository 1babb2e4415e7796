//! The malformed-scene corpus tests/malformed/: every `<case>.gltf|.glb` with the text of
//! its `<case>.expect` (an expected error substring, or `ok`), sorted by name.

use std::path::{Path, PathBuf};

pub fn malformed_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/malformed")
}

pub fn malformed_cases() -> Vec<(PathBuf, String)> {
    let mut cases: Vec<PathBuf> = std::fs::read_dir(malformed_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")))
        .collect();
    cases.sort();
    cases
        .into_iter()
        .map(|path| {
            let expect_file = PathBuf::from(format!("{}.expect", path.display()));
            let expect = std::fs::read_to_string(&expect_file)
                .unwrap_or_else(|e| panic!("{}: {e} (every case needs its .expect)", expect_file.display()));
            (path, expect.trim().to_string())
        })
        .collect()
}
