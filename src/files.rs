//! Files written whole or not at all: every file the library and the command line write goes
//! through [`write_replacing`], so a failed write leaves whatever was there untouched.

use std::path::Path;

use crate::{Error, Result};

/// Writes the file at `path` so that a failed write leaves whatever was there untouched:
/// `write` fills a new file beside it (in the same folder, so the rename stays on one file
/// system), which replaces `path` only once complete; on failure it is removed. An existing
/// `path` that is not a regular file (a folder, a device, a pipe, a link) or that is read-only is
/// refused before anything is written.
pub fn write_replacing(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let tmp = partial_path(path)?;
    let result =
        write(&tmp).and_then(|()| std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e)));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Checks, before any work, that [`write_replacing`] can write `path`: what it refuses is
/// refused, and the folder must exist and take a new file (one is created and removed).
pub fn check_writable(path: &Path) -> Result<()> {
    let tmp = partial_path(path)?;
    std::fs::File::create(&tmp).map_err(|e| Error::io(path, e))?;
    let _ = std::fs::remove_file(&tmp);
    Ok(())
}

/// The new file [`write_replacing`] fills beside `path`, once `path` is known not to be refused.
fn partial_path(path: &Path) -> Result<std::path::PathBuf> {
    let refuse = |why: &str| Error::Io {
        path: path.into(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidInput, why.to_string()),
    };
    if let Ok(meta) = std::fs::symlink_metadata(path) {
        if !meta.file_type().is_file() {
            return Err(refuse("exists and is not a regular file; not replaced"));
        }
        if meta.permissions().readonly() {
            return Err(refuse("exists and is read-only; not replaced"));
        }
    }
    let name = path.file_name().ok_or_else(|| refuse("names no file"))?.to_string_lossy();
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let ext = path.extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
    Ok(dir.join(format!(".{name}.{}.partial{ext}", std::process::id())))
}

/// Writes `bytes` to `path` with [`write_replacing`].
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_replacing(path, |tmp| std::fs::write(tmp, bytes).map_err(|e| Error::io(path, e)))
}
