//! Atomic file replacement: write a temporary file next to the destination, flush it to
//! disk, then rename it over the destination.

use anyhow::{anyhow, bail, Result};
use std::io::{BufWriter, Write};
use std::path::Path;

/// Writes `path` atomically with `fill`, which receives a buffered writer onto a temporary
/// file in the same directory (hidden name `.<file>.XXXXXX.tmp`). The temporary file is
/// removed if `fill` or any later step fails; the destination is replaced only by a complete
/// file that has been synced to disk. `what` names the kind of file in error messages.
///
/// Every error is one line that names `path`.
pub(crate) fn write_atomic(path: &Path, what: &str, fill: impl FnOnce(&mut dyn Write) -> Result<()>) -> Result<()> {
    let shown = path.display();
    let Some(file_name) = path.file_name() else {
        bail!("cannot write {what} {shown}: the path does not name a file");
    };
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        if dir.exists() {
            bail!("cannot write {what} {shown}: {} is not a directory", dir.display());
        }
        bail!("cannot write {what} {shown}: directory {} does not exist", dir.display());
    }
    if path.is_dir() {
        bail!("cannot write {what} {shown}: it is a directory");
    }

    let prefix = format!(".{}.", file_name.to_string_lossy());
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    {
        // NamedTempFile defaults to 0600; ask for 0666 so the user's umask decides, as for
        // any ordinary file.
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let tmp = builder
        .tempfile_in(dir)
        .map_err(|e| anyhow!("cannot write {what} {shown}: cannot create a file in {}: {e}", dir.display()))?;

    {
        let mut w = BufWriter::with_capacity(1 << 20, tmp.as_file());
        fill(&mut w).map_err(|e| anyhow!("cannot write {what} {shown}: {e:#}"))?;
        w.flush().map_err(|e| anyhow!("cannot write {what} {shown}: {e}"))?;
    }
    tmp.as_file().sync_all().map_err(|e| anyhow!("cannot write {what} {shown}: {e}"))?;
    tmp.persist(path).map_err(|e| anyhow!("cannot write {what} {shown}: {}", e.error))?;
    Ok(())
}
