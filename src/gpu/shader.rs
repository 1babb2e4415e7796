//! GLSL -> SPIR-V through shaderc, with `#include` resolved from glsl/ and per-variant
//! `#define`s. The sources are embedded in the binary at build time (glsl/tests/, the test
//! and benchmark kernels, only with the `test-kernels` feature); setting
//! `VKVCM_GLSL_DIR` reads them from that folder instead (for shader development).
//! Resources declared without a `binding = N` get one from the compiler (glslang's
//! auto-mapping); kernels are bound by name (src/gpu/reflect.rs).
//!
//! A `Gpu`'s [`ShaderCache`] builds each kernel variant once: its shader module and
//! reflected interface are kept by the variant's [`spirv_key`], and with a kernel cache
//! (src/gpu/kernel_cache.rs) its SPIR-V is read from disk instead of compiled when an
//! earlier process compiled the same variant.

use std::borrow::Cow;
use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, OnceLock};

use anyhow::{anyhow, Result};
use ash::vk;

use super::kernel_cache::{CacheDir, Key, KeyBuilder};
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

/// The file that `#include "requested"` in the file `requester` names, as (resolved name,
/// text): relative to the including file's folder first, then to glsl/.
fn resolve_include(requested: &str, requester: &str) -> Option<(String, Cow<'static, str>)> {
    let dir = requester.rsplit_once('/').map(|(d, _)| d).unwrap_or("");
    let candidates = if dir.is_empty() {
        vec![requested.to_string()]
    } else {
        vec![format!("{dir}/{requested}"), requested.to_string()]
    };
    candidates.into_iter().find_map(|c| source(&c).map(|text| (c, text)))
}

/// The names in the `#include "name"` (or `<name>`) lines of `text`.
fn include_names(text: &str) -> impl Iterator<Item = &str> {
    text.lines().filter_map(|line| {
        let rest = line.trim_start().strip_prefix('#')?.trim_start().strip_prefix("include")?.trim_start();
        let close = match rest.chars().next()? {
            '"' => '"',
            '<' => '>',
            _ => return None,
        };
        rest[1..].split_once(close).map(|(name, _)| name)
    })
}

/// A kernel's source and every file it includes, transitively, each read once: what its
/// compile reads and its key hashes. Includes are found by their `#include` lines, those
/// in disabled `#if` branches too (so these are all the files the compile may read), and
/// the compile takes them from here rather than reading the files again: it compiles
/// exactly the texts that were hashed, even while `VKVCM_GLSL_DIR`'s files change.
struct ResolvedSources {
    /// (resolved name, text): the kernel first, then in the order they are first included.
    files: Vec<(String, String)>,
    /// (requested name, requester's resolved name) -> index in `files`.
    includes: HashMap<(String, String), usize>,
}

impl ResolvedSources {
    fn new(name: &str, source: &str) -> ResolvedSources {
        let mut files = vec![(name.to_string(), source.to_string())];
        let mut index_of = HashMap::from([(name.to_string(), 0)]);
        let mut includes = HashMap::new();
        let mut next = 0;
        while next < files.len() {
            let requester = files[next].0.clone();
            // In the order of the text (the key hashes the files in this order), each once.
            let mut requested: Vec<String> = Vec::new();
            for req in include_names(&files[next].1) {
                if !requested.iter().any(|r| r == req) {
                    requested.push(req.to_string());
                }
            }
            for req in requested {
                // An include that is not found is left out; the compile reports it if it is
                // really read.
                let Some((resolved, text)) = resolve_include(&req, &requester) else { continue };
                let index = *index_of.entry(resolved.clone()).or_insert_with(|| {
                    files.push((resolved, text.into_owned()));
                    files.len() - 1
                });
                includes.insert((req, requester.clone()), index);
            }
            next += 1;
        }
        ResolvedSources { files, includes }
    }

    /// What shaderc's include callback returns for `#include "requested"` in `requester`.
    fn include(&self, requested: &str, requester: &str) -> shaderc::IncludeCallbackResult {
        match self.includes.get(&(requested.to_string(), requester.to_string())) {
            Some(&i) => {
                let (name, text) = &self.files[i];
                Ok(shaderc::ResolvedInclude { resolved_name: name.clone(), content: text.clone() })
            }
            None => Err(format!("cannot find include {requested:?} (looked in glsl/)")),
        }
    }
}

/// Every shaderc setting of a compile besides its defines and sources; all of them are
/// part of the compile's key ([`spirv_key`]).
#[derive(Clone, Copy, Debug)]
struct CompileSettings {
    target_env: shaderc::TargetEnv,
    env_version: shaderc::EnvVersion,
    spirv_version: shaderc::SpirvVersion,
    optimization: shaderc::OptimizationLevel,
    debug_info: bool,
    auto_bind_uniforms: bool,
}

impl CompileSettings {
    /// `optimize: false` keeps every name in the SPIR-V (for reflection) without debug
    /// info.
    fn new(optimize: bool) -> CompileSettings {
        CompileSettings {
            // SPIR-V 1.5 (Vulkan 1.2): 1.6 would emit LocalSizeId and need maintenance4.
            target_env: shaderc::TargetEnv::Vulkan,
            env_version: shaderc::EnvVersion::Vulkan1_2,
            spirv_version: shaderc::SpirvVersion::V1_5,
            optimization: if optimize {
                shaderc::OptimizationLevel::Performance
            } else {
                shaderc::OptimizationLevel::Zero
            },
            // The optimiser strips the names that kernels are bound by unless debug info is
            // kept; ShaderCache reflects them, then strips the debug instructions
            // ([`strip_debug_info`]), which leaves the optimiser's instruction stream (the
            // same with and without debug info, checked with spirv-opt --strip-debug).
            debug_info: optimize,
            auto_bind_uniforms: true,
        }
    }

    fn options<'a>(&self) -> Result<shaderc::CompileOptions<'a>> {
        let mut opts = shaderc::CompileOptions::new().map_err(|e| anyhow!("shaderc options: {e}"))?;
        opts.set_target_env(self.target_env, self.env_version as u32);
        opts.set_target_spirv(self.spirv_version);
        opts.set_optimization_level(self.optimization);
        if self.debug_info {
            opts.set_generate_debug_info();
        }
        opts.set_auto_bind_uniforms(self.auto_bind_uniforms);
        Ok(opts)
    }
}

/// What identifies the GLSL compiler: the libraries build.rs linked (their versions, sizes
/// and dates) and the SPIR-V version shaderc reports.
fn compiler_identity() -> &'static str {
    static IDENTITY: OnceLock<String> = OnceLock::new();
    IDENTITY.get_or_init(|| {
        let (spirv, revision) = shaderc::get_spirv_version();
        format!("{}; SPIR-V {spirv:#x} revision {revision}", env!("VKVCM_SHADER_COMPILER"))
    })
}

/// The key of a compile's SPIR-V: the compiler, its settings, the kernel's name (shaderc
/// records it in the debug info), the texts of the kernel and of every file it includes,
/// with their names, and the defines in their order. vkvcm's version and the cache's
/// format are in every key (src/gpu/kernel_cache.rs).
fn spirv_key(name: &str, sources: &ResolvedSources, defines: &[(&str, &str)], settings: &CompileSettings) -> Key {
    let mut k = KeyBuilder::new("spirv");
    k.field("compiler", compiler_identity()).field("settings", format!("{settings:?}")).field("kernel", name);
    for (file, text) in &sources.files {
        k.field("file", file).field("text", text);
    }
    for (define, value) in defines {
        k.field("define", define).field("value", value);
    }
    k.finish()
}

/// Compiles `sources` (the kernel `name` and its includes) with `defines`.
fn compile(
    name: &str,
    sources: &ResolvedSources,
    defines: &[(&str, &str)],
    settings: &CompileSettings,
) -> Result<Vec<u32>> {
    let compiler = shaderc::Compiler::new().map_err(|e| anyhow!("shaderc init failed: {e}"))?;
    let mut opts = settings.options()?;
    for (k, v) in defines {
        opts.add_macro_definition(k, Some(v));
    }
    opts.set_include_callback(|req, _ty, requester, _depth| sources.include(req, requester));
    COMPILES.fetch_add(1, Ordering::Relaxed);
    let source = &sources.files[0].1;
    match compiler.compile_into_spirv(source, shaderc::ShaderKind::Compute, name, "main", Some(&opts)) {
        Ok(art) => Ok(art.as_binary().to_vec()),
        Err(shaderc::Error::CompilationError(_, log)) => {
            Err(CompileError { name: name.to_string(), log: log.trim_end().to_string() }.into())
        }
        Err(e) => Err(anyhow!("shaderc failed on {name}: {e}")),
    }
}

/// Compiles a compute shader. `name` is used for error messages and include lookup.
pub fn compile_glsl(name: &str, source: &str, defines: &[(&str, &str)]) -> Result<Vec<u32>> {
    compile_glsl_opt(name, source, defines, true)
}

/// As [`compile_glsl`]; `optimize: false` keeps every name in the SPIR-V (for reflection).
pub fn compile_glsl_opt(name: &str, source: &str, defines: &[(&str, &str)], optimize: bool) -> Result<Vec<u32>> {
    compile(name, &ResolvedSources::new(name, source), defines, &CompileSettings::new(optimize))
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

/// The SPIR-V files of the kernel cache are kept within this many bytes in all (the least
/// recently written are removed first); a kernel variant's file is 10-200 KiB.
pub const MAX_SPIRV_CACHE_BYTES: u64 = 256 << 20;

/// The kernel cache's file of the SPIR-V of `key`.
fn spirv_file(key: &Key) -> String {
    format!("spirv-{}.bin", key.hex())
}

/// The SPIR-V of `key` from the kernel cache, with its interface, if it is there and
/// intact (a SPIR-V module that reflects).
fn load_spirv(dir: &CacheDir, name: &str, key: &Key) -> Option<(Vec<u32>, KernelInterface)> {
    let bytes = dir.read(&spirv_file(key), key)?;
    if bytes.len() % 4 != 0 {
        return None;
    }
    let words: Vec<u32> = bytes.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])).collect();
    if words.first() != Some(&0x0723_0203) {
        return None;
    }
    let interface = reflect(name, &words).ok()?;
    Some((words, interface))
}

/// Writes the SPIR-V of `key` to the kernel cache, and keeps the cache's SPIR-V within
/// [`MAX_SPIRV_CACHE_BYTES`].
fn store_spirv(dir: &CacheDir, key: &Key, spirv: &[u32]) {
    let file = spirv_file(key);
    let bytes: Vec<u8> = spirv.iter().flat_map(|w| w.to_le_bytes()).collect();
    if dir.write(&file, key, &bytes) {
        dir.prune("spirv-", MAX_SPIRV_CACHE_BYTES, &file);
    }
}

/// How a `Gpu` got its kernels' SPIR-V so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ShaderCounts {
    /// Kernel variants compiled with shaderc.
    pub compiled: usize,
    /// Kernel variants whose SPIR-V was read from the kernel cache on disk.
    pub from_disk: usize,
}

/// Shader modules and their reflected interfaces by kernel variant ([`spirv_key`]),
/// created once per `Gpu`; with a kernel cache, SPIR-V compiled by an earlier process is
/// read from disk and what is compiled is written there.
pub(crate) struct ShaderCache {
    disk: Option<CacheDir>,
    modules: Mutex<HashMap<Key, (vk::ShaderModule, KernelInterface)>>,
    compiled: AtomicUsize,
    from_disk: AtomicUsize,
}

impl ShaderCache {
    pub(crate) fn new(disk: Option<CacheDir>) -> ShaderCache {
        ShaderCache { disk, modules: Mutex::default(), compiled: AtomicUsize::new(0), from_disk: AtomicUsize::new(0) }
    }

    pub(crate) fn counts(&self) -> ShaderCounts {
        ShaderCounts {
            compiled: self.compiled.load(Ordering::Relaxed),
            from_disk: self.from_disk.load(Ordering::Relaxed),
        }
    }

    pub(crate) fn module(
        &self,
        device: &ash::Device,
        name: &str,
        defines: &[(&str, &str)],
        has: &dyn Fn(&str) -> bool,
    ) -> Result<(vk::ShaderModule, KernelInterface)> {
        let src = source(name).ok_or_else(|| anyhow!("no kernel named {name:?} in glsl/"))?;
        let sources = ResolvedSources::new(name, &src);
        let settings = CompileSettings::new(true);
        let key = spirv_key(name, &sources, defines, &settings);
        let mut map = self.modules.lock().map_err(|_| anyhow!("shader cache poisoned"))?;
        if let Some((m, i)) = map.get(&key) {
            return Ok((*m, i.clone()));
        }
        let (spirv, interface) = match self.disk.as_ref().and_then(|d| load_spirv(d, name, &key)) {
            Some(loaded) => {
                self.from_disk.fetch_add(1, Ordering::Relaxed);
                loaded
            }
            None => {
                let spirv = compile(name, &sources, defines, &settings)?;
                self.compiled.fetch_add(1, Ordering::Relaxed);
                let interface = reflect(name, &spirv)?;
                if let Some(d) = &self.disk {
                    store_spirv(d, &key, &spirv);
                }
                (spirv, interface)
            }
        };
        // Before the module exists: refused, not created, when the device lacks a feature.
        interface.check_features(name, has)?;
        let spirv = strip_debug_info(&spirv);
        let info = vk::ShaderModuleCreateInfo::default().code(&spirv);
        // SAFETY: SPIR-V from shaderc (or as shaderc wrote it to the kernel cache: the
        // entry's digest matched).
        let m = unsafe { device.create_shader_module(&info, None) }?;
        map.insert(key, (m, interface.clone()));
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
