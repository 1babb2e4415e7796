//! GLSL -> SPIR-V through shaderc, with `#include` resolved from glsl/ and per-variant
//! `#define`s. The sources are embedded in the binary at build time; setting
//! `VKVCM_GLSL_DIR` reads them from that folder instead (for shader development).
//! Resources declared without a `binding = N` get one from the compiler (glslang's
//! auto-mapping); kernels are bound by name (src/gpu/reflect.rs). Compiled SPIR-V and
//! shader modules are cached by (name, source, defines).

use std::borrow::Cow;
use std::collections::hash_map::DefaultHasher;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use anyhow::{anyhow, Result};
use ash::vk;

use super::reflect::{reflect, KernelInterface};

mod embedded {
    include!(concat!(env!("OUT_DIR"), "/glsl_sources.rs"));
}

/// A GLSL source by its path relative to glsl/ (e.g. `"bvh.glsl"`, `"tests/add.comp"`).
pub fn source(name: &str) -> Option<Cow<'static, str>> {
    if let Ok(dir) = std::env::var("VKVCM_GLSL_DIR") {
        if let Ok(s) = std::fs::read_to_string(std::path::Path::new(&dir).join(name)) {
            return Some(Cow::Owned(s));
        }
    }
    embedded::SOURCES.iter().find(|(n, _)| *n == name).map(|(_, s)| Cow::Borrowed(*s))
}

/// The names of all embedded sources.
pub fn source_names() -> impl Iterator<Item = &'static str> {
    embedded::SOURCES.iter().map(|(n, _)| *n)
}

/// A GLSL compile failure; the message carries glslang's `file:line: error` lines.
#[derive(Debug, thiserror::Error)]
#[error("GLSL compile error in {name}:\n{log}")]
pub struct CompileError {
    pub name: String,
    pub log: String,
}

static COMPILES: AtomicUsize = AtomicUsize::new(0);

/// How many shaderc compilations this process has run (for tests of the cache).
pub fn compile_count() -> usize {
    COMPILES.load(Ordering::Relaxed)
}

fn resolve_include(requested: &str, requester: &str) -> Result<shaderc::ResolvedInclude, String> {
    // Relative to the including file's folder first, then to glsl/.
    let dir = requester.rsplit_once('/').map(|(d, _)| d).unwrap_or("");
    let candidates = if dir.is_empty() {
        vec![requested.to_string()]
    } else {
        vec![format!("{dir}/{requested}"), requested.to_string()]
    };
    for c in candidates {
        if let Some(src) = source(&c) {
            return Ok(shaderc::ResolvedInclude { resolved_name: c, content: src.into_owned() });
        }
    }
    Err(format!("cannot find include {requested:?} (looked in glsl/)"))
}

/// Compiles a compute shader. `name` is used for error messages and include lookup.
pub fn compile_glsl(name: &str, source: &str, defines: &[(&str, &str)]) -> Result<Vec<u32>> {
    compile_glsl_opt(name, source, defines, true)
}

/// As [`compile_glsl`]; `optimize: false` keeps every name in the SPIR-V (for reflection).
pub fn compile_glsl_opt(name: &str, source: &str, defines: &[(&str, &str)], optimize: bool) -> Result<Vec<u32>> {
    let compiler = shaderc::Compiler::new().map_err(|e| anyhow!("shaderc init failed: {e}"))?;
    let mut opts = shaderc::CompileOptions::new().map_err(|e| anyhow!("shaderc options: {e}"))?;
    // SPIR-V 1.5 (Vulkan 1.2): 1.6 would emit LocalSizeId and need maintenance4.
    opts.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_2 as u32);
    opts.set_target_spirv(shaderc::SpirvVersion::V1_5);
    if optimize {
        opts.set_optimization_level(shaderc::OptimizationLevel::Performance);
        // The optimiser strips the names that kernels are bound by unless debug info is
        // kept; ShaderCache reflects them, then strips the debug instructions
        // ([`strip_debug_info`]), which leaves the optimiser's instruction stream (the
        // same with and without debug info, checked with spirv-opt --strip-debug).
        opts.set_generate_debug_info();
    } else {
        opts.set_optimization_level(shaderc::OptimizationLevel::Zero);
    }
    opts.set_auto_bind_uniforms(true);
    for (k, v) in defines {
        opts.add_macro_definition(k, Some(v));
    }
    opts.set_include_callback(|req, _ty, requester, _depth| resolve_include(req, requester));
    COMPILES.fetch_add(1, Ordering::Relaxed);
    match compiler.compile_into_spirv(source, shaderc::ShaderKind::Compute, name, "main", Some(&opts)) {
        Ok(art) => Ok(art.as_binary().to_vec()),
        Err(shaderc::Error::CompilationError(_, log)) => {
            Err(CompileError { name: name.to_string(), log: log.trim_end().to_string() }.into())
        }
        Err(e) => Err(anyhow!("shaderc failed on {name}: {e}")),
    }
}

/// `spirv` without its debug instructions (OpSource*, OpString, OpName, OpMemberName,
/// OpLine, OpNoLine, OpModuleProcessed), which the driver does not need.
pub fn strip_debug_info(spirv: &[u32]) -> Vec<u32> {
    const DEBUG_OPS: [u32; 9] = [2, 3, 4, 5, 6, 7, 8, 317, 330];
    let mut out = Vec::with_capacity(spirv.len());
    out.extend_from_slice(&spirv[..spirv.len().min(5)]);
    let mut i = 5;
    while i < spirv.len() {
        let count = (spirv[i] >> 16) as usize;
        let op = spirv[i] & 0xffff;
        if count == 0 || i + count > spirv.len() {
            // Malformed: keep the rest as it is (the driver will say what is wrong).
            out.extend_from_slice(&spirv[i..]);
            break;
        }
        if !DEBUG_OPS.contains(&op) {
            out.extend_from_slice(&spirv[i..i + count]);
        }
        i += count;
    }
    out
}

fn key(name: &str, source: &str, defines: &[(&str, &str)]) -> u64 {
    let mut h = DefaultHasher::new();
    (name, source, defines).hash(&mut h);
    h.finish()
}

/// Shader modules and their reflected interfaces by (name, source, defines), created once
/// per `Gpu`.
#[derive(Default)]
pub(crate) struct ShaderCache {
    modules: Mutex<HashMap<u64, (vk::ShaderModule, KernelInterface)>>,
}

impl ShaderCache {
    pub(crate) fn module(
        &self,
        device: &ash::Device,
        name: &str,
        defines: &[(&str, &str)],
    ) -> Result<(vk::ShaderModule, KernelInterface)> {
        let src = source(name).ok_or_else(|| anyhow!("no kernel named {name:?} in glsl/"))?;
        let k = key(name, &src, defines);
        let mut map = self.modules.lock().map_err(|_| anyhow!("shader cache poisoned"))?;
        if let Some((m, i)) = map.get(&k) {
            return Ok((*m, i.clone()));
        }
        let spirv = compile_glsl(name, &src, defines)?;
        let interface = reflect(name, &spirv)?;
        let spirv = strip_debug_info(&spirv);
        let info = vk::ShaderModuleCreateInfo::default().code(&spirv);
        // SAFETY: valid SPIR-V from shaderc.
        let m = unsafe { device.create_shader_module(&info, None) }?;
        map.insert(k, (m, interface.clone()));
        Ok((m, interface))
    }

    /// Destroys every module.
    ///
    /// # Safety
    /// No pipeline creation may be in flight.
    pub(crate) unsafe fn destroy(&self, device: &ash::Device) {
        if let Ok(mut map) = self.modules.lock() {
            for (_, (m, _)) in map.drain() {
                // SAFETY: caller guarantees no use.
                unsafe { device.destroy_shader_module(m, None) };
            }
        }
    }
}
