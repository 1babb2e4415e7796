//! The kernel cache on disk (docs/kernel-cache.md): what a later process can reuse of the
//! kernels an earlier one built, so that repeated renders do not pay for compiling them.
//!
//! One folder ([`default_dir`]) holds two kinds of file:
//! * `spirv-<key>.bin`, one per kernel variant: the SPIR-V shaderc produced, keyed by
//!   everything that determines it (src/gpu/shader.rs, `spirv_key`);
//! * `pipelines-<key>.bin`, one per device and driver: the driver's VkPipelineCache data
//!   (src/gpu/pipeline_cache.rs), keyed by the device and driver identity.
//!
//! Every file is an entry: [`MAGIC`], the 32-byte key, the SHA-256 of the payload, the
//! payload. A file whose magic, key or digest does not match (truncated, corrupt, written
//! by another format) is a miss and is overwritten by the next write, so nothing corrupt
//! ever reaches reflection or the driver. Writes go to a temporary file in the same folder
//! that is then renamed over the entry, so a concurrent reader sees the old or the new
//! file, never half of one. A folder that cannot be created, read or written costs one
//! warning per process, and the kernels are then built without it.

use std::ffi::OsString;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, SystemTime};

use sha2::{Digest, Sha256};

/// The first bytes of every entry; the digit is the format's version (also in every key).
const MAGIC: &[u8; 8] = b"VKVCMKC1";
const KEY_BYTES: usize = 32;
const HEADER_BYTES: usize = MAGIC.len() + KEY_BYTES + KEY_BYTES;

/// Prefix of the temporary files of [`CacheDir::write`]; ones older than
/// [`STALE_TEMP_AGE`] are left over from a process killed mid-write and are removed.
const TEMP_PREFIX: &str = ".vkvcm-tmp-";
const STALE_TEMP_AGE: Duration = Duration::from_secs(3600);

/// A cache key: the SHA-256 of labelled fields ([`KeyBuilder`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct Key([u8; KEY_BYTES]);

impl Key {
    /// The key in lowercase hexadecimal (file names).
    pub fn hex(&self) -> String {
        self.0.iter().map(|b| format!("{b:02x}")).collect()
    }
}

/// Hashes the fields that determine a cached thing into a [`Key`]. Each field is its
/// label and its value, each preceded by its length, so that no two different lists of
/// fields hash the same bytes. Every key also covers the entry format and vkvcm's version.
pub(crate) struct KeyBuilder(Sha256);

impl KeyBuilder {
    /// A key of the kind `kind` (e.g. `"spirv"`).
    pub fn new(kind: &str) -> KeyBuilder {
        let mut k = KeyBuilder(Sha256::new());
        k.field("format", MAGIC);
        k.field("vkvcm", env!("CARGO_PKG_VERSION"));
        k.field("kind", kind);
        k
    }

    pub fn field(&mut self, label: &str, value: impl AsRef<[u8]>) -> &mut KeyBuilder {
        for part in [label.as_bytes(), value.as_ref()] {
            self.0.update((part.len() as u64).to_le_bytes());
            self.0.update(part);
        }
        self
    }

    pub fn finish(self) -> Key {
        Key(self.0.finalize().into())
    }
}

/// The folder of the kernel cache when nothing else says: `$VKVCM_CACHE_DIR` if set
/// (set and empty: no cache, `None`), else `$XDG_CACHE_HOME/vkvcm`, else
/// `$HOME/.cache/vkvcm`; `None` when none of them is usable.
pub fn default_dir() -> Option<PathBuf> {
    dir_from(std::env::var_os("VKVCM_CACHE_DIR"), std::env::var_os("XDG_CACHE_HOME"), std::env::var_os("HOME"))
}

/// [`default_dir`] from the values of those three variables. As the XDG base-directory
/// specification says, a relative `XDG_CACHE_HOME` is ignored.
fn dir_from(vkvcm: Option<OsString>, xdg_cache_home: Option<OsString>, home: Option<OsString>) -> Option<PathBuf> {
    if let Some(dir) = vkvcm {
        return (!dir.is_empty()).then(|| PathBuf::from(dir));
    }
    if let Some(xdg) = xdg_cache_home.map(PathBuf::from).filter(|p| p.is_absolute()) {
        return Some(xdg.join("vkvcm"));
    }
    home.filter(|h| !h.is_empty()).map(|h| PathBuf::from(h).join(".cache").join("vkvcm"))
}

/// Whether this process has printed its kernel-cache warning.
static WARNED: AtomicBool = AtomicBool::new(false);

/// Prints `message` as a warning unless one was printed already in this process.
fn warn_once(dir: &Path, message: &str) {
    if !WARNED.swap(true, Ordering::Relaxed) {
        eprintln!(
            "warning: kernel cache {}: {message}; kernels are built without it \
             (VKVCM_CACHE_DIR chooses another folder, --no-kernel-cache turns it off)",
            dir.display()
        );
    }
}

/// The kernel cache's folder, as one `Gpu` uses it.
#[derive(Clone, Debug)]
pub(crate) struct CacheDir {
    dir: PathBuf,
}

impl CacheDir {
    pub(crate) fn new(dir: PathBuf) -> CacheDir {
        CacheDir { dir }
    }

    pub(crate) fn path(&self) -> &Path {
        &self.dir
    }

    /// The payload of the entry `file` if it holds `key` and is intact; `None` when it is
    /// missing, unreadable (one warning), or not an intact entry of `key`.
    pub(crate) fn read(&self, file: &str, key: &Key) -> Option<Vec<u8>> {
        let bytes = match std::fs::read(self.dir.join(file)) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return None,
            Err(e) => {
                warn_once(&self.dir, &format!("cannot read {file}: {e}"));
                return None;
            }
        };
        unseal(key, &bytes).map(<[u8]>::to_vec)
    }

    /// Writes `payload` as the entry `file` of `key`, atomically; a failure costs one
    /// warning per process. Returns whether it was written.
    pub(crate) fn write(&self, file: &str, key: &Key, payload: &[u8]) -> bool {
        let written = (|| -> std::io::Result<()> {
            std::fs::create_dir_all(&self.dir)?;
            let mut tmp = tempfile::Builder::new().prefix(TEMP_PREFIX).tempfile_in(&self.dir)?;
            tmp.write_all(&seal(key, payload))?;
            tmp.persist(self.dir.join(file)).map_err(|e| e.error)?;
            Ok(())
        })();
        match written {
            Ok(()) => true,
            Err(e) => {
                warn_once(&self.dir, &format!("cannot write {file}: {e}"));
                false
            }
        }
    }

    /// Keeps the entries whose names start with `prefix` within `max_bytes` in all, by
    /// removing the least recently written first (never `keep`), and removes temporary
    /// files left over from killed processes. Best effort: errors are ignored (another
    /// process may be pruning at the same time).
    pub(crate) fn prune(&self, prefix: &str, max_bytes: u64, keep: &str) {
        let Ok(entries) = std::fs::read_dir(&self.dir) else { return };
        let now = SystemTime::now();
        let mut files = Vec::new();
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            let Ok(meta) = e.metadata() else { continue };
            let modified = meta.modified().unwrap_or(now);
            if name.starts_with(TEMP_PREFIX) {
                if now.duration_since(modified).is_ok_and(|age| age > STALE_TEMP_AGE) {
                    let _ = std::fs::remove_file(e.path());
                }
            } else if name.starts_with(prefix) && name != keep && meta.is_file() {
                files.push((modified, meta.len(), e.path()));
            }
        }
        let kept = std::fs::metadata(self.dir.join(keep)).map_or(0, |m| m.len());
        let mut total: u64 = kept + files.iter().map(|(_, len, _)| len).sum::<u64>();
        files.sort();
        for (_, len, path) in files {
            if total <= max_bytes {
                break;
            }
            if std::fs::remove_file(path).is_ok() {
                total -= len;
            }
        }
    }
}

/// `payload` as an entry of `key`.
fn seal(key: &Key, payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER_BYTES + payload.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&key.0);
    out.extend_from_slice(&Sha256::digest(payload));
    out.extend_from_slice(payload);
    out
}

/// The payload of `entry` if it is an intact entry of `key`.
fn unseal<'a>(key: &Key, entry: &'a [u8]) -> Option<&'a [u8]> {
    if entry.len() < HEADER_BYTES || &entry[..MAGIC.len()] != MAGIC {
        return None;
    }
    let (stored_key, rest) = entry[MAGIC.len()..].split_at(KEY_BYTES);
    let (digest, payload) = rest.split_at(KEY_BYTES);
    (stored_key == key.0 && digest == Sha256::digest(payload).as_slice()).then_some(payload)
}

/// The SHA-256 of `bytes` (to tell whether a file changed).
pub(crate) fn digest(bytes: &[u8]) -> [u8; KEY_BYTES] {
    Sha256::digest(bytes).into()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(text: &str) -> Key {
        let mut k = KeyBuilder::new("test");
        k.field("text", text);
        k.finish()
    }

    #[test]
    fn fields_are_not_ambiguous() {
        let of = |fields: &[(&str, &str)]| {
            let mut k = KeyBuilder::new("test");
            for (l, v) in fields {
                k.field(l, v);
            }
            k.finish()
        };
        assert_ne!(of(&[("a", "bc")]), of(&[("ab", "c")]));
        assert_ne!(of(&[("a", "b"), ("c", "")]), of(&[("a", "bc")]));
        assert_eq!(of(&[("a", "b")]), of(&[("a", "b")]));
        assert_ne!(KeyBuilder::new("x").finish(), KeyBuilder::new("y").finish());
    }

    #[test]
    fn an_entry_opens_only_intact_and_with_its_key() {
        let k = key("one");
        let entry = seal(&k, b"payload bytes");
        assert_eq!(unseal(&k, &entry), Some(&b"payload bytes"[..]));
        assert_eq!(unseal(&key("two"), &entry), None);
        for len in 0..entry.len() {
            assert_eq!(unseal(&k, &entry[..len]), None, "truncated to {len}");
        }
        for i in 0..entry.len() {
            let mut bad = entry.clone();
            bad[i] ^= 0x10;
            assert_eq!(unseal(&k, &bad), None, "byte {i} flipped");
        }
        assert_eq!(unseal(&k, &seal(&k, b"")), Some(&b""[..]));
    }

    #[test]
    fn the_folder_follows_the_environment() {
        let s = |v: &str| Some(OsString::from(v));
        assert_eq!(dir_from(s("/c"), s("/x"), s("/h")), Some(PathBuf::from("/c")));
        assert_eq!(dir_from(s(""), s("/x"), s("/h")), None);
        assert_eq!(dir_from(None, s("/x"), s("/h")), Some(PathBuf::from("/x/vkvcm")));
        assert_eq!(dir_from(None, s("relative"), s("/h")), Some(PathBuf::from("/h/.cache/vkvcm")));
        assert_eq!(dir_from(None, s(""), s("/h")), Some(PathBuf::from("/h/.cache/vkvcm")));
        assert_eq!(dir_from(None, None, s("/h")), Some(PathBuf::from("/h/.cache/vkvcm")));
        assert_eq!(dir_from(None, None, None), None);
        assert_eq!(dir_from(None, None, s("")), None);
    }

    #[test]
    fn write_then_read_and_prune() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = CacheDir::new(tmp.path().join("made/by/write"));
        let (a, b) = (key("a"), key("b"));
        assert_eq!(dir.read("x-a.bin", &a), None);
        assert!(dir.write("x-a.bin", &a, &[1; 100]));
        std::thread::sleep(Duration::from_millis(20));
        assert!(dir.write("x-b.bin", &b, &[2; 100]));
        assert_eq!(dir.read("x-a.bin", &a), Some(vec![1; 100]));
        assert_eq!(dir.read("x-a.bin", &b), None, "an entry answers only its own key");
        // Room for one entry: the older one goes, the one just written stays.
        dir.prune("x-", (HEADER_BYTES + 150) as u64, "x-b.bin");
        assert_eq!(dir.read("x-a.bin", &a), None);
        assert_eq!(dir.read("x-b.bin", &b), Some(vec![2; 100]));
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, vec![OsString::from("x-b.bin")], "no temporary file is left");
    }

    #[test]
    fn an_unwritable_folder_is_a_failed_write_not_a_panic() {
        let tmp = tempfile::tempdir().unwrap();
        let file = tmp.path().join("a-file");
        std::fs::write(&file, b"not a folder").unwrap();
        let dir = CacheDir::new(file.join("cache"));
        assert!(!dir.write("x.bin", &key("a"), b"data"));
        assert_eq!(dir.read("x.bin", &key("a")), None);
        dir.prune("x", 0, "x.bin");
    }
}
