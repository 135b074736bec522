//! Atomic file writes: write to a temporary file in the destination's
//! directory, flush and `fsync` it, then rename it over the final name.
//!
//! A rename within one directory is atomic on POSIX file systems, so a reader
//! (or a rerun after a crash) sees either the old file, or the complete new
//! one — never a truncated one. If the writer fails, or the process is killed
//! part-way, nothing appears under the final name; the temporary file
//! (`.NAME.XXXXXX.tmp`) is removed on error and on drop. Files are created
//! with mode 0666 minus the process umask, as `File::create` would.

use std::fs::File;
use std::io::{BufWriter, Seek, Write};
use std::path::{Path, PathBuf};

use crate::{Error, Result};

/// A file being written under a temporary name, to appear under its final
/// name only on [`AtomicFile::commit`]. Dropping it uncommitted removes the
/// temporary file.
///
/// Use it directly to commit several files together (ENVI `.img` + `.hdr`):
/// write all, then commit in order; otherwise use [`write_atomic`].
pub struct AtomicFile {
    path: PathBuf,
    writer: BufWriter<tempfile::NamedTempFile>,
}

impl AtomicFile {
    /// Start writing `path` (its directory must exist).
    pub fn create(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref().to_path_buf();
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let name = path
            .file_name()
            .ok_or_else(|| {
                Error::invalid("output path", format!("`{}` names no file", path.display()))
            })?
            .to_string_lossy()
            .into_owned();
        let prefix = format!(".{name}.");
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        // The final file gets the permissions of any newly created file
        // (0666 minus the umask, usually 0644), not tempfile's private 0600.
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let tmp = builder.tempfile_in(&dir).map_err(|e| Error::io(&path, e))?;
        Ok(AtomicFile {
            path,
            writer: BufWriter::with_capacity(1 << 20, tmp),
        })
    }

    /// The final path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The (buffered, seekable) writer of the temporary file.
    pub fn writer(&mut self) -> &mut BufWriter<tempfile::NamedTempFile> {
        &mut self.writer
    }

    /// Flush, `fsync` and rename the file to its final name, replacing any
    /// existing file there.
    pub fn commit(self) -> Result<()> {
        let path = self.path;
        let tmp = self
            .writer
            .into_inner()
            .map_err(|e| Error::io(&path, e.into_error()))?;
        tmp.as_file().sync_all().map_err(|e| Error::io(&path, e))?;
        tmp.persist(&path).map_err(|e| Error::io(&path, e.error))?;
        // Make the rename itself durable (POSIX: fsync the directory).
        #[cfg(unix)]
        if let Some(dir) = path.parent() {
            let dir = if dir.as_os_str().is_empty() {
                Path::new(".")
            } else {
                dir
            };
            if let Ok(d) = File::open(dir) {
                let _ = d.sync_all();
            }
        }
        Ok(())
    }
}

/// A writer that is both [`Write`] and [`Seek`] (the EXR encoder seeks).
pub trait WriteSeek: Write + Seek {}
impl<T: Write + Seek> WriteSeek for T {}

/// Write `path` atomically: `write` fills a temporary file in the same
/// directory, which is then flushed, `fsync`ed and renamed to `path`. If
/// `write` returns an error, no file appears under `path` (an existing one
/// is left untouched) and the temporary file is removed.
pub fn write_atomic<T>(
    path: impl AsRef<Path>,
    write: impl FnOnce(&mut dyn WriteSeek) -> Result<T>,
) -> Result<T> {
    let mut file = AtomicFile::create(path)?;
    let value = write(file.writer())?;
    file.commit()?;
    Ok(value)
}
