//! Writes through a temporary file and a rename.

use crate::IoError;
use std::io::Write;
use std::path::Path;

/// The temporary file for `path`: in the same folder (so the rename is atomic), hidden,
/// tagged with the process id, and keeping the extension, since some writers (image
/// encoders) pick the format from it.
fn temporary_for(path: &Path) -> std::path::PathBuf {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let stem = path
        .file_stem()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let pid = std::process::id();
    match path.extension() {
        Some(ext) => dir.join(format!(".{stem}.tmp-{pid}.{}", ext.to_string_lossy())),
        None => dir.join(format!(".{stem}.tmp-{pid}")),
    }
}

/// Runs `write` on a temporary file beside `path`, then renames it over `path`. On any
/// failure the temporary file is removed and `path` is untouched. Every writer of the
/// project goes through here.
///
/// # Errors
/// What `write` returns, or [`IoError::Io`] naming `path` when the rename fails.
pub fn write_via<E: From<IoError>>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    let tmp = temporary_for(path);
    let result = write(&tmp)
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| E::from(IoError::io(path, e))));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Writes `bytes` to `path` atomically ([`write_via`]), flushed and synced before the
/// rename.
///
/// # Errors
/// [`IoError::Io`] naming `path` when the folder is missing or not writable.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    write_via(path, |tmp| {
        (|| {
            let mut file = std::fs::File::create(tmp)?;
            file.write_all(bytes)?;
            file.sync_all()
        })()
        .map_err(|e| IoError::io(path, e))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_and_replaces() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "two");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
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
        assert_eq!(seen.unwrap().extension().unwrap(), "png");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn missing_folder_is_an_error_naming_the_file() {
        let err = write_atomic(Path::new("/nonexistent-dir-era/x.txt"), b"a").unwrap_err();
        assert!(err.to_string().contains("/nonexistent-dir-era/x.txt"));
    }
}
