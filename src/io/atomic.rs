//! Writing files so that a reader sees the old bytes or the new, never half of either, and a
//! group of files (an OBJ and its `.mtl`, an output and its stats) changes as one.
//!
//! Each file's new bytes go to a temporary file in the same folder, named
//! `.NAME.slayer-tmp.PID`, which is synced; only when every file of the batch is staged are
//! they renamed over their targets, and the folders synced. Should a rename fail, the targets
//! already replaced get their old bytes back (kept under the same pattern until the batch
//! ends). A process killed mid-write leaves its temporary files behind: the next batch that
//! writes into that folder removes those whose process is gone (by the pattern: only ours).

use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use super::IoError;

/// What ends every temporary file's name before `.PID`.
const TEMP_MARK: &str = ".slayer-tmp.";

/// Bytes gathered before each write to a staged file.
const WRITE_BUFFER: usize = 1 << 20;

/// Files written together: [`AtomicBatch::stage`] each, then [`AtomicBatch::commit`]. Dropping
/// a batch without committing removes what it staged and leaves every target as it was.
#[derive(Debug, Default)]
pub struct AtomicBatch {
    staged: Vec<Staged>,
    /// Folders already swept of stale temporary files by this batch.
    swept: Vec<PathBuf>,
}

#[derive(Debug)]
struct Staged {
    target: PathBuf,
    temporary: PathBuf,
}

/// Writes `bytes` to `path` atomically: a batch of one.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    let mut batch = AtomicBatch::new();
    batch.stage(path, bytes)?;
    batch.commit()
}

impl AtomicBatch {
    pub fn new() -> AtomicBatch {
        AtomicBatch::default()
    }

    /// Writes `bytes` to a synced temporary file beside `path`; nothing visible changes yet.
    pub fn stage(&mut self, path: &Path, bytes: &[u8]) -> Result<(), IoError> {
        self.stage_with(path, |out| out.write_all(bytes))
    }

    /// Streams what `write` writes (buffered) to a synced temporary file beside `path`, so a
    /// large file is never held whole in memory; nothing visible changes yet.
    pub fn stage_with(
        &mut self,
        path: &Path,
        write: impl FnOnce(&mut dyn Write) -> io::Result<()>,
    ) -> Result<(), IoError> {
        let folder = folder_of(path);
        if !self.swept.contains(&folder) {
            sweep_stale_temporaries(&folder);
            self.swept.push(folder);
        }
        let temporary = temporary_name(path, "");
        // Recorded first, so that a failed write is removed with the rest.
        self.staged.push(Staged {
            target: path.to_path_buf(),
            temporary: temporary.clone(),
        });
        let written = || -> io::Result<()> {
            let mut out = io::BufWriter::with_capacity(WRITE_BUFFER, fs::File::create(&temporary)?);
            write(&mut out)?;
            out.into_inner().map_err(|e| e.into_error())?.sync_all()
        };
        written().map_err(|source| io_error(path, source))
    }

    /// Renames every staged file over its target and syncs the folders. On a failed rename the
    /// targets already replaced are put back, so either every target changed or none did.
    pub fn commit(mut self) -> Result<(), IoError> {
        let staged = std::mem::take(&mut self.staged);
        let mut kept = Vec::new(); // (target, its old bytes' temporary name, if it existed)
        for (i, file) in staged.iter().enumerate() {
            let result = keep_old(&file.target).and_then(|old| {
                kept.push((file.target.clone(), old));
                fs::rename(&file.temporary, &file.target)
            });
            if let Err(source) = result {
                restore(&kept[..i.min(kept.len())]);
                discard_kept(&kept[i.min(kept.len())..]);
                for later in &staged[i..] {
                    let _ = fs::remove_file(&later.temporary);
                }
                return Err(io_error(&file.target, source));
            }
        }
        discard_kept(&kept);
        let mut folders: Vec<PathBuf> = staged.iter().map(|f| folder_of(&f.target)).collect();
        folders.dedup();
        for folder in folders {
            // Best effort: the files are in place; a file system that cannot sync a folder
            // (some refuse) is no reason to report the write as failed.
            let _ = sync_folder(&folder);
        }
        Ok(())
    }
}

impl Drop for AtomicBatch {
    fn drop(&mut self) {
        for file in &self.staged {
            let _ = fs::remove_file(&file.temporary);
        }
    }
}

fn io_error(path: &Path, source: io::Error) -> IoError {
    IoError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// The folder `path` is in (`.` for a bare file name).
fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// `.NAME<extra>.slayer-tmp.PID` beside `path`.
fn temporary_name(path: &Path, extra: &str) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "file".into());
    path.with_file_name(format!(".{name}{extra}{TEMP_MARK}{}", std::process::id()))
}

/// A second name for the target's old bytes (a hard link), so that a failed batch can put them
/// back; `None` when there is no old file.
fn keep_old(target: &Path) -> io::Result<Option<PathBuf>> {
    match fs::symlink_metadata(target) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(e),
        // A folder cannot be replaced by a file: refuse before anything is renamed.
        Ok(m) if m.is_dir() => Err(io::Error::new(
            io::ErrorKind::IsADirectory,
            "is a folder; cannot write a file there",
        )),
        Ok(_) => {
            let old = temporary_name(target, "~old");
            let _ = fs::remove_file(&old);
            // A link where the file system allows it, a copy where it does not.
            fs::hard_link(target, &old).or_else(|_| fs::copy(target, &old).map(|_| ()))?;
            Ok(Some(old))
        }
    }
}

/// Puts back the old bytes of targets a failed batch had replaced (a target that did not exist
/// before is removed).
fn restore(kept: &[(PathBuf, Option<PathBuf>)]) {
    for (target, old) in kept {
        match old {
            Some(old) => {
                let _ = fs::rename(old, target);
            }
            None => {
                let _ = fs::remove_file(target);
            }
        }
    }
}

fn discard_kept(kept: &[(PathBuf, Option<PathBuf>)]) {
    for old in kept.iter().filter_map(|(_, old)| old.as_ref()) {
        let _ = fs::remove_file(old);
    }
}

/// Syncs a folder, so that the renames in it survive a crash.
fn sync_folder(folder: &Path) -> io::Result<()> {
    #[cfg(unix)]
    {
        fs::File::open(folder)?.sync_all()
    }
    #[cfg(not(unix))]
    {
        let _ = folder;
        Ok(())
    }
}

/// Removes the temporary files in `folder` that a process no longer running left behind.
/// Best effort: a folder that cannot be listed is left alone.
pub fn sweep_stale_temporaries(folder: &Path) {
    let Ok(entries) = fs::read_dir(folder) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(temporary_pid) else {
            continue;
        };
        let regular = entry.file_type().is_ok_and(|t| t.is_file());
        if regular && !process_lives(pid) {
            let _ = fs::remove_file(entry.path());
        }
    }
}

/// The process id in a temporary file's name `.NAME.slayer-tmp.PID`, if `name` is one.
fn temporary_pid(name: &str) -> Option<u32> {
    let rest = name.strip_prefix('.')?;
    let (stem, pid) = rest.rsplit_once(TEMP_MARK)?;
    if stem.is_empty() || pid.is_empty() || !pid.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    pid.parse().ok()
}

/// Whether a process with this id runs (ours always does). Where that cannot be told, yes:
/// a file is never removed on a guess.
fn process_lives(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    #[cfg(unix)]
    {
        let Ok(pid) = libc::pid_t::try_from(pid) else {
            return true;
        };
        // Signal 0 only asks whether the process exists; EPERM means it does, not ours.
        // SAFETY: kill with signal 0 sends nothing and touches no memory.
        let status = unsafe { libc::kill(pid, 0) };
        status == 0 || io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
    }
    #[cfg(not(unix))]
    {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporary_names_are_recognised_only_by_the_pattern() {
        let path = temporary_name(Path::new("/x/out.obj"), "");
        let name = path.file_name().unwrap().to_str().unwrap();
        assert_eq!(temporary_pid(name), Some(std::process::id()));
        assert_eq!(temporary_pid(".out.obj~old.slayer-tmp.12"), Some(12));
        for other in [
            "out.obj",
            ".out.obj.tmp12",
            "out.obj.slayer-tmp.12",
            ".out.obj.slayer-tmp.",
            ".out.obj.slayer-tmp.12x",
            "..slayer-tmp.5x",
        ] {
            assert_eq!(temporary_pid(other), None, "{other}");
        }
    }

    #[test]
    fn a_failed_rename_puts_every_target_back() {
        let dir = std::env::temp_dir().join(format!("slayer-atomic-{}", std::process::id()));
        fs::create_dir_all(dir.join("b")).unwrap();
        let a = dir.join("a");
        fs::write(&a, b"old a").unwrap();
        let mut batch = AtomicBatch::new();
        batch.stage(&a, b"new a").unwrap();
        // `b` is a folder: its rename fails after `a`'s could have succeeded.
        batch.stage(&dir.join("b"), b"new b").unwrap();
        assert!(batch.commit().is_err());
        assert_eq!(fs::read(&a).unwrap(), b"old a");
        let names: Vec<_> = fs::read_dir(&dir).unwrap().flatten().collect();
        assert_eq!(names.len(), 2, "no temporary file is left: {names:?}");
        fs::remove_dir_all(dir).unwrap();
    }
}
