//! All-or-nothing output: how every command writes its result.
//!
//! A command's outputs are one result (a model blob and its sidecar; a
//! folder of panels and its `report.json`; plots and `metrics.json`). An
//! [`Output`] collects every file of a result in memory, then
//! [`Output::commit`] writes them in three steps:
//!
//! 1. **stage**: each file is written, flushed and synced under a hidden
//!    temporary name beside its target (`.NAME.tmp-PID-N`, same file
//!    system, so the rename below is atomic). Any failure here (a full
//!    disk, a missing folder, a target that is a directory) removes every
//!    temporary file, and no target has been touched.
//! 2. **lock**: a lock file (`.protogist.lock` in an output folder,
//!    `.NAME.lock` beside the first of loose files) is created exclusively.
//!    A concurrent writer of the same result waits for it (the commit holds
//!    it for milliseconds) and then writes its own complete result after;
//!    one that cannot take it within [`LOCK_WAIT`] fails with
//!    [`HostError::Locked`]. A lock older than [`STALE_LOCK`] (its writer
//!    was killed) is broken.
//! 3. **publish**: every temporary file is renamed onto its target; then,
//!    for an output folder, the files of the previous result that this one
//!    does not replace are removed (they are listed in the folder's
//!    manifest [`MANIFEST`], so no file the user put there is ever
//!    touched), and the new manifest is written last.
//!
//! Single files go through the same path ([`write_atomic`]).

use crate::error::{HostError, Result};
use crate::panels::Panel;
use std::collections::BTreeSet;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant, SystemTime};

/// The manifest of an output folder: the names of the files of its last
/// complete result, one per line, written after all of them.
pub const MANIFEST: &str = ".protogist-result";

/// The lock file of an output folder.
pub const DIR_LOCK: &str = ".protogist.lock";

/// How long a commit waits for a concurrent writer's lock.
pub const LOCK_WAIT: Duration = Duration::from_secs(10);

/// A lock file older than this is a killed writer's, and is broken.
pub const STALE_LOCK: Duration = Duration::from_secs(60);

/// Makes temporary names unique within the process (threads).
static SERIAL: AtomicU64 = AtomicU64::new(0);

/// One result: every file of a command's output, written all or nothing
/// by [`Output::commit`] (see the module documentation).
#[derive(Debug, Default)]
pub struct Output {
    /// The output folder, when the result is a folder.
    dir: Option<PathBuf>,
    /// Target paths and contents, in the order added.
    files: Vec<(PathBuf, Vec<u8>)>,
}

impl Output {
    /// A result of loose files, given by their paths (such as a model blob
    /// and its sidecar). The lock is beside the first file added.
    pub fn files() -> Self {
        Self::default()
    }

    /// A result that is an output folder (created if missing): files are
    /// added by name, and a file of the folder's previous result that this
    /// one does not hold is removed on commit.
    pub fn dir(dir: impl Into<PathBuf>) -> Self {
        Self {
            dir: Some(dir.into()),
            files: Vec::new(),
        }
    }

    /// Adds a file: a path for [`Output::files`], a name inside the folder
    /// for [`Output::dir`]. A later file of the same target replaces it.
    pub fn add(&mut self, path: impl AsRef<Path>, bytes: Vec<u8>) -> &mut Self {
        let path = match &self.dir {
            Some(d) => d.join(path),
            None => path.as_ref().to_path_buf(),
        };
        self.files.retain(|(p, _)| *p != path);
        self.files.push((path, bytes));
        self
    }

    /// Adds `value` as pretty-printed JSON with a final newline.
    ///
    /// # Errors
    /// [`HostError::Serialize`] when `value` cannot be serialised.
    pub fn add_json(
        &mut self,
        path: impl AsRef<Path>,
        value: &impl serde::Serialize,
    ) -> Result<&mut Self> {
        let mut text = serde_json::to_vec_pretty(value).map_err(|e| HostError::Serialize {
            what: path.as_ref().display().to_string(),
            reason: e.to_string(),
        })?;
        text.push(b'\n');
        Ok(self.add(path, text))
    }

    /// Adds every panel as `NAME.png`, encoded now.
    ///
    /// # Errors
    /// [`HostError::Encode`].
    pub fn add_panels(&mut self, panels: &[Panel]) -> Result<&mut Self> {
        for p in panels {
            let bytes = p.encode_png()?;
            self.add(format!("{}.png", p.name), bytes);
        }
        Ok(self)
    }

    /// The output folder of an [`Output::dir`] result.
    pub fn folder(&self) -> Option<&Path> {
        self.dir.as_deref()
    }

    /// The target paths and contents, in the order added (not written).
    pub fn into_files(self) -> Vec<(PathBuf, Vec<u8>)> {
        self.files
    }

    /// The target paths, in the order added.
    pub fn paths(&self) -> Vec<PathBuf> {
        self.files.iter().map(|(p, _)| p.clone()).collect()
    }

    /// Writes the result: stage, lock, publish (module documentation).
    /// Returns the target paths.
    ///
    /// # Errors
    /// [`HostError::Io`] or [`HostError::NotADirectory`] (nothing of this
    /// result is then left under a final name, nor any temporary file),
    /// [`HostError::Locked`] when a concurrent writer holds the lock.
    pub fn commit(self) -> Result<Vec<PathBuf>> {
        if let Some(d) = &self.dir {
            ensure_dir(d)?;
        }
        let Some((first, _)) = self.files.first() else {
            return Ok(Vec::new());
        };
        let lock = match &self.dir {
            Some(d) => d.join(DIR_LOCK),
            None => first.with_file_name(format!(".{}.lock", file_name(first))),
        };
        let mut staged: Vec<(PathBuf, &Path)> = Vec::with_capacity(self.files.len());
        let result = (|| {
            for (path, bytes) in &self.files {
                let tmp = temp_name(path);
                staged.push((tmp.clone(), path));
                write_synced(&tmp, bytes)?;
            }
            // Every target is checked before the first rename, so that no
            // rename can fail halfway for a foreseeable reason.
            if let Some((_, path)) = staged.iter().find(|(_, p)| p.is_dir()) {
                return Err(HostError::io(
                    *path,
                    std::io::Error::other("is a directory, not a file"),
                ));
            }
            let _guard = Lock::take(&lock)?;
            for (tmp, path) in &staged {
                fs::rename(tmp, path).map_err(|e| HostError::io(path, e))?;
            }
            if let Some(d) = &self.dir {
                replace_manifest(d, &self.files)?;
            }
            Ok(())
        })();
        if let Err(e) = result {
            // Best effort: the original error is what the user needs to see.
            for (tmp, _) in &staged {
                let _ = fs::remove_file(tmp);
            }
            return Err(e);
        }
        Ok(self.paths())
    }
}

/// Writes `bytes` to `path` atomically ([`Output`] with one file): to a
/// hidden temporary name beside it, synced, then renamed into place. On
/// failure `path` is untouched and no temporary file is left.
///
/// # Errors
/// As [`Output::commit`].
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut out = Output::files();
    out.add(path, bytes.to_vec());
    out.commit().map(|_| ())
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned())
}

/// A unique hidden temporary name beside `path`.
fn temp_name(path: &Path) -> PathBuf {
    let n = SERIAL.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(
        ".{}.tmp-{}-{n}",
        file_name(path),
        std::process::id()
    ))
}

/// Writes `bytes` to `path` and flushes them to disk.
fn write_synced(path: &Path, bytes: &[u8]) -> Result<()> {
    let io = |e| HostError::io(path, e);
    let mut file = fs::File::create(path).map_err(io)?;
    file.write_all(bytes).map_err(io)?;
    file.sync_all().map_err(io)
}

/// Removes the files of `dir`'s previous result that `files` does not
/// replace, then writes the new manifest.
fn replace_manifest(dir: &Path, files: &[(PathBuf, Vec<u8>)]) -> Result<()> {
    let path = dir.join(MANIFEST);
    let new: BTreeSet<String> = files
        .iter()
        .filter_map(|(p, _)| p.strip_prefix(dir).ok())
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    if let Ok(old) = fs::read_to_string(&path) {
        for name in old.lines().filter(|n| !n.is_empty() && !new.contains(*n)) {
            // Only plain names inside the folder: never follow a manifest out.
            let p = Path::new(name);
            if p.components()
                .all(|c| matches!(c, std::path::Component::Normal(_)))
            {
                let _ = fs::remove_file(dir.join(p));
            }
        }
    }
    let text: String = new.iter().map(|n| format!("{n}\n")).collect();
    let tmp = temp_name(&path);
    let result = write_synced(&tmp, text.as_bytes())
        .and_then(|()| fs::rename(&tmp, &path).map_err(|e| HostError::io(&path, e)));
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// An exclusively created lock file, removed on drop.
struct Lock(PathBuf);

impl Lock {
    fn take(path: &Path) -> Result<Self> {
        let start = Instant::now();
        loop {
            match fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(path)
            {
                Ok(mut f) => {
                    // The holder, for a user who finds the file.
                    let _ = writeln!(f, "{}", std::process::id());
                    return Ok(Self(path.to_path_buf()));
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let age = fs::metadata(path)
                        .and_then(|m| m.modified())
                        .ok()
                        .and_then(|t| SystemTime::now().duration_since(t).ok());
                    if age.is_some_and(|a| a > STALE_LOCK) {
                        let _ = fs::remove_file(path);
                        continue;
                    }
                    if start.elapsed() > LOCK_WAIT {
                        return Err(HostError::Locked {
                            path: path.to_path_buf(),
                            waited: LOCK_WAIT.as_secs(),
                        });
                    }
                    std::thread::sleep(Duration::from_millis(5));
                }
                Err(e) => return Err(HostError::io(path, e)),
            }
        }
    }
}

impl Drop for Lock {
    fn drop(&mut self) {
        let _ = fs::remove_file(&self.0);
    }
}

/// Creates `dir` (and its parents) if needed.
///
/// # Errors
/// [`HostError::NotADirectory`] when `dir` is a file, [`HostError::Io`] when
/// it cannot be created.
pub fn ensure_dir(dir: &Path) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        return Err(HostError::NotADirectory(dir.to_path_buf()));
    }
    fs::create_dir_all(dir).map_err(|e| HostError::io(dir, e))
}

/// Writes every panel as `DIR/{name}.png`, all or nothing: one
/// [`Output`] result .
/// Returns the final paths.
///
/// # Errors
/// [`HostError::Encode`] or [`HostError::Io`]; `dir` is then left without
/// any panel of this call.
pub fn write_panels(dir: &Path, panels: &[Panel]) -> Result<Vec<PathBuf>> {
    let mut out = Output::dir(dir);
    out.add_panels(panels)?;
    out.commit()
}

/// Columns of the overview montage.
const OVERVIEW_COLUMNS: usize = 4;

/// Adds the overview montage to `panels`, writes them all into `dir`, and
/// appends the closing summary lines (time and output directory).
///
/// # Errors
/// As [`write_panels`].
pub fn finish(
    dir: &std::path::Path,
    panels: Vec<crate::panels::Panel>,
    summary: &mut crate::summary::Summary,
    start: std::time::Instant,
) -> crate::error::Result<()> {
    finish_with(crate::output::Output::dir(dir), panels, summary, start)
}

/// As [`finish`], the panels committed with the other files of `out` (an
/// [`Output::dir`](crate::output::Output::dir) result, such as a report) as
/// one result.
///
/// # Errors
/// As [`crate::output::Output::commit`].
pub fn finish_with(
    mut out: crate::output::Output,
    mut panels: Vec<crate::panels::Panel>,
    summary: &mut crate::summary::Summary,
    start: std::time::Instant,
) -> crate::error::Result<()> {
    let overview = crate::panels::montage(&panels, OVERVIEW_COLUMNS);
    panels.push(crate::panels::Panel::new("overview", overview));
    out.add_panels(&panels)?;
    let dir = out.folder().map(std::path::Path::to_path_buf);
    let written = out.commit()?;
    let pngs = written
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .count();
    summary.push(
        "total time",
        format!("{:.1} ms", start.elapsed().as_secs_f64() * 1e3),
    );
    summary.push(
        "output",
        format!("{} ({pngs} PNG files)", dir.unwrap_or_default().display()),
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_folder_result_replaces_the_previous_one_and_spares_other_files() {
        let dir = tempfile::tempdir().unwrap();
        fs::write(dir.path().join("mine.txt"), b"user").unwrap();
        let mut a = Output::dir(dir.path());
        a.add("a.txt", b"1".to_vec()).add("gone.txt", b"1".to_vec());
        a.commit().unwrap();
        let mut b = Output::dir(dir.path());
        b.add("a.txt", b"2".to_vec());
        b.commit().unwrap();
        assert_eq!(names(dir.path()), [MANIFEST, "a.txt", "mine.txt"]);
        assert_eq!(fs::read(dir.path().join("a.txt")).unwrap(), b"2");
        assert_eq!(fs::read(dir.path().join("mine.txt")).unwrap(), b"user");
    }

    #[test]
    fn a_failed_commit_leaves_the_previous_result_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let mut a = Output::dir(dir.path());
        a.add("a.txt", b"old".to_vec());
        a.commit().unwrap();
        let before = names(dir.path());
        let mut b = Output::dir(dir.path());
        // The second file cannot be staged: its folder does not exist.
        b.add("a.txt", b"new".to_vec())
            .add("missing/b.txt", b"new".to_vec());
        assert!(matches!(b.commit(), Err(HostError::Io { .. })));
        assert_eq!(names(dir.path()), before);
        assert_eq!(fs::read(dir.path().join("a.txt")).unwrap(), b"old");
    }

    #[test]
    fn a_target_that_is_a_directory_fails_before_any_rename() {
        let dir = tempfile::tempdir().unwrap();
        let blob = dir.path().join("model.bin");
        fs::create_dir(&blob).unwrap();
        let mut out = Output::files();
        out.add(dir.path().join("model.bin.json"), b"{}".to_vec())
            .add(&blob, b"PGML".to_vec());
        assert!(out.commit().is_err());
        assert_eq!(names(dir.path()), ["model.bin"]);
    }

    #[test]
    fn concurrent_writers_leave_one_complete_result() {
        let dir = tempfile::tempdir().unwrap();
        let threads: Vec<_> = (0..6u8)
            .map(|k| {
                let d = dir.path().to_path_buf();
                std::thread::spawn(move || {
                    let mut out = Output::files();
                    for name in ["x", "y", "z"] {
                        out.add(d.join(name), vec![k; 4096]);
                    }
                    out.commit()
                })
            })
            .collect();
        for t in threads {
            t.join().unwrap().unwrap();
        }
        let read = |n: &str| fs::read(dir.path().join(n)).unwrap();
        assert_eq!(read("x"), read("y"));
        assert_eq!(read("y"), read("z"));
        assert_eq!(names(dir.path()), ["x", "y", "z"]);
    }

    #[test]
    fn a_held_lock_is_waited_for_and_a_stale_one_broken() {
        let dir = tempfile::tempdir().unwrap();
        let lock = dir.path().join(".f.lock");
        fs::write(&lock, b"1").unwrap();
        let old = SystemTime::now() - STALE_LOCK - Duration::from_secs(5);
        fs::File::options()
            .write(true)
            .open(&lock)
            .unwrap()
            .set_modified(old)
            .unwrap();
        write_atomic(&dir.path().join("f"), b"ok").unwrap();
        assert_eq!(names(dir.path()), ["f"]);
    }

    #[test]
    fn a_failed_write_leaves_no_panel_of_the_run() {
        let dir = tempfile::tempdir().unwrap();
        let img = image::DynamicImage::ImageRgb8(image::RgbImage::new(2, 2));
        let panels = [
            Panel::new("first", img.clone()),
            // A name inside a missing sub-directory fails on write.
            Panel::new("missing/second", img),
        ];
        assert!(write_panels(dir.path(), &panels).is_err());
        let left: Vec<_> = fs::read_dir(dir.path()).unwrap().collect();
        assert!(left.is_empty(), "{left:?}");
    }
}
