//! Reading and writing cbvh's files: [`IoError`], the one error every
//! part of the crate reports a failed read or write with (the file's path
//! and the operating system's error), and atomic saves for every file cbvh
//! writes (codec files, meshes, images, reports, plots).
//!
//! An atomic save writes the bytes to a temporary file beside the target,
//! flushes them to disk and renames the temporary file over the target. A
//! reader never sees a half-written file, a process that has the old file
//! memory-mapped keeps its (unlinked) old pages instead of dying with
//! SIGBUS when the file is rewritten in place, and a writer that fails or
//! is dropped half way leaves the old file (or none) under the name.
//!
//! [`atomic_write`] saves bytes already in memory; [`AtomicFile`] is a
//! buffered [`Write`] for output produced as it goes (meshes, images),
//! made visible by [`AtomicFile::commit`]. [`save`] and [`read`] are
//! [`atomic_write`] and [`std::fs::read`] reporting an [`IoError`].

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// A file could not be opened, read, written or renamed: the one I/O
/// error of the crate. Every codec's error, [`MeshError`](crate::MeshError)
/// and the rest wrap it, so that a message always names the file.
#[derive(Debug, thiserror::Error)]
#[error("{}: {source}", path.display())]
pub struct IoError {
    /// The file (or directory) the operation was on.
    pub path: PathBuf,
    /// The operating system's error.
    #[source]
    pub source: std::io::Error,
}

impl IoError {
    /// `source` on `path`.
    pub fn new(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self {
            path: path.into(),
            source,
        }
    }

    /// A closure turning an [`std::io::Error`] on `path` into an
    /// [`IoError`] (for `map_err`).
    pub fn at(path: &Path) -> impl Fn(std::io::Error) -> IoError + Copy + '_ {
        move |source| IoError::new(path, source)
    }
}

/// A copy with the same path, kind and message ([`std::io::Error`] is not
/// `Clone`; the copy's error is built from the kind and the message).
impl Clone for IoError {
    fn clone(&self) -> Self {
        Self::new(
            &self.path,
            std::io::Error::new(self.source.kind(), self.source.to_string()),
        )
    }
}

/// The same path, and an error of the same kind and message.
impl PartialEq for IoError {
    fn eq(&self, other: &Self) -> bool {
        self.path == other.path
            && self.source.kind() == other.source.kind()
            && self.source.to_string() == other.source.to_string()
    }
}

/// [`atomic_write`], reporting an [`IoError`] naming `path`.
pub fn save(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    atomic_write(path, bytes).map_err(IoError::at(path))
}

/// The whole file at `path`, or an [`IoError`] naming it.
pub fn read(path: &Path) -> Result<Vec<u8>, IoError> {
    std::fs::read(path).map_err(IoError::at(path))
}

/// Writes `bytes` to `path` atomically (see the module docs). On error the
/// temporary file is removed and `path` is untouched.
pub fn atomic_write(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut f = AtomicFile::create(path)?;
    f.write_all(bytes)?;
    f.commit()
}

/// A file written under a temporary name beside its target and renamed
/// over it by [`commit`](Self::commit). Dropped without a commit (an
/// error, a panic), it removes its temporary file and leaves the target
/// as it was.
pub struct AtomicFile {
    /// `None` once committed.
    out: Option<BufWriter<File>>,
    tmp: PathBuf,
    path: PathBuf,
}

impl AtomicFile {
    /// Starts writing `path`: creates the temporary file beside it (so an
    /// unwritable directory fails here, before any work).
    pub fn create(path: &Path) -> std::io::Result<Self> {
        let tmp = temp_beside(path);
        let f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)?;
        Ok(Self {
            out: Some(BufWriter::with_capacity(1 << 20, f)),
            tmp,
            path: path.to_path_buf(),
        })
    }

    /// The target: the name the file gets when committed.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flushes the bytes to disk and renames the file over the target. On
    /// error the temporary file is removed and the target is untouched.
    pub fn commit(mut self) -> std::io::Result<()> {
        let out = self.out.take().expect("an AtomicFile commits once");
        let result = (|| {
            let f = out.into_inner().map_err(|e| e.into_error())?;
            f.sync_all()?;
            drop(f);
            std::fs::rename(&self.tmp, &self.path)
        })();
        if result.is_err() {
            std::fs::remove_file(&self.tmp).ok();
        }
        result
    }

    fn out(&mut self) -> &mut BufWriter<File> {
        self.out.as_mut().expect("not committed")
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.out().write(buf)
    }

    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        self.out().write_all(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.out().flush()
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.out.take().is_some() {
            std::fs::remove_file(&self.tmp).ok();
        }
    }
}

/// `dir/.name.tmp-PID-N`: in the target's directory (a rename does not
/// cross file systems), unique per process and call.
fn temp_beside(path: &Path) -> PathBuf {
    use std::sync::atomic::{AtomicU64, Ordering};
    static N: AtomicU64 = AtomicU64::new(0);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "cbvh".into());
    let n = N.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}.tmp-{}-{n}", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Asserts that `dir` holds one file: no temporary file was left.
    fn only_one_file_in(dir: &Path) {
        let names: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names.len(), 1, "{names:?}");
    }

    #[test]
    fn atomic_write_replaces_and_leaves_no_temp_file() {
        let dir = std::env::temp_dir().join(format!("cbvh-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("x.bin");
        atomic_write(&p, b"first").unwrap();
        atomic_write(&p, b"second").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"second");
        only_one_file_in(&dir);
        // A target in a missing directory is an error, not a panic.
        assert!(atomic_write(&dir.join("no/such/x.bin"), b"x").is_err());
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn an_uncommitted_file_leaves_the_target_and_no_temp_file() {
        let dir = std::env::temp_dir().join(format!("cbvh-atomic-drop-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("x.bin");
        atomic_write(&p, b"old").unwrap();
        {
            let mut f = AtomicFile::create(&p).unwrap();
            f.write_all(b"half of the new").unwrap();
            // Before the commit the target still holds the old bytes.
            assert_eq!(std::fs::read(&p).unwrap(), b"old");
        }
        assert_eq!(std::fs::read(&p).unwrap(), b"old");
        let mut f = AtomicFile::create(&p).unwrap();
        f.write_all(b"new").unwrap();
        f.commit().unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"new");
        only_one_file_in(&dir);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn io_errors_name_the_file_and_copy_equal() {
        let dir = std::env::temp_dir().join(format!("cbvh-ioerror-{}", std::process::id()));
        let missing = dir.join("no/such/x.bin");
        let e = read(&missing).unwrap_err();
        assert_eq!(e.path, missing);
        assert_eq!(e.source.kind(), std::io::ErrorKind::NotFound);
        let shown = e.to_string();
        assert!(
            shown.starts_with(&format!("{}: ", missing.display())),
            "{shown}"
        );
        assert_eq!(e.clone(), e);
        assert_eq!(e.clone().to_string(), shown);
        let w = save(&missing, b"x").unwrap_err();
        assert_eq!(w.path, missing);
        assert_ne!(
            w,
            IoError::new(dir.join("other"), std::io::ErrorKind::NotFound.into())
        );
        assert!(!missing.exists());
    }
}
