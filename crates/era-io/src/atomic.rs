//! The one safe way era writes files.
//!
//! Every output goes to a temporary file created beside its target and is renamed over
//! the target only once it is complete and synced to disk. The guarantees:
//!
//! - The target must be a regular file or must not exist. A device (`/dev/null`,
//!   `/dev/full`), a FIFO, a socket, a folder or a symbolic link is refused, before
//!   anything is written and again right before the rename, with an [`IoError`] naming
//!   the path and what it is.
//! - The temporary file gets a random name (`.era-tmp-<pid>-<random>.<ext>`, the
//!   target's extension kept, since image encoders pick the format from it) and is
//!   created exclusively (`O_CREAT | O_EXCL`, by the `tempfile` crate), so an existing
//!   entry or a planted symbolic link at that name makes creation fail and is never
//!   followed. After the writer has run, the path must still be the very file that was
//!   created (same device and inode).
//! - The data is synced (`fsync`) before the rename; any write error (a full disk, a
//!   file size limit) is returned, naming the target, and the target is untouched.
//! - A run with several outputs stages them all in an [`OutputSet`] (a private folder
//!   `.era-staging-<pid>-<random>` inside the destination) and moves them into place
//!   only at the end: a failure before [`OutputSet::commit`] leaves every earlier output
//!   as it was.
//! - Temporary files and staging folders left by killed runs are removed the next time
//!   era writes into that folder: only entries whose name has era's exact form, whose
//!   process no longer exists, and which are a regular file (or a real folder for
//!   staging), never following a symbolic link.
//! - Every temporary file, staging folder and folder lock of the process is in one
//!   registry. [`abandon`] (the CLI calls it on SIGINT, SIGTERM and SIGHUP, then exits)
//!   waits for a commit in progress to end, removes them all, and holds the registry so
//!   that nothing new is made or committed before the process is gone: earlier outputs
//!   stay whole and nothing of era's is left behind.
//! - An output folder ([`OutputSet::new`]) is held by one run at a time: an advisory
//!   lock (`flock`) on the file [`LOCK_NAME`] inside it, which holds the run's process
//!   id. A second run into the folder is refused with a message naming the first; the
//!   lock file is removed when the set ends (and by [`abandon`]), and a lock file left by
//!   a killed run holds nothing (the kernel released its lock).

use crate::IoError;
use std::collections::{BTreeMap, BTreeSet};
use std::ffi::OsString;
use std::fs::Metadata;
use std::io::Write;
use std::os::unix::fs::{FileTypeExt, MetadataExt, OpenOptionsExt, PermissionsExt};
use std::path::{Component, Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// Name prefix of a temporary file; the process id and [`RANDOM_CHARS`] characters
/// follow.
pub const TEMPORARY_PREFIX: &str = ".era-tmp-";
/// Name prefix of a staging folder; the process id and [`RANDOM_CHARS`] characters
/// follow.
pub const STAGING_PREFIX: &str = ".era-staging-";
/// Random alphanumeric characters in a temporary or staging name.
pub const RANDOM_CHARS: usize = 12;
/// Name of the lock file inside an output folder that a run holds.
pub const LOCK_NAME: &str = ".era-lock";

/// What an entry of the registry is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// A temporary file.
    File,
    /// A staging folder.
    Folder,
    /// A folder lock: the file with this device and inode (removed only while the path
    /// is still that file).
    Lock(u64, u64),
}

/// The era entries this process has made and not yet committed or removed.
struct Live {
    next: u64,
    entries: BTreeMap<u64, (PathBuf, Kind)>,
}

static LIVE: Mutex<Live> = Mutex::new(Live {
    next: 0,
    entries: BTreeMap::new(),
});

/// The registry, locked (a panic elsewhere while it was held does not matter to it).
fn live() -> MutexGuard<'static, Live> {
    LIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// An entry in the registry; dropping it takes the entry out.
#[derive(Debug)]
struct Registration(u64);

impl Registration {
    /// Registers `path` (made while `live` was held, so that [`abandon`] sees it).
    fn under(live: &mut Live, path: &Path, kind: Kind) -> Registration {
        let id = live.next;
        live.next += 1;
        live.entries.insert(id, (path.to_path_buf(), kind));
        Registration(id)
    }

    /// Takes the entry out while the registry is held (after a rename made it a real
    /// output).
    fn settle(&self, live: &mut Live) {
        live.entries.remove(&self.0);
    }
}

impl Drop for Registration {
    fn drop(&mut self) {
        self.settle(&mut live());
    }
}

/// Removes every temporary file, staging folder and folder lock of this process, after
/// any commit in progress has ended, and keeps the registry held for good: nothing new
/// is made or committed afterwards. For a process about to exit on a signal. Returns
/// how many entries were removed.
pub fn abandon() -> usize {
    let mut live = live();
    let removed = remove_entries(&mut live);
    // Held until the process ends.
    std::mem::forget(live);
    removed
}

/// [`abandon`]'s work on a registry: removes its entries and empties it.
fn remove_entries(live: &mut Live) -> usize {
    let mut removed = 0;
    for (path, kind) in std::mem::take(&mut live.entries).into_values() {
        let gone = match kind {
            Kind::File => std::fs::remove_file(&path).is_ok(),
            Kind::Folder => remove_staging(&path),
            Kind::Lock(dev, ino) => match std::fs::symlink_metadata(&path) {
                Ok(m) if m.dev() == dev && m.ino() == ino => std::fs::remove_file(&path).is_ok(),
                // Not ours any more: another run's lock now.
                _ => false,
            },
        };
        removed += usize::from(gone);
    }
    removed
}

/// Removes a staging folder that a writer of this process may still be writing into:
/// renamed first to a fresh name of era's form, so that no file can be created at its
/// old path while it is removed (a file created during the removal would leave it).
fn remove_staging(path: &Path) -> bool {
    let folder = folder_of(path);
    let seed = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64);
    let moved = (0..8u64).find_map(|k| {
        // Twelve digits are twelve alphanumerics: the name has era's exact form.
        let name = format!(
            "{STAGING_PREFIX}{}-{:012}",
            std::process::id(),
            seed.wrapping_add(k) % 1_000_000_000_000
        );
        let target = folder.join(name);
        (!target.exists() && std::fs::rename(path, &target).is_ok()).then_some(target)
    });
    let doomed = moved.as_deref().unwrap_or(path);
    (0..3).any(|_| std::fs::remove_dir_all(doomed).is_ok())
}

/// Whether two metadata describe the same file (device and inode).
fn same_file(a: &Metadata, b: &Metadata) -> bool {
    a.dev() == b.dev() && a.ino() == b.ino()
}

/// What a non-regular entry is, for messages.
fn kind_of(meta: &Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_symlink() {
        "a symbolic link"
    } else if t.is_dir() {
        "a folder"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_fifo() {
        "a FIFO (named pipe)"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

/// Checks that `path` may be written: a regular file or nothing (a symbolic link is not
/// followed: it is refused).
///
/// # Errors
/// [`IoError::Format`] naming `path` and what it is ("is a character device: era writes
/// only regular files"), or [`IoError::Io`] when it cannot be examined.
pub fn check_target(path: &Path) -> Result<(), IoError> {
    match std::fs::symlink_metadata(path) {
        Ok(meta) if meta.file_type().is_file() => Ok(()),
        Ok(meta) => Err(IoError::format(
            path,
            "",
            format!("is {}: era writes only regular files", kind_of(&meta)),
        )),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(IoError::io(path, e)),
    }
}

/// The folder of `path` (`.` for a bare name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// A fresh temporary file for `path`, beside it, created exclusively, and its entry in
/// the registry.
fn temporary_for(path: &Path) -> Result<(tempfile::NamedTempFile, Registration), IoError> {
    let folder = folder_of(path);
    remove_stale(folder);
    let suffix = match path.extension() {
        Some(ext) => {
            let mut s = OsString::from(".");
            s.push(ext);
            s
        }
        None => OsString::new(),
    };
    let mut live = live();
    let tmp = tempfile::Builder::new()
        .prefix(&format!("{TEMPORARY_PREFIX}{}-", std::process::id()))
        .rand_bytes(RANDOM_CHARS)
        .suffix(&suffix)
        // The mode an ordinary create gives (the umask applies), not tempfile's 0600:
        // the output is the user's file.
        .permissions(std::fs::Permissions::from_mode(0o666))
        .tempfile_in(folder)
        .map_err(|e| temporary_error(path, folder, e))?;
    let registration = Registration::under(&mut live, tmp.path(), Kind::File);
    Ok((tmp, registration))
}

/// Why the temporary file could not be made, said of the destination: a missing folder
/// by name, else the OS error without `tempfile`'s "at path .era-tmp-…" (a name the user
/// never gave).
fn temporary_error(path: &Path, folder: &Path, e: std::io::Error) -> IoError {
    // The OS error's kind is kept (Python maps it to FileNotFoundError and the like).
    let plain = if !folder.is_dir() {
        let what = if folder.exists() {
            "is not a folder"
        } else {
            "does not exist: create it first"
        };
        format!("the folder {} {what}", folder.display())
    } else {
        let text = e.to_string();
        match text.rfind(" at path ") {
            Some(at) => text[..at].to_string(),
            None => text,
        }
    };
    IoError::io(path, std::io::Error::new(e.kind(), plain))
}

/// Syncs the temporary file, checks the target once more and renames over it.
fn finish(
    tmp: tempfile::NamedTempFile,
    registration: Registration,
    path: &Path,
) -> Result<(), IoError> {
    // The writer was given the path: it must have written the file created for it, not
    // something put in its place.
    let ours = tmp.as_file().metadata().map_err(|e| IoError::io(path, e))?;
    match std::fs::symlink_metadata(tmp.path()) {
        Ok(m) if m.file_type().is_file() && same_file(&m, &ours) => {}
        _ => {
            return Err(IoError::format(
                path,
                "",
                format!(
                    "the temporary file {} was replaced while writing",
                    tmp.path().display()
                ),
            ))
        }
    }
    tmp.as_file().sync_all().map_err(|e| IoError::io(path, e))?;
    check_target(path)?;
    let mut live = live();
    tmp.persist(path).map_err(|e| IoError::io(path, e.error))?;
    registration.settle(&mut live);
    Ok(())
}

/// Runs `write` on a fresh temporary file beside `path` (created exclusively, with a
/// random name that keeps the extension), then syncs it and renames it over `path`. On
/// any failure the temporary file is removed and `path` is untouched. Every writer of
/// the project goes through here.
///
/// # Errors
/// What `write` returns; [`IoError`] naming `path` when it is not a regular file or
/// absent, when the temporary file cannot be made or synced, or when the rename fails.
pub fn write_via<E: From<IoError>>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    check_target(path)?;
    let (tmp, registration) = temporary_for(path)?;
    write(tmp.path())?;
    finish(tmp, registration, path)?;
    Ok(())
}

/// Writes `bytes` to `path` atomically ([`write_via`]), through the handle of the
/// temporary file, synced before the rename.
///
/// # Errors
/// [`IoError`] naming `path` when the folder is missing or not writable, the disk is
/// full, or `path` is not a regular file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    check_target(path)?;
    let (mut tmp, registration) = temporary_for(path)?;
    tmp.as_file_mut()
        .write_all(bytes)
        .and_then(|()| tmp.as_file_mut().flush())
        .map_err(|e| IoError::io(path, e))?;
    finish(tmp, registration, path)
}

/// The process id in `name` when it has the exact form `PREFIX<pid>-<RANDOM_CHARS
/// alphanumerics>` followed by nothing (or, for a temporary file, `.<extension>`).
fn era_pid(name: &str, prefix: &str, extension_allowed: bool) -> Option<u32> {
    let rest = name.strip_prefix(prefix)?;
    let (pid, rest) = rest.split_once('-')?;
    if pid.is_empty() || pid.len() > 10 || !pid.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let random = rest.get(..RANDOM_CHARS)?;
    if !random.bytes().all(|b| b.is_ascii_alphanumeric()) {
        return None;
    }
    let tail = &rest[RANDOM_CHARS..];
    let tail_ok = tail.is_empty() || (extension_allowed && tail.starts_with('.'));
    if !tail_ok {
        return None;
    }
    pid.parse().ok()
}

/// Whether process `pid` is running; `true` when that cannot be told (no `/proc`), so
/// nothing is removed then. A zombie (state `Z` or `X` in `/proc/PID/stat`: dead, not
/// yet reaped by its parent) is not running: its files are as abandoned as those of a
/// process that is gone.
fn process_alive(pid: u32) -> bool {
    if !Path::new("/proc/self").exists() {
        return true;
    }
    if pid == std::process::id() {
        return true;
    }
    let entry = Path::new("/proc").join(pid.to_string());
    match std::fs::read_to_string(entry.join("stat")) {
        Ok(stat) => !matches!(process_state(&stat), Some('Z' | 'X' | 'x')),
        // Gone between the listing and the read, or never there.
        Err(_) => entry.exists(),
    }
}

/// The state letter of a `/proc/PID/stat` line: the field after the command name, which
/// is in parentheses and may itself hold spaces and parentheses (hence the last `)`).
fn process_state(stat: &str) -> Option<char> {
    let (_, after) = stat.rsplit_once(')')?;
    after.trim_start().chars().next()
}

/// Removes from `folder` the temporary files (`.era-tmp-<pid>-…`, regular files) and
/// staging folders (`.era-staging-<pid>-…`, real folders) of processes that no longer
/// run. Nothing else is touched, symbolic links are never followed, and errors are
/// ignored (a leftover is harmless). Returns how many entries were removed.
pub fn remove_stale(folder: &Path) -> usize {
    let Ok(entries) = std::fs::read_dir(folder) else {
        return 0;
    };
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(name) = name.to_str() else { continue };
        let (pid, is_staging) = if let Some(pid) = era_pid(name, TEMPORARY_PREFIX, true) {
            (pid, false)
        } else if let Some(pid) = era_pid(name, STAGING_PREFIX, false) {
            (pid, true)
        } else {
            continue;
        };
        if process_alive(pid) {
            continue;
        }
        // DirEntry::file_type does not follow a symbolic link.
        let Ok(kind) = entry.file_type() else {
            continue;
        };
        let path = entry.path();
        let gone = if is_staging && kind.is_dir() {
            // std's remove_dir_all does not follow symbolic links inside.
            std::fs::remove_dir_all(&path).is_ok()
        } else if !is_staging && kind.is_file() {
            std::fs::remove_file(&path).is_ok()
        } else {
            false
        };
        removed += usize::from(gone);
    }
    removed
}

/// Checks that `name` is a plain relative path (no root, no `..`, no `.`), so that an
/// output cannot land outside its folder.
fn plain_relative(name: &Path) -> bool {
    !name.as_os_str().is_empty() && name.components().all(|c| matches!(c, Component::Normal(_)))
}

/// The outputs of one run, written as a transaction.
///
/// [`OutputSet::new`] makes a private staging folder (`.era-staging-<pid>-<random>`,
/// mode 0700) inside the destination folder, which also proves early, before any long
/// work, that the folder takes files. [`OutputSet::stage`] gives the path inside it
/// where the writer of an output puts its file (the ordinary writers, [`write_atomic`]
/// and [`write_via`], are simply given that path); it refuses an output whose target
/// is not a regular file or absent. [`OutputSet::commit`] checks every target again and
/// renames the staged files into place, creating subfolders (such as `pairs/`); when a
/// rename fails, the outputs already moved are put back as they were. Dropping an
/// uncommitted set removes the staging folder and leaves the destination untouched.
#[derive(Debug)]
pub struct OutputSet {
    folder: PathBuf,
    // Fields drop in this order: the staging folder, its registration, then the lock.
    staging: tempfile::TempDir,
    _registration: Registration,
    _lock: Option<FolderLock>,
    names: BTreeSet<PathBuf>,
}

/// The advisory lock a run holds on its output folder ([`LOCK_NAME`]).
#[derive(Debug)]
struct FolderLock {
    path: PathBuf,
    // Closed last (releasing the lock), after the file is unlinked and the entry gone.
    file: Option<std::fs::File>,
    registration: Registration,
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        // Under the registry (so a signal's clean-up cannot act between), while the
        // lock is still held: unlink the file if it is still ours, take the entry out,
        // then release the lock by closing the file. A run that opened the path meanwhile
        // finds it unlinked after its lock and opens the path again.
        let mut live = live();
        if let Some(file) = &self.file {
            if let (Ok(ours), Ok(there)) = (file.metadata(), std::fs::symlink_metadata(&self.path))
            {
                if same_file(&ours, &there) {
                    let _ = std::fs::remove_file(&self.path);
                }
            }
        }
        self.registration.settle(&mut live);
        drop(self.file.take());
    }
}

/// Whether a lock error means the file system has no locks (then the folder is not
/// locked): `ENOTSUP`, and `ENOLCK` (NFS without its lock daemon).
fn no_locks_here(e: &std::io::Error) -> bool {
    e.kind() == std::io::ErrorKind::Unsupported || e.raw_os_error() == Some(libc::ENOLCK)
}

/// Takes the lock of `folder` for this run: `None` where the file system has no locks.
///
/// # Errors
/// [`IoError`] naming `folder` when another run holds it (with that run's process id),
/// or the lock file when it cannot be opened (a symbolic link there is not followed).
fn lock_folder(folder: &Path) -> Result<Option<FolderLock>, IoError> {
    use std::io::{Read, Seek};
    let path = folder.join(LOCK_NAME);
    // A few tries: the holder may remove the file between our open and our lock.
    for _ in 0..16 {
        let open = |write: bool| {
            std::fs::OpenOptions::new()
                .read(true)
                .write(write)
                .create(write)
                .mode(0o644)
                .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC | libc::O_NONBLOCK)
                .open(&path)
        };
        // A lock file another user left is locked read-only (flock needs no write).
        let (mut file, writable) = match open(true) {
            Ok(f) => (f, true),
            Err(e) if e.kind() == std::io::ErrorKind::PermissionDenied => {
                (open(false).map_err(|e| IoError::io(&path, e))?, false)
            }
            Err(e) => return Err(IoError::io(&path, e)),
        };
        let ours = file.metadata().map_err(|e| IoError::io(&path, e))?;
        if !ours.file_type().is_file() {
            return Err(IoError::format(
                &path,
                "",
                format!(
                    "is {}: era keeps its folder lock in a regular file",
                    kind_of(&ours)
                ),
            ));
        }
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                // The holder's process id, read through the file we opened.
                let mut text = String::new();
                let _ = Read::by_ref(&mut file).take(32).read_to_string(&mut text);
                let holder = text
                    .trim()
                    .parse::<u32>()
                    .map(|pid| format!(" (process {pid})"))
                    .unwrap_or_default();
                return Err(IoError::format(
                    folder,
                    "",
                    format!(
                        "another era run{holder} is writing into this folder: wait for it to end, or choose another folder"
                    ),
                ));
            }
            Err(std::fs::TryLockError::Error(e)) if no_locks_here(&e) => {
                // Leave no empty lock file of ours behind.
                if ours.len() == 0 {
                    let _ = std::fs::remove_file(&path);
                }
                return Ok(None);
            }
            Err(std::fs::TryLockError::Error(e)) => return Err(IoError::io(&path, e)),
        }
        let mut live = live();
        match std::fs::symlink_metadata(&path) {
            Ok(m) if same_file(&m, &ours) => {
                if writable {
                    // Whose lock it is, for the message of a run refused.
                    let _ = file
                        .set_len(0)
                        .and_then(|()| file.rewind())
                        .and_then(|()| writeln!(file, "{}", std::process::id()));
                }
                let registration =
                    Registration::under(&mut live, &path, Kind::Lock(ours.dev(), ours.ino()));
                return Ok(Some(FolderLock {
                    path,
                    file: Some(file),
                    registration,
                }));
            }
            // Unlinked by the run that held it: open the path again.
            _ => continue,
        }
    }
    Err(IoError::format(
        &path,
        "",
        "the folder lock keeps being replaced: is another program removing it?",
    ))
}

impl OutputSet {
    /// A set writing into `folder`, which must exist, holding the folder's lock
    /// ([`LOCK_NAME`]) until it is committed or dropped; stale era entries in it are
    /// removed first ([`remove_stale`]).
    ///
    /// # Errors
    /// [`IoError`] naming `folder` when it is not a folder, cannot take files, or
    /// another era run is writing into it.
    pub fn new(folder: &Path) -> Result<Self, IoError> {
        OutputSet::open(folder, true)
    }

    /// A set for the single file `path` (and any files beside it): its folder, which
    /// must exist. The folder is not locked: many runs may each write their own file
    /// into one folder.
    ///
    /// # Errors
    /// As [`OutputSet::new`].
    pub fn beside(path: &Path) -> Result<Self, IoError> {
        OutputSet::open(folder_of(path), false)
    }

    fn open(folder: &Path, lock: bool) -> Result<Self, IoError> {
        let folder = if folder.as_os_str().is_empty() {
            Path::new(".")
        } else {
            folder
        };
        match std::fs::metadata(folder) {
            Ok(m) if m.is_dir() => {}
            Ok(m) => {
                return Err(IoError::format(
                    folder,
                    "",
                    format!("is {}, not a folder", kind_of(&m)),
                ))
            }
            Err(e) => return Err(IoError::io(folder, e)),
        }
        let lock = if lock { lock_folder(folder)? } else { None };
        remove_stale(folder);
        let mut live = live();
        let staging = tempfile::Builder::new()
            .prefix(&format!("{STAGING_PREFIX}{}-", std::process::id()))
            .rand_bytes(RANDOM_CHARS)
            .permissions(std::fs::Permissions::from_mode(0o700))
            .tempdir_in(folder)
            .map_err(|e| IoError::io(folder, e))?;
        let registration = Registration::under(&mut live, staging.path(), Kind::Folder);
        Ok(OutputSet {
            folder: folder.to_path_buf(),
            staging,
            _registration: registration,
            _lock: lock,
            names: BTreeSet::new(),
        })
    }

    /// The destination folder.
    pub fn folder(&self) -> &Path {
        &self.folder
    }

    /// Where the output `name` (relative to the destination folder, e.g. `model.json`
    /// or `pairs/pair_1_1.png`) will end up.
    pub fn target(&self, name: impl AsRef<Path>) -> PathBuf {
        self.folder.join(name)
    }

    /// The path inside the staging folder where the output `name` is to be written.
    /// The target is checked now (a regular file or absent, its folders real folders),
    /// so a bad target is refused before the work.
    ///
    /// # Errors
    /// [`IoError`] naming the target when it is not a plain relative name, is not a
    /// regular file or absent, or when the staging subfolder cannot be made.
    pub fn stage(&mut self, name: impl AsRef<Path>) -> Result<PathBuf, IoError> {
        let name = name.as_ref();
        let target = self.target(name);
        if !plain_relative(name) {
            return Err(IoError::format(
                &target,
                "",
                "an output name must be a plain relative path",
            ));
        }
        self.check(name)?;
        let staged = self.staging.path().join(name);
        if let Some(parent) = staged.parent() {
            // Under the registry: after a signal's clean-up this never runs, so the
            // removed staging folder is not made again.
            let _live = live();
            std::fs::create_dir_all(parent).map_err(|e| IoError::io(&target, e))?;
        }
        self.names.insert(name.to_path_buf());
        Ok(staged)
    }

    /// The target of `name` and every folder on the way to it (below the destination)
    /// must be a real folder or absent, the target a regular file or absent.
    fn check(&self, name: &Path) -> Result<(), IoError> {
        let mut folder = self.folder.clone();
        let mut parts = name.components().peekable();
        while let Some(part) = parts.next() {
            folder.push(part);
            if parts.peek().is_none() {
                break;
            }
            match std::fs::symlink_metadata(&folder) {
                Ok(m) if m.is_dir() => {}
                Ok(m) => {
                    return Err(IoError::format(
                        &folder,
                        "",
                        format!("is {}: era writes only into real folders", kind_of(&m)),
                    ))
                }
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => return Err(IoError::io(&folder, e)),
            }
        }
        check_target(&self.target(name))
    }

    /// Moves every staged output into place and removes the staging folder. Returns the
    /// targets written.
    ///
    /// # Errors
    /// [`IoError`] naming the output when it was staged but not written, when its target
    /// is no longer a regular file or absent, or when a folder or rename fails; the
    /// destination is then as before the commit (outputs already moved are put back).
    pub fn commit(self) -> Result<Vec<PathBuf>, IoError> {
        self.commit_with(|_| {})
    }

    /// [`OutputSet::commit`] with `before_move(k)` run before the k-th rename (tests).
    fn commit_with(self, mut before_move: impl FnMut(usize)) -> Result<Vec<PathBuf>, IoError> {
        for name in &self.names {
            let staged = self.staging.path().join(name);
            match std::fs::symlink_metadata(&staged) {
                Ok(m) if m.is_file() => {}
                _ => {
                    return Err(IoError::format(
                        self.target(name),
                        "",
                        "was staged but not written",
                    ))
                }
            }
            self.check(name)?;
        }
        // A signal's clean-up waits until the renames (or their roll-back) are done.
        let held = live();
        let mut moved: Vec<(PathBuf, Option<PathBuf>)> = Vec::new();
        let mut result = Ok(());
        for (k, name) in self.names.iter().enumerate() {
            before_move(k);
            match self.move_into_place(name, k) {
                Ok(backup) => moved.push((self.target(name), backup)),
                Err(e) => {
                    result = Err(e);
                    break;
                }
            }
        }
        if let Err(e) = result {
            // Put back what was there: the previous set stays whole.
            for (target, backup) in moved.into_iter().rev() {
                let _ = match backup {
                    Some(old) => std::fs::rename(old, &target),
                    None => std::fs::remove_file(&target),
                };
            }
            drop(held);
            return Err(e);
        }
        drop(held);
        let mut folders: BTreeSet<PathBuf> = BTreeSet::new();
        for name in &self.names {
            folders.insert(folder_of(&self.target(name)).to_path_buf());
        }
        for folder in folders {
            // Makes the renames durable; some file systems refuse to sync a folder.
            if let Ok(f) = std::fs::File::open(&folder) {
                let _ = f.sync_all();
            }
        }
        let targets = self.names.iter().map(|n| self.target(n)).collect();
        let _ = self.staging.close();
        Ok(targets)
    }

    /// Renames the staged `name` over its target, keeping the previous target (a hard
    /// link in the staging folder) for a roll-back; returns that backup.
    fn move_into_place(&self, name: &Path, k: usize) -> Result<Option<PathBuf>, IoError> {
        let target = self.target(name);
        let parent = folder_of(&target);
        std::fs::create_dir_all(parent).map_err(|e| IoError::io(&target, e))?;
        self.check(name)?;
        let backup = if target.exists() {
            let b = self.staging.path().join(format!(".previous-{k}"));
            std::fs::hard_link(&target, &b).ok().map(|()| b)
        } else {
            None
        };
        std::fs::rename(self.staging.path().join(name), &target)
            .map_err(|e| IoError::io(&target, e))?;
        Ok(backup)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::symlink;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    fn mkfifo(path: &Path) {
        let c = std::ffi::CString::new(path.as_os_str().as_encoded_bytes()).unwrap();
        // SAFETY: a valid NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0);
    }

    /// A zombie's files are abandoned: its state letter is read past a command name with
    /// spaces and parentheses, and a real zombie (a child killed and not yet reaped)
    /// counts as dead.
    #[test]
    fn a_zombie_is_not_alive() {
        assert_eq!(process_state("42 (era) R 1 42"), Some('R'));
        assert_eq!(process_state("42 (a b) c)) Z 1 42"), Some('Z'));
        assert_eq!(process_state("garbage"), None);
        let mut child = std::process::Command::new("sleep")
            .arg("30")
            .spawn()
            .expect("sleep runs");
        let pid = child.id();
        assert!(process_alive(pid));
        child.kill().expect("kill");
        // Not reaped yet: /proc/PID is still there, a zombie.
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(5);
        while process_alive(pid) && std::time::Instant::now() < deadline {
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        assert!(Path::new("/proc").join(pid.to_string()).exists());
        assert!(!process_alive(pid));
        child.wait().expect("reaped");
    }

    /// A pid that is not running: above the kernel's pid_max.
    const DEAD_PID: u32 = 4_194_999;

    #[test]
    fn writes_and_replaces() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "two");
        assert_eq!(names(dir.path()), ["x.txt"]);
    }

    #[test]
    fn a_failing_writer_leaves_nothing_and_the_temporary_keeps_the_extension() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("fig.png");
        let mut seen = None;
        let r: Result<(), IoError> = write_via(&target, |tmp| {
            seen = Some(tmp.to_path_buf());
            std::fs::write(tmp, b"half").unwrap();
            Err(IoError::format(tmp, "", "encoder failed"))
        });
        assert!(r.is_err());
        let seen = seen.unwrap();
        assert_eq!(seen.extension().unwrap(), "png");
        let name = seen.file_name().unwrap().to_str().unwrap().to_owned();
        assert_eq!(
            era_pid(&name, TEMPORARY_PREFIX, true),
            Some(std::process::id()),
            "{name}"
        );
        assert!(names(dir.path()).is_empty());
    }

    #[test]
    fn a_missing_folder_is_named_not_the_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("absent").join("a.csv");
        let e = write_atomic(&target, b"x").unwrap_err().to_string();
        assert!(
            e.contains("a.csv") && e.contains("absent does not exist: create it first"),
            "{e}"
        );
        assert!(
            !e.contains(TEMPORARY_PREFIX) && !e.contains("at path"),
            "{e}"
        );
        let e = write_atomic(&target, b"x").unwrap_err();
        assert!(
            matches!(&e, IoError::Io { error, .. } if error.kind() == std::io::ErrorKind::NotFound),
            "{e:?}"
        );
    }

    #[test]
    fn temporary_names_are_random() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("a.csv");
        let mut seen = Vec::new();
        for _ in 0..2 {
            let _: Result<(), IoError> = write_via(&target, |tmp| {
                seen.push(tmp.to_path_buf());
                Err(IoError::format(tmp, "", "stop"))
            });
        }
        assert_ne!(seen[0], seen[1]);
    }

    #[test]
    fn missing_folder_is_an_error_naming_the_file() {
        let err = write_atomic(Path::new("/nonexistent-dir-era/x.txt"), b"a").unwrap_err();
        assert!(err.to_string().contains("/nonexistent-dir-era/x.txt"));
    }

    #[test]
    fn non_regular_targets_are_refused_and_untouched() {
        let dir = tempfile::tempdir().unwrap();
        let decoy = dir.path().join("decoy");
        std::fs::write(&decoy, b"precious").unwrap();
        let link = dir.path().join("link.csv");
        symlink(&decoy, &link).unwrap();
        let fifo = dir.path().join("pipe.csv");
        mkfifo(&fifo);
        let folder = dir.path().join("folder.csv");
        std::fs::create_dir(&folder).unwrap();
        for (path, what) in [
            (&link, "a symbolic link"),
            (&fifo, "a FIFO"),
            (&folder, "a folder"),
            (&PathBuf::from("/dev/null"), "a character device"),
        ] {
            let err = write_atomic(path, b"x").unwrap_err().to_string();
            assert!(err.contains(&path.display().to_string()), "{err}");
            assert!(err.contains(what), "{err}");
            assert!(err.contains("era writes only regular files"), "{err}");
            let r: Result<(), IoError> = write_via(path, |_| panic!("writer must not run"));
            assert!(r.is_err());
        }
        assert_eq!(std::fs::read(&decoy).unwrap(), b"precious");
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert!(std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo());
        assert_eq!(
            names(dir.path()),
            ["decoy", "folder.csv", "link.csv", "pipe.csv"]
        );
    }

    #[test]
    fn a_target_turned_into_a_link_during_the_write_is_refused_at_the_rename() {
        let dir = tempfile::tempdir().unwrap();
        let decoy = dir.path().join("decoy");
        std::fs::write(&decoy, b"precious").unwrap();
        let target = dir.path().join("out.csv");
        let r: Result<(), IoError> = write_via(&target, |tmp| {
            std::fs::write(tmp, b"new").unwrap();
            symlink(&decoy, &target).unwrap();
            Ok(())
        });
        assert!(r.unwrap_err().to_string().contains("a symbolic link"));
        assert_eq!(std::fs::read(&decoy).unwrap(), b"precious");
        assert_eq!(names(dir.path()), ["decoy", "out.csv"]);
    }

    #[test]
    fn a_replaced_temporary_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let decoy = dir.path().join("decoy");
        std::fs::write(&decoy, b"precious").unwrap();
        let target = dir.path().join("out.csv");
        let r: Result<(), IoError> = write_via(&target, |tmp| {
            std::fs::remove_file(tmp).unwrap();
            symlink(&decoy, tmp).unwrap();
            Ok(())
        });
        assert!(r
            .unwrap_err()
            .to_string()
            .contains("replaced while writing"));
        assert!(!target.exists());
        assert_eq!(std::fs::read(&decoy).unwrap(), b"precious");
    }

    #[test]
    fn output_mode_follows_the_umask_not_0600() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.json");
        write_atomic(&p, b"{}").unwrap();
        let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
        // SAFETY: umask only reads and sets the process mask; restored at once.
        let mask = unsafe {
            let m = libc::umask(0o022);
            libc::umask(m);
            m
        };
        assert_eq!(mode, 0o666 & !(mask as u32));
    }

    #[test]
    fn era_names_are_told_apart_exactly() {
        let r = "a".repeat(RANDOM_CHARS);
        assert_eq!(
            era_pid(&format!(".era-tmp-77-{r}.png"), TEMPORARY_PREFIX, true),
            Some(77)
        );
        assert_eq!(
            era_pid(&format!(".era-tmp-77-{r}"), TEMPORARY_PREFIX, true),
            Some(77)
        );
        assert_eq!(
            era_pid(&format!(".era-staging-5-{r}"), STAGING_PREFIX, false),
            Some(5)
        );
        for bad in [
            format!(".era-tmp-77-{r}x"),
            format!(".era-tmp-77-{}", "a".repeat(RANDOM_CHARS - 1)),
            format!(".era-tmp--{r}"),
            format!(".era-tmp-7a-{r}"),
            format!(".era-tmp-77-{}!", "a".repeat(RANDOM_CHARS - 1)),
            format!("era-tmp-77-{r}"),
            format!(".era-tmp-77{r}"),
            format!(".era-tmp-99999999999-{r}"),
        ] {
            assert_eq!(era_pid(&bad, TEMPORARY_PREFIX, true), None, "{bad}");
        }
        assert_eq!(
            era_pid(&format!(".era-staging-5-{r}.x"), STAGING_PREFIX, false),
            None
        );
    }

    #[test]
    fn only_stale_era_entries_of_dead_processes_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let r = "Ab3".repeat(RANDOM_CHARS / 3);
        let me = std::process::id();
        let decoy = d.join("decoy");
        std::fs::write(&decoy, b"precious").unwrap();
        let decoy_dir = d.join("decoy_dir");
        std::fs::create_dir(&decoy_dir).unwrap();
        std::fs::write(decoy_dir.join("inside"), b"keep").unwrap();
        // Removed: dead pid, era's form, right kind.
        std::fs::write(d.join(format!(".era-tmp-{DEAD_PID}-{r}.csv")), b"old").unwrap();
        std::fs::write(d.join(format!(".era-tmp-{DEAD_PID}-{r}")), b"old").unwrap();
        let stale = d.join(format!(".era-staging-{DEAD_PID}-{r}"));
        std::fs::create_dir_all(stale.join("pairs")).unwrap();
        std::fs::write(stale.join("pairs/p.png"), b"old").unwrap();
        // A symbolic link inside a stale staging folder is removed, not followed.
        symlink(&decoy_dir, stale.join("link")).unwrap();
        // Kept: a live pid, look-alikes, wrong kinds.
        let kept = [
            format!(".era-tmp-{me}-{r}.csv"),
            format!(".era-staging-{me}-{r}"),
            format!(".era-tmp-{DEAD_PID}-{r}x"),
            format!(".era-tmp-{DEAD_PID}_{r}"),
            format!("era-tmp-{DEAD_PID}-{r}"),
            format!(".era-staging-{DEAD_PID}-{r}.d"),
            format!(".era-tmp-{DEAD_PID}-{}", "-".repeat(RANDOM_CHARS)),
        ];
        for k in &kept {
            std::fs::write(d.join(k), b"keep").unwrap();
        }
        // Right names, wrong kinds: a link named like a temporary file, a folder named
        // like a temporary file, a link named like a staging folder.
        let s = "Q".repeat(RANDOM_CHARS);
        symlink(&decoy, d.join(format!(".era-tmp-{DEAD_PID}-{s}.png"))).unwrap();
        std::fs::create_dir(d.join(format!(".era-tmp-{DEAD_PID}-{s}"))).unwrap();
        symlink(&decoy_dir, d.join(format!(".era-staging-{DEAD_PID}-{s}"))).unwrap();

        assert_eq!(remove_stale(d), 3);
        let left = names(d);
        assert_eq!(left.len(), 2 + kept.len() + 3, "{left:?}");
        for k in &kept {
            assert!(left.contains(k), "{k} removed");
        }
        assert_eq!(std::fs::read(&decoy).unwrap(), b"precious");
        assert_eq!(std::fs::read(decoy_dir.join("inside")).unwrap(), b"keep");
    }

    #[test]
    fn an_output_set_commits_all_at_once() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(d.join("a.json"), b"old a").unwrap();
        let mut set = OutputSet::new(d).unwrap();
        write_atomic(&set.stage("a.json").unwrap(), b"new a").unwrap();
        write_atomic(&set.stage("pairs/p_1_1.svg").unwrap(), b"p").unwrap();
        // Nothing is in place before the commit.
        assert_eq!(std::fs::read(d.join("a.json")).unwrap(), b"old a");
        assert!(!d.join("pairs").exists());
        let targets = set.commit().unwrap();
        assert_eq!(targets.len(), 2);
        assert_eq!(std::fs::read(d.join("a.json")).unwrap(), b"new a");
        assert_eq!(std::fs::read(d.join("pairs/p_1_1.svg")).unwrap(), b"p");
        assert_eq!(names(d), ["a.json", "pairs"]);
    }

    #[test]
    fn a_dropped_output_set_leaves_the_folder_as_it_was() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(d.join("a.json"), b"old a").unwrap();
        {
            let mut set = OutputSet::new(d).unwrap();
            write_atomic(&set.stage("a.json").unwrap(), b"new a").unwrap();
            write_atomic(&set.stage("b.json").unwrap(), b"new b").unwrap();
            // A later output fails: the set is dropped without a commit.
        }
        assert_eq!(std::fs::read(d.join("a.json")).unwrap(), b"old a");
        assert_eq!(names(d), ["a.json"]);
    }

    #[test]
    fn an_output_set_refuses_bad_targets_early_and_at_the_commit() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let decoy = d.join("decoy");
        std::fs::write(&decoy, b"precious").unwrap();
        symlink(&decoy, d.join("link.json")).unwrap();
        let elsewhere = tempfile::tempdir().unwrap();
        symlink(elsewhere.path(), d.join("pairs")).unwrap();
        let mut set = OutputSet::new(d).unwrap();
        assert!(set
            .stage("link.json")
            .unwrap_err()
            .to_string()
            .contains("symbolic link"));
        assert!(set
            .stage("pairs/x.svg")
            .unwrap_err()
            .to_string()
            .contains("real folders"));
        assert!(set.stage("../x.svg").is_err());
        assert!(set.stage("/tmp/x.svg").is_err());
        write_atomic(&set.stage("a.json").unwrap(), b"a").unwrap();
        write_atomic(&set.stage("b.json").unwrap(), b"b").unwrap();
        // b.json turns into a FIFO before the commit: nothing moves.
        mkfifo(&d.join("b.json"));
        let err = set.commit().unwrap_err().to_string();
        assert!(err.contains("FIFO"), "{err}");
        assert!(!d.join("a.json").exists());
        assert_eq!(std::fs::read(&decoy).unwrap(), b"precious");
        assert!(names(elsewhere.path()).is_empty());
        assert_eq!(names(d), ["b.json", "decoy", "link.json", "pairs"]);
    }

    #[test]
    fn a_failed_rename_puts_the_earlier_outputs_back() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(d.join("a.json"), b"old a").unwrap();
        let mut set = OutputSet::new(d).unwrap();
        write_atomic(&set.stage("a.json").unwrap(), b"new a").unwrap();
        write_atomic(&set.stage("b.json").unwrap(), b"new b").unwrap();
        write_atomic(&set.stage("z/c.json").unwrap(), b"new c").unwrap();
        // A file appears where the folder `z` is to be made, after the checks and the
        // first two renames: the third fails and the first two are undone.
        let in_the_way = d.join("z");
        let err = set
            .commit_with(|k| {
                if k == 2 {
                    std::fs::write(&in_the_way, b"in the way").unwrap();
                }
            })
            .unwrap_err();
        assert!(err.to_string().contains("z/c.json"), "{err}");
        assert_eq!(std::fs::read(d.join("a.json")).unwrap(), b"old a");
        assert!(!d.join("b.json").exists());
        assert_eq!(names(d), ["a.json", "z"]);
    }

    #[test]
    fn an_output_set_needs_a_folder_that_takes_files() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("file");
        std::fs::write(&f, b"x").unwrap();
        assert!(OutputSet::new(&f)
            .unwrap_err()
            .to_string()
            .contains("not a folder"));
        assert!(OutputSet::new(&dir.path().join("missing")).is_err());
    }

    #[test]
    fn one_run_at_a_time_holds_an_output_folder() {
        let dir = tempfile::tempdir().unwrap();
        let mut first = OutputSet::new(dir.path()).unwrap();
        let lock = dir.path().join(LOCK_NAME);
        assert_eq!(
            std::fs::read_to_string(&lock).unwrap().trim(),
            std::process::id().to_string()
        );
        // A second set (another run: flock locks are per open file) is refused, naming
        // the holder, and leaves nothing behind.
        let e = OutputSet::new(dir.path()).unwrap_err().to_string();
        assert!(
            e.contains(&format!(
                "another era run (process {}) is writing into this folder",
                std::process::id()
            )),
            "{e}"
        );
        // A single-file set beside it is not held up.
        let mut single = OutputSet::beside(&dir.path().join("x.csv")).unwrap();
        write_atomic(&single.stage("x.csv").unwrap(), b"x").unwrap();
        single.commit().unwrap();
        write_atomic(&first.stage("a.txt").unwrap(), b"a").unwrap();
        first.commit().unwrap();
        // The lock went with the set; the next run takes the folder.
        assert_eq!(names(dir.path()), ["a.txt", "x.csv"]);
        let again = OutputSet::new(dir.path()).unwrap();
        drop(again);
        assert_eq!(names(dir.path()), ["a.txt", "x.csv"]);
    }

    #[test]
    fn a_lock_file_left_by_a_killed_run_holds_nothing() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join(LOCK_NAME), "999999999\n").unwrap();
        let set = OutputSet::new(dir.path()).unwrap();
        drop(set);
        assert!(names(dir.path()).is_empty());
    }

    #[test]
    fn a_planted_link_as_the_lock_is_not_followed() {
        let dir = tempfile::tempdir().unwrap();
        let decoy = dir.path().join("decoy");
        std::fs::write(&decoy, "keep").unwrap();
        symlink(&decoy, dir.path().join(LOCK_NAME)).unwrap();
        let e = OutputSet::new(dir.path()).unwrap_err().to_string();
        assert!(e.contains(LOCK_NAME), "{e}");
        assert_eq!(std::fs::read_to_string(&decoy).unwrap(), "keep");
    }

    #[test]
    fn the_registry_holds_what_a_signal_must_remove() {
        let dir = tempfile::tempdir().unwrap();
        let set = OutputSet::new(dir.path()).unwrap();
        let staging = set.staging.path().to_path_buf();
        let registered = |p: &Path| live().entries.values().any(|(q, _)| q == p);
        assert!(registered(&staging));
        assert!(registered(&dir.path().join(LOCK_NAME)));
        drop(set);
        assert!(!registered(&staging));
        assert!(!registered(&dir.path().join(LOCK_NAME)));
        let target = dir.path().join("t.txt");
        write_via(&target, |p| -> Result<(), IoError> {
            assert!(registered(p));
            std::fs::write(p, "t").map_err(|e| IoError::io(p, e))
        })
        .unwrap();
        assert!(!live()
            .entries
            .values()
            .any(|(q, _)| q.starts_with(dir.path())));
    }

    #[test]
    fn a_signal_s_clean_up_removes_what_the_registry_holds_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(d.join("earlier.txt"), "earlier").unwrap();
        let tmp = d.join(".era-tmp-1-abcdefghijkl.csv");
        std::fs::write(&tmp, "half").unwrap();
        let staging = d.join(".era-staging-1-abcdefghijkl");
        std::fs::create_dir_all(staging.join("pairs")).unwrap();
        std::fs::write(staging.join("pairs/p.png"), "half").unwrap();
        let lock = d.join(LOCK_NAME);
        std::fs::write(&lock, "1\n").unwrap();
        let meta = std::fs::metadata(&lock).unwrap();
        // A lock file that is another run's by now (a new inode at the path) stays.
        let replaced = d.join("other").join(LOCK_NAME);
        std::fs::create_dir(d.join("other")).unwrap();
        std::fs::write(&replaced, "2\n").unwrap();
        let other = std::fs::metadata(&replaced).unwrap();
        let mut private = Live {
            next: 0,
            entries: BTreeMap::new(),
        };
        let registrations = [
            Registration::under(&mut private, &tmp, Kind::File),
            Registration::under(&mut private, &staging, Kind::Folder),
            Registration::under(&mut private, &lock, Kind::Lock(meta.dev(), meta.ino())),
            // An inode the file at the path does not have (`meta.ino() + 1` could be it:
            // a file system may give the next file the next inode).
            Registration::under(
                &mut private,
                &replaced,
                Kind::Lock(other.dev(), other.ino() ^ 1),
            ),
        ];
        // Their drops would settle ids of the process's registry: these are the private
        // one's.
        for r in registrations {
            std::mem::forget(r);
        }
        assert_eq!(remove_entries(&mut private), 3);
        assert!(private.entries.is_empty());
        assert_eq!(names(d), ["earlier.txt", "other"]);
        assert!(replaced.exists());
    }
}
