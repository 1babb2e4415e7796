// Link shaderc against Debian's static glslang / SPIRV-Tools libraries (see
// docs/toolchain.md, 3): Debian's libshaderc.so is unusable and building shaderc from
// source takes ~23 minutes. Elsewhere the shaderc crate's own discovery is used.
fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    embed_glsl();
    println!("cargo:rerun-if-env-changed=SHADERC_LIB_DIR");
    let dir = std::path::Path::new("/usr/lib/x86_64-linux-gnu");
    let compiler = if cfg!(target_os = "linux") && dir.join("libglslang.a").exists() {
        println!("cargo:rustc-link-search=native={}", dir.display());
        let mut linked = vec!["shaderc_combined"];
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
                linked.push(lib);
            }
        }
        debian_compiler_identity(dir, &linked)
    } else {
        let lib_dir = std::env::var("SHADERC_LIB_DIR").unwrap_or_default();
        format!("shaderc as shaderc-sys finds it (SHADERC_LIB_DIR={lib_dir:?})")
    };
    // Part of the key of the kernel cache's SPIR-V (src/gpu/shader.rs, compiler_identity).
    println!("cargo:rustc-env=VKVCM_SHADER_COMPILER={compiler}");
}

/// What identifies the GLSL compiler linked from Debian's static libraries: the versions
/// of shaderc, glslang and SPIRV-Tools, and the size and modification time of every
/// static library linked (which change when any of those packages is rebuilt or
/// upgraded; build.rs then re-runs, so the binary carries the new identity).
fn debian_compiler_identity(dir: &std::path::Path, linked: &[&str]) -> String {
    let pc_version = |name: &str| {
        let text = std::fs::read_to_string(dir.join("pkgconfig").join(format!("{name}.pc"))).unwrap_or_default();
        text.lines().find_map(|l| l.strip_prefix("Version:")).unwrap_or("?").trim().to_string()
    };
    let build_info = std::fs::read_to_string("/usr/include/glslang/build_info.h").unwrap_or_default();
    let glslang: Vec<&str> = ["MAJOR", "MINOR", "PATCH"]
        .iter()
        .map(|part| {
            let prefix = format!("#define GLSLANG_VERSION_{part} ");
            build_info.lines().find_map(|l| l.strip_prefix(prefix.as_str())).unwrap_or("?").trim()
        })
        .collect();
    let mut out = format!(
        "shaderc {}, glslang {}, SPIRV-Tools {}; static libraries:",
        pc_version("shaderc_combined"),
        glslang.join("."),
        pc_version("SPIRV-Tools")
    );
    for lib in linked {
        let path = dir.join(format!("lib{lib}.a"));
        println!("cargo:rerun-if-changed={}", path.display());
        let meta = std::fs::metadata(&path).ok();
        let size = meta.as_ref().map_or(0, |m| m.len());
        let modified = meta
            .and_then(|m| m.modified().ok())
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map_or(0, |d| d.as_secs());
        out.push_str(&format!(" {lib} {size} bytes @{modified}"));
    }
    out
}

/// Embeds every file under glsl/ into the binary (`glsl_sources.rs` in OUT_DIR) so that
/// `vkvcm` compiles its kernels at run time without needing the source tree. glsl/tests/
/// (test and benchmark kernels) only with the `test-kernels` feature: a render never runs
/// them.
fn embed_glsl() {
    // The manifest directory of this run (cargo sets it for build scripts), not the one
    // this script was compiled in: a target/ dir copied to another checkout would
    // otherwise list (and watch) the first checkout's shaders.
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let root = std::path::Path::new(&manifest).join("glsl");
    println!("cargo:rerun-if-changed={}", root.display());
    let mut files = Vec::new();
    collect(&root, &root, &mut files);
    if std::env::var_os("CARGO_FEATURE_TEST_KERNELS").is_none() {
        files.retain(|(rel, _)| !rel.starts_with("tests/"));
    }
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
