//! Reading input files with bounds: the one reader of every file a command
//! or an import names (MCL sources, PNML, PDDL, scenarios, journals,
//! traces).
//!
//! Only regular files are read: a folder, a device (`/dev/zero`), a FIFO or a
//! socket is refused from its metadata, before it is opened (opening a FIFO
//! blocks until a writer comes). The file is then opened without blocking
//! and checked again (it may have been replaced in between), and at most
//! `limit + 1` bytes are read, so that a file larger than the limit is
//! refused without being read whole, even one that grows while it is read.
//! It lives in `mcl-net` because every crate that reads files depends on it.

use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};

/// The limit on a source file (MCL, PNML, PDDL, scenarios, world models,
/// plans): 16 MiB.
pub const MAX_SOURCE_BYTES: u64 = 16 << 20;

/// The limit on a file of records written by a run (traces, journals): 256 MiB.
pub const MAX_RECORDS_BYTES: u64 = 256 << 20;

/// Why a file was not read.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Reason {
    /// Nothing at this path.
    NotFound,
    /// A folder.
    Folder,
    /// Something that is not a regular file: a device, a FIFO, a socket
    /// (named in the text).
    NotRegular(&'static str),
    /// More bytes than the limit.
    TooLarge {
        /// The limit, in bytes.
        limit: u64,
    },
    /// Bytes that are not UTF-8 text.
    NotUtf8,
    /// Any other input/output error (its text).
    Io(String),
}

impl fmt::Display for Reason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Reason::NotFound => write!(f, "no such file"),
            Reason::Folder => write!(f, "it is a folder"),
            Reason::NotRegular(kind) => write!(f, "it is {kind}, not a regular file"),
            Reason::TooLarge { limit } => write!(f, "it is larger than the limit of {}", size(*limit)),
            Reason::NotUtf8 => write!(f, "it is not UTF-8 text"),
            Reason::Io(e) => write!(f, "{e}"),
        }
    }
}

/// A size in the largest binary unit that divides it.
fn size(bytes: u64) -> String {
    match bytes {
        b if b >= 1 << 20 && b % (1 << 20) == 0 => format!("{} MiB", b >> 20),
        b if b >= 1 << 10 && b % (1 << 10) == 0 => format!("{} KiB", b >> 10),
        b => format!("{b} bytes"),
    }
}

/// A file that could not be read: its path and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReadError {
    /// The path as given.
    pub path: PathBuf,
    /// Why it was not read.
    pub reason: Reason,
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "cannot read `{}`: {}", self.path.display(), self.reason)
    }
}

impl std::error::Error for ReadError {}

/// The kind of a file that is neither a folder nor a regular file.
fn special_kind(ft: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ft.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if ft.is_socket() {
            return "a socket";
        }
        if ft.is_char_device() {
            return "a character device";
        }
        if ft.is_block_device() {
            return "a block device";
        }
    }
    let _ = ft;
    "a special file"
}

fn io_reason(e: &std::io::Error) -> Reason {
    match e.kind() {
        std::io::ErrorKind::NotFound => Reason::NotFound,
        _ => Reason::Io(e.to_string()),
    }
}

/// Checks a file's type (symlinks followed): `Ok` for a regular file.
fn check_type(ft: &std::fs::FileType) -> Result<(), Reason> {
    if ft.is_file() {
        Ok(())
    } else if ft.is_dir() {
        Err(Reason::Folder)
    } else {
        Err(Reason::NotRegular(special_kind(ft)))
    }
}

/// Opens a path for reading without ever blocking on it.
fn open(path: &Path) -> std::io::Result<std::fs::File> {
    let mut o = std::fs::OpenOptions::new();
    o.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        o.custom_flags(libc::O_NONBLOCK);
    }
    o.open(path)
}

/// The bytes of the regular file at `path`, at most `limit` of them.
pub fn read_bytes(path: &Path, limit: u64) -> Result<Vec<u8>, ReadError> {
    let fail = |reason| ReadError { path: path.to_path_buf(), reason };
    let meta = std::fs::metadata(path).map_err(|e| fail(io_reason(&e)))?;
    check_type(&meta.file_type()).map_err(fail)?;
    if meta.len() > limit {
        return Err(fail(Reason::TooLarge { limit }));
    }
    let file = open(path).map_err(|e| fail(io_reason(&e)))?;
    // The path may name another file now: check the one that is open.
    let meta = file.metadata().map_err(|e| fail(io_reason(&e)))?;
    check_type(&meta.file_type()).map_err(fail)?;
    let mut bytes = Vec::with_capacity(meta.len().min(limit) as usize);
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes).map_err(|e| fail(io_reason(&e)))?;
    if bytes.len() as u64 > limit {
        return Err(fail(Reason::TooLarge { limit }));
    }
    Ok(bytes)
}

/// The UTF-8 text of the regular file at `path`, at most `limit` bytes.
pub fn read_text(path: &Path, limit: u64) -> Result<String, ReadError> {
    let bytes = read_bytes(path, limit)?;
    String::from_utf8(bytes).map_err(|_| ReadError { path: path.to_path_buf(), reason: Reason::NotUtf8 })
}

/// The text of a source file (MCL, PNML, PDDL, scenario, world model,
/// plan): [`read_text`] with [`MAX_SOURCE_BYTES`].
pub fn read_source(path: &Path) -> Result<String, ReadError> {
    read_text(path, MAX_SOURCE_BYTES)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("mcl-net-input-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn regular_files_are_read_within_the_limit() {
        let d = tmp("regular");
        let p = d.join("a.txt");
        std::fs::write(&p, "hello").unwrap();
        assert_eq!(read_text(&p, 5).unwrap(), "hello");
        assert_eq!(read_text(&p, 4).unwrap_err().reason, Reason::TooLarge { limit: 4 });
        std::fs::write(&p, [0xff, 0xfe]).unwrap();
        assert_eq!(read_text(&p, 10).unwrap_err().reason, Reason::NotUtf8);
        assert_eq!(read_text(&d.join("none"), 10).unwrap_err().reason, Reason::NotFound);
        assert_eq!(read_text(&d, 10).unwrap_err().reason, Reason::Folder);
        let e = read_source(&d).unwrap_err().to_string();
        assert!(e.starts_with("cannot read `") && e.ends_with("`: it is a folder"), "{e}");
        assert_eq!(Reason::TooLarge { limit: MAX_SOURCE_BYTES }.to_string(), "it is larger than the limit of 16 MiB");
    }

    #[cfg(unix)]
    #[test]
    fn devices_fifos_and_sockets_are_refused_without_blocking() {
        let e = read_source(Path::new("/dev/zero")).unwrap_err();
        assert_eq!(e.reason, Reason::NotRegular("a character device"));
        let d = tmp("special");
        let fifo = d.join("fifo");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|s| s.success()) {
            assert_eq!(read_source(&fifo).unwrap_err().reason, Reason::NotRegular("a FIFO (named pipe)"));
        }
        let sock = d.join("sock");
        let _l = std::os::unix::net::UnixListener::bind(&sock).unwrap();
        assert_eq!(read_source(&sock).unwrap_err().reason, Reason::NotRegular("a socket"));
    }
}
