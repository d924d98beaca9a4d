//! The salsa database: source files are inputs, everything else is a query.

use dashmap::DashMap;
use mcl_net::input::Reason;
use salsa::Setter;
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;

/// One source file. `text` is `None` when the file does not exist or cannot
/// be read (`unreadable` says why); it is still an input so that creating the
/// file later invalidates every query that looked for it. Files are read by
/// `mcl_net::input` (regular files only, at most 16 MiB).
#[salsa::input(debug)]
pub struct SourceFile {
    #[returns(ref)]
    pub path: PathBuf,
    #[returns(ref)]
    pub text: Option<Arc<str>>,
    /// Why `text` is `None`.
    #[returns(ref)]
    pub unreadable: Option<Reason>,
}

/// The database interface the queries need.
#[salsa::db]
pub trait Db: salsa::Database {
    /// The input for `path` (normalized), reading it from disk on first use
    /// unless an editor has set its text.
    fn file(&self, path: &Path) -> SourceFile;
    /// The standard library file, implicitly imported by every program.
    fn stdlib(&self) -> SourceFile;
}

/// The path under which the standard library appears in diagnostics.
pub const STDLIB_PATH: &str = "<mcl-std>/std.mcl";
/// The text of the standard library.
pub const STDLIB_TEXT: &str = include_str!("../std/std.mcl");

/// The concrete database used by the CLI and the language server.
#[salsa::db]
#[derive(Clone, Default)]
pub struct Database {
    storage: salsa::Storage<Self>,
    files: Arc<DashMap<PathBuf, SourceFile>>,
}

#[salsa::db]
impl salsa::Database for Database {}

#[salsa::db]
impl Db for Database {
    fn file(&self, path: &Path) -> SourceFile {
        let path = normalize(path);
        if let Some(f) = self.files.get(&path) {
            return *f;
        }
        let (text, unreadable) = read(&path);
        *self.files.entry(path.clone()).or_insert_with(|| SourceFile::new(self, path, text, unreadable))
    }

    fn stdlib(&self) -> SourceFile {
        let path = PathBuf::from(STDLIB_PATH);
        if let Some(f) = self.files.get(&path) {
            return *f;
        }
        *self
            .files
            .entry(path.clone())
            .or_insert_with(|| SourceFile::new(self, path, Some(Arc::from(STDLIB_TEXT)), None))
    }
}

impl Database {
    pub fn new() -> Self {
        Self::default()
    }

    /// A database that reports every salsa event (query executions, ...) to
    /// `f`: for tests of incrementality and for profiling.
    pub fn with_events(f: impl Fn(salsa::Event) + Send + Sync + 'static) -> Self {
        Database { storage: salsa::Storage::new(Some(Box::new(f))), files: Default::default() }
    }

    /// Sets the text of a file, as an editor does for an open document
    /// (creating the input if needed). Returns the input.
    pub fn set_text(&mut self, path: &Path, text: impl Into<Arc<str>>) -> SourceFile {
        let path = normalize(path);
        let text = Some(text.into());
        let existing = self.files.get(&path).map(|f| *f);
        match existing {
            Some(f) => {
                if f.text(self) != &text {
                    f.set_text(self).to(text);
                }
                if f.unreadable(self).is_some() {
                    f.set_unreadable(self).to(None);
                }
                f
            }
            None => {
                let f = SourceFile::new(self, path.clone(), text, None);
                self.files.insert(path, f);
                f
            }
        }
    }

    /// Re-reads a file from disk (after a change notification, or when an
    /// editor closes it).
    pub fn reload(&mut self, path: &Path) {
        let path = normalize(path);
        let existing = self.files.get(&path).map(|f| *f);
        if let Some(f) = existing {
            let (text, unreadable) = read(&path);
            if f.text(self) != &text {
                f.set_text(self).to(text);
            }
            if f.unreadable(self) != &unreadable {
                f.set_unreadable(self).to(unreadable);
            }
        }
    }

    /// Every file the database knows.
    pub fn files(&self) -> Vec<SourceFile> {
        self.files.iter().map(|e| *e.value()).collect()
    }
}

/// The text of a file, or why it cannot be read. Never blocks (a FIFO is
/// refused before it is opened) and never reads more than
/// `mcl_net::input::MAX_SOURCE_BYTES`.
fn read(path: &Path) -> (Option<Arc<str>>, Option<Reason>) {
    // A byte order mark is no part of the text: without it, byte offsets,
    // columns and the rendered source lines agree.
    match mcl_net::input::read_source(path) {
        Ok(t) => (Some(t.strip_prefix('\u{feff}').map_or_else(|| Arc::from(t.as_str()), Arc::from)), None),
        Err(e) => (None, Some(e.reason)),
    }
}

/// Makes a path absolute and removes `.` and `..` components lexically (and
/// resolves symlinks when the file exists), so that one file has one input.
pub fn normalize(path: &Path) -> PathBuf {
    if path.starts_with("<mcl-std>") {
        return path.to_path_buf();
    }
    if let Ok(p) = path.canonicalize() {
        return p;
    }
    let abs =
        if path.is_absolute() { path.to_path_buf() } else { std::env::current_dir().unwrap_or_default().join(path) };
    let mut out = PathBuf::new();
    for c in abs.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other.as_os_str()),
        }
    }
    out
}
