//! Atomic file writes: a file is written next to its destination under a
//! temporary name and renamed over it only when complete, so a run that is
//! killed, interrupted or fails half-way never destroys an earlier good file
//! (a leftover `.<name>.<pid>.tmp` at most remains).

use std::fs::File;
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{CoreError, Result};

/// Distinguishes the temporary files of one process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// A file being written atomically: [`AtomicFile::commit`] renames it into
/// place; dropping it uncommitted removes the temporary file and leaves the
/// destination as it was.
#[derive(Debug)]
pub struct AtomicFile {
    file: Option<File>,
    temporary: PathBuf,
    destination: PathBuf,
}

impl AtomicFile {
    /// Starts writing `destination`: a temporary file in the same folder.
    ///
    /// # Errors
    ///
    /// [`CoreError::Io`] naming `destination` when it is a directory or its
    /// folder cannot be written.
    pub fn create(destination: &Path) -> Result<AtomicFile> {
        if destination.is_dir() {
            return Err(CoreError::io(
                io::Error::new(
                    io::ErrorKind::IsADirectory,
                    "is a directory, not a file name",
                ),
                Some(destination),
            ));
        }
        let name = destination
            .file_name()
            .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
        let temporary = destination.with_file_name(format!(
            ".{name}.{}.{}.tmp",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        let file = File::create(&temporary).map_err(|e| CoreError::io(e, Some(destination)))?;
        Ok(AtomicFile {
            file: Some(file),
            temporary,
            destination: destination.to_path_buf(),
        })
    }

    /// The file's final name.
    pub fn destination(&self) -> &Path {
        &self.destination
    }

    /// The name it is written under until [`AtomicFile::commit`] (in the destination's
    /// folder): to read back what was written before it replaces anything.
    pub fn temporary(&self) -> &Path {
        &self.temporary
    }

    /// Flushes the data to disk and renames the file into place.
    ///
    /// # Errors
    ///
    /// [`CoreError::Io`] naming the destination when the data cannot be
    /// synced or the rename fails (the temporary file is then removed).
    pub fn commit(mut self) -> Result<()> {
        let file = self.file.take();
        let result = (|| {
            if let Some(mut f) = file {
                f.flush()?;
                f.sync_all()?;
            }
            std::fs::rename(&self.temporary, &self.destination)
        })();
        result.map_err(|e| {
            let _ = std::fs::remove_file(&self.temporary);
            CoreError::io(e, Some(&self.destination))
        })
    }

    fn file(&mut self) -> io::Result<&mut File> {
        self.file
            .as_mut()
            .ok_or_else(|| io::Error::other("the file is already committed"))
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.file()?.write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.file()?.flush()
    }
}

impl Seek for AtomicFile {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        self.file()?.seek(pos)
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.file.take().is_some() {
            let _ = std::fs::remove_file(&self.temporary);
        }
    }
}

/// Commits a buffered atomic file: flushes the buffer, then
/// [`AtomicFile::commit`].
///
/// # Errors
///
/// [`CoreError::Io`] naming the destination.
pub fn commit_buffered(writer: BufWriter<AtomicFile>) -> Result<()> {
    let destination = writer.get_ref().destination().to_path_buf();
    writer
        .into_inner()
        .map_err(|e| CoreError::io(e.into_error(), Some(&destination)))?
        .commit()
}

/// Writes `bytes` to `path` atomically.
///
/// # Errors
///
/// [`CoreError::Io`] naming `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut f = AtomicFile::create(path)?;
    f.write_all(bytes)
        .map_err(|e| CoreError::io(e, Some(path)))?;
    f.commit()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("modelgap-atomic-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn an_uncommitted_file_leaves_the_old_one_and_no_litter() {
        let d = dir("drop");
        let path = d.join("data.csv");
        std::fs::write(&path, "old").unwrap();
        {
            let mut f = AtomicFile::create(&path).unwrap();
            f.write_all(b"half of the new").unwrap();
        }
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
        write_atomic(&path, b"new").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_directory_is_refused_by_name() {
        let d = dir("isdir");
        let e = write_atomic(&d, b"x").unwrap_err().to_string();
        assert!(
            e.contains("is a directory") && e.contains(&d.display().to_string()),
            "{e}"
        );
        std::fs::remove_dir_all(&d).unwrap();
    }
}
