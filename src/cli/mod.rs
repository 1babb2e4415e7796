//! The subcommands of the `vkvcm` binary, one module each.

pub mod bench;
pub mod converge;
pub mod diff;
pub mod progress;
pub mod render;

use anyhow::{Context, Result};

/// Writes `value` as pretty JSON, atomically.
pub fn write_json<T: serde::Serialize>(p: &std::path::Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    let dir = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
    let mut f = tempfile::NamedTempFile::new_in(dir).with_context(|| format!("cannot write {}", p.display()))?;
    std::io::Write::write_all(&mut f, text.as_bytes())?;
    f.persist(p).with_context(|| format!("cannot write {}", p.display()))?;
    Ok(())
}
