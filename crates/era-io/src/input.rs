//! Every input file is read here, exactly once, into memory; the readers then parse
//! those bytes and never open the path again.
//!
//! - a folder is refused;
//! - a regular file is memory-mapped (its real size is known, nothing is copied);
//! - anything else (a pipe, `/dev/stdin`, `<(…)`, a FIFO, a character device such as
//!   `/dev/zero`) is read as a stream, up to [`era::params::limits::INPUT_BYTES`] (1 GiB;
//!   `ERA_MAX_INPUT_BYTES` raises it), and refused past it.
//!
//! A FIFO is opened with `O_NONBLOCK` so that `open` itself cannot wait for a writer
//! forever, then switched back to blocking reads: with no writer the read sees the end
//! at once (an empty file), with one it reads what the writer sends.

use crate::IoError;
use era::params::limits::{Limit, Saturated, INPUT_BYTES};
use std::io::Read;
use std::path::Path;

/// The bytes of an input file.
pub enum InputBytes {
    /// A regular file, memory-mapped.
    Mapped(memmap2::Mmap),
    /// A stream read into memory (or an empty file).
    Owned(Vec<u8>),
}

impl std::ops::Deref for InputBytes {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        match self {
            InputBytes::Mapped(m) => m,
            InputBytes::Owned(v) => v,
        }
    }
}

impl std::fmt::Debug for InputBytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "InputBytes({} bytes)", self.len())
    }
}

impl InputBytes {
    /// The bytes as an owned vector (copies a mapped file).
    pub fn into_vec(self) -> Vec<u8> {
        match self {
            InputBytes::Mapped(m) => m.to_vec(),
            InputBytes::Owned(v) => v,
        }
    }
}

#[cfg(unix)]
fn open(path: &Path) -> std::io::Result<std::fs::File> {
    use std::os::unix::fs::OpenOptionsExt;
    use std::os::unix::io::AsRawFd;
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(path)?;
    // Back to blocking reads: O_NONBLOCK was only there so that open could not wait.
    let fd = file.as_raw_fd();
    // SAFETY: fcntl on a descriptor we own, with integer arguments only.
    let flags = unsafe { libc::fcntl(fd, libc::F_GETFL) };
    if flags < 0 || unsafe { libc::fcntl(fd, libc::F_SETFL, flags & !libc::O_NONBLOCK) } < 0 {
        return Err(std::io::Error::last_os_error());
    }
    Ok(file)
}

#[cfg(not(unix))]
fn open(path: &Path) -> std::io::Result<std::fs::File> {
    std::fs::File::open(path)
}

/// Reads the input at `path` once (see the module doc).
///
/// # Errors
/// [`IoError::Io`] when it cannot be opened or read; [`IoError::Format`] for a folder;
/// [`IoError::Limit`] for a stream longer than [`INPUT_BYTES`].
pub fn read_input(path: &Path) -> Result<InputBytes, IoError> {
    read_input_limited(path, INPUT_BYTES)
}

/// A folder given where a file is read: an operating-system refusal
/// ([`std::io::ErrorKind::IsADirectory`], so that Python raises `IsADirectoryError`), in
/// words that say what to do.
fn is_a_folder(path: &Path) -> IoError {
    IoError::io(
        path,
        std::io::Error::new(
            std::io::ErrorKind::IsADirectory,
            "is a folder, not a file: name a file inside it",
        ),
    )
}

/// [`read_input`] with another limit on streamed input (for tests and callers that
/// know better).
///
/// # Errors
/// As [`read_input`].
pub fn read_input_limited(path: &Path, limit: Limit) -> Result<InputBytes, IoError> {
    if path.is_dir() {
        return Err(is_a_folder(path));
    }
    let file = open(path).map_err(|e| IoError::io(path, e))?;
    let meta = file.metadata().map_err(|e| IoError::io(path, e))?;
    if meta.is_dir() {
        return Err(is_a_folder(path));
    }
    if meta.is_file() {
        if meta.len() == 0 {
            return Ok(InputBytes::Owned(Vec::new()));
        }
        // SAFETY: the map is read-only; a file truncated by another process while it is
        // read is outside what era promises (as for any mmap-based reader).
        return match unsafe { memmap2::Mmap::map(&file) } {
            Ok(map) => Ok(InputBytes::Mapped(map)),
            Err(_) => read_stream(file, path, limit, meta.len()).map(InputBytes::Owned),
        };
    }
    read_stream(file, path, limit, 0).map(InputBytes::Owned)
}

/// Reads a stream up to `limit` bytes; one byte more is an error. The buffer grows by
/// doubling but never past the limit (+1), so a stream at the limit needs at most
/// 1.5× it while the buffer moves.
fn read_stream(
    mut file: std::fs::File,
    path: &Path,
    limit: Limit,
    hint: u64,
) -> Result<Vec<u8>, IoError> {
    let allowed = limit.allowed();
    let cap = usize::try_from(allowed.saturating_add(1)).unwrap_or(usize::MAX);
    let mut buf: Vec<u8> = Vec::new();
    let mut chunk = vec![0u8; 1 << 16];
    while buf.len() < cap {
        let want = chunk.len().min(cap - buf.len());
        let n = match file.read(&mut chunk[..want]) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(IoError::io(path, e)),
        };
        if buf.len() + n > buf.capacity() {
            // Double, but never past the limit (+1 byte to notice going over it).
            let grow = buf
                .capacity()
                .max(usize::try_from(hint).unwrap_or(0))
                .max(1 << 16)
                .min(cap - buf.len())
                .max(n);
            buf.try_reserve_exact(grow).map_err(|_| {
                IoError::format(
                    path,
                    "",
                    format!(
                        "cannot hold {} bytes of input in memory",
                        Saturated(buf.len().checked_add(grow))
                    ),
                )
            })?;
        }
        buf.extend_from_slice(&chunk[..n]);
    }
    if buf.len() as u64 > allowed {
        return Err(IoError::limit(
            path,
            era::params::limits::LimitError {
                context: "input read as a stream (a pipe, FIFO or device)".into(),
                asked: buf.len() as u64,
                allowed,
                what: limit.what,
                env: limit.env,
            },
        ));
    }
    Ok(buf)
}

/// The bytes as UTF-8 text without a leading byte-order mark.
///
/// # Errors
/// [`IoError::Format`] naming the line and byte column of the first invalid byte.
pub fn utf8<'a>(bytes: &'a [u8], path: &Path) -> Result<&'a str, IoError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    std::str::from_utf8(bytes).map_err(|e| {
        let at = e.valid_up_to();
        let line = 1 + bytes[..at].iter().filter(|b| **b == b'\n').count();
        let column = at
            - bytes[..at]
                .iter()
                .rposition(|b| *b == b'\n')
                .map_or(0, |p| p + 1)
            + 1;
        IoError::format(
            path,
            format!("line {line}, byte {column}: "),
            format!(
                "not UTF-8 text (byte 0x{:02x}); save the file as UTF-8",
                bytes[at]
            ),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folders_are_refused_and_files_read() {
        let dir = tempfile::tempdir().unwrap();
        let e = read_input(dir.path()).unwrap_err().to_string();
        assert!(e.contains("folder"), "{e}");
        let f = dir.path().join("a.csv");
        std::fs::write(&f, "abc").unwrap();
        assert_eq!(&*read_input(&f).unwrap(), b"abc");
        std::fs::write(&f, "").unwrap();
        assert!(read_input(&f).unwrap().is_empty());
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_device_stream_stops_at_the_limit() {
        let limit = Limit {
            what: "bytes",
            default: 100_000,
            env: "ERA_TEST_INPUT_LIMIT_NEVER_SET",
        };
        let e = read_input_limited(Path::new("/dev/zero"), limit).unwrap_err();
        assert!(matches!(e, IoError::Limit { .. }), "{e}");
        let m = e.to_string();
        assert!(
            m.contains("100000") && m.contains("ERA_TEST_INPUT_LIMIT_NEVER_SET"),
            "{m}"
        );
    }

    #[test]
    fn utf8_drops_a_bom_and_names_a_bad_byte() {
        assert_eq!(utf8(b"\xEF\xBB\xBFa,b", Path::new("f")).unwrap(), "a,b");
        let e = utf8(b"a\nbc\xff", Path::new("f")).unwrap_err().to_string();
        assert!(e.contains("line 2, byte 3") && e.contains("0xff"), "{e}");
    }
}
