// Link shaderc against Debian's static glslang / SPIRV-Tools libraries (see
// docs/toolchain.md, 3): Debian's libshaderc.so is unusable and building shaderc from
// source takes ~23 minutes. Elsewhere the shaderc crate's own discovery is used.
fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    embed_glsl();
    println!("cargo:rerun-if-env-changed=SHADERC_LIB_DIR");
    let dir = std::path::Path::new("/usr/lib/x86_64-linux-gnu");
    if cfg!(target_os = "linux") && dir.join("libglslang.a").exists() {
        println!("cargo:rustc-link-search=native={}", dir.display());
        for lib in [
            "glslang",
            "MachineIndependent",
            "GenericCodeGen",
            "OSDependent",
            "OGLCompiler",
            "HLSL",
            "SPIRV",
            "SPIRV-Tools-opt",
            "SPIRV-Tools",
        ] {
            if dir.join(format!("lib{lib}.a")).exists() {
                println!("cargo:rustc-link-lib=static={lib}");
            }
        }
    }
}

/// Embeds every file under glsl/ into the binary (`glsl_sources.rs` in OUT_DIR) so that
/// `vkvcm` compiles its kernels at run time without needing the source tree.
fn embed_glsl() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl");
    println!("cargo:rerun-if-changed={}", root.display());
    let mut files = Vec::new();
    collect(&root, &root, &mut files);
    files.sort();
    let mut out = String::from("pub static SOURCES: &[(&str, &str)] = &[\n");
    // Paths relative to CARGO_MANIFEST_DIR as the crate sees it when it is compiled, not
    // absolute paths from this script's run: a checkout moved or copied together with its
    // target/ dir (where cargo need not re-run this script) still embeds its own shaders.
    for (rel, _) in files {
        out.push_str(&format!(
            "    ({rel:?}, include_str!(concat!(env!(\"CARGO_MANIFEST_DIR\"), {:?}))),\n",
            format!("/glsl/{rel}")
        ));
    }
    out.push_str("];\n");
    let dest = std::path::Path::new(&std::env::var("OUT_DIR").unwrap()).join("glsl_sources.rs");
    std::fs::write(dest, out).unwrap();
}

fn collect(root: &std::path::Path, dir: &std::path::Path, out: &mut Vec<(String, String)>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let path = e.path();
        if path.is_dir() {
            println!("cargo:rerun-if-changed={}", path.display());
            collect(root, &path, out);
        } else if matches!(path.extension().and_then(|x| x.to_str()), Some("glsl" | "comp")) {
            let rel = path.strip_prefix(root).unwrap().to_string_lossy().replace('\\', "/");
            out.push((rel, path.to_string_lossy().into_owned()));
        }
    }
}
