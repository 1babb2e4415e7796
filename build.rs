// Link shaderc against Debian's static glslang / SPIRV-Tools libraries (see
// ../shared/TOOLCHAIN.md): Debian's libshaderc.so is unusable and building shaderc from
// source takes ~23 minutes. Elsewhere the shaderc crate's own discovery is used.
fn main() {
    println!("cargo:rerun-if-changed=build.rs");
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
