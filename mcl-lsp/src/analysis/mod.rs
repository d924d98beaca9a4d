//! The editor features, as plain functions over a database snapshot.
//!
//! Nothing here knows about tokio or the transport: every function takes an
//! [`Analysis`] (a `&Database` plus what the server knows about open
//! documents) and returns LSP values. Salsa may cancel any of them by
//! unwinding with `salsa::Cancelled` when an edit arrives; the server catches
//! that and answers `ContentModified`.

pub mod bridge;
pub mod completion;
pub mod coordination;
pub mod diagnostics;
pub mod fixes;
pub mod hover;
pub mod index;
pub mod navigation;
pub mod outline;
pub mod semantic;

use mcl_compiler::db::STDLIB_PATH;
use mcl_compiler::queries::{line_index, parse, program};
use mcl_compiler::{Database, Db, SourceFile};
use mcl_syntax::{LineIndex, Span};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::Arc;
use tower_lsp_server::ls_types::{Location, Position, Range, Uri};

/// An open document, as the server last saw it.
#[derive(Clone, Debug)]
pub struct DocInfo {
    pub uri: Uri,
    pub path: PathBuf,
    pub version: i32,
}

/// What the server knows besides the database: open documents (by path and
/// by URI), the `*.mcl` files of the workspace folders, and where the
/// standard library is shown.
#[derive(Clone, Debug, Default)]
pub struct World {
    pub docs: HashMap<PathBuf, DocInfo>,
    pub by_uri: HashMap<String, PathBuf>,
    pub workspace_files: Arc<Vec<PathBuf>>,
    /// A copy of the standard library on disk, so that "go to definition"
    /// of `AchieveOneGoal` opens something (written on first use).
    pub std_copy: Option<PathBuf>,
}

impl World {
    /// The path the database uses for a URI: the file path of a `file:` URI
    /// (normalized), or a stable made-up path for other schemes.
    pub fn path_of(&self, uri: &Uri) -> PathBuf {
        if let Some(p) = self.by_uri.get(uri.as_str()) {
            return p.clone();
        }
        path_of_uri(uri)
    }

    /// The URI of a path: the open document's own URI if it is open.
    pub fn uri_of(&self, path: &Path) -> Option<Uri> {
        if let Some(d) = self.docs.get(path) {
            return Some(d.uri.clone());
        }
        if path == Path::new(STDLIB_PATH) {
            return self.std_copy.as_ref().and_then(Uri::from_file_path);
        }
        Uri::from_file_path(path)
    }

    pub fn version_of(&self, path: &Path) -> Option<i32> {
        self.docs.get(path).map(|d| d.version)
    }
}

/// The database path of a URI that is not an open document.
pub fn path_of_uri(uri: &Uri) -> PathBuf {
    let is_file = uri.scheme().as_str().eq_ignore_ascii_case("file");
    if is_file {
        if let Some(p) = uri.to_file_path() {
            return mcl_compiler::db::normalize(&p);
        }
    }
    // `untitled:Untitled-1` and friends: a path no disk file has.
    let safe: String =
        uri.as_str().chars().map(|c| if c.is_ascii_alphanumeric() || c == '.' || c == '-' { c } else { '_' }).collect();
    PathBuf::from(format!("/.mcl-lsp-virtual/{safe}"))
}

/// Writes the standard library next to the user's caches so that a client
/// can open it; returns its path.
pub fn materialize_stdlib() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
        .unwrap_or_else(std::env::temp_dir);
    let dir = base.join("mcl").join(format!("std-{}", env!("CARGO_PKG_VERSION")));
    let path = dir.join("std.mcl");
    let text = mcl_compiler::db::STDLIB_TEXT;
    if std::fs::read_to_string(&path).ok().as_deref() != Some(text) {
        std::fs::create_dir_all(&dir).ok()?;
        std::fs::write(&path, text).ok()?;
    }
    path.canonicalize().ok()
}

/// A read-only view for one request: a database snapshot and the world.
pub struct Analysis<'a> {
    pub db: &'a Database,
    pub world: &'a World,
}

impl<'a> Analysis<'a> {
    pub fn new(db: &'a Database, world: &'a World) -> Self {
        Analysis { db, world }
    }

    pub fn dyn_db(&self) -> &'a dyn Db {
        self.db
    }

    /// The input of a document (open or not).
    pub fn file(&self, uri: &Uri) -> SourceFile {
        self.db.file(&self.world.path_of(uri))
    }

    pub fn file_at(&self, path: &Path) -> SourceFile {
        self.db.file(path)
    }

    pub fn text(&self, file: SourceFile) -> &'a str {
        file.text(self.db).as_deref().unwrap_or("")
    }

    pub fn line_index(&self, file: SourceFile) -> &'a LineIndex {
        line_index(self.db, file)
    }

    pub fn ast(&self, file: SourceFile) -> &'a mcl_syntax::ast::SourceFile {
        &parse(self.db, file).file
    }

    pub fn is_std(&self, file: SourceFile) -> bool {
        file == self.db.stdlib()
    }

    pub fn path(&self, file: SourceFile) -> &'a Path {
        file.path(self.db)
    }

    pub fn uri(&self, file: SourceFile) -> Option<Uri> {
        self.world.uri_of(file.path(self.db))
    }

    pub fn position(&self, file: SourceFile, offset: usize) -> Position {
        let (line, character) = self.line_index(file).utf16_position(self.text(file), offset);
        Position { line, character }
    }

    pub fn range(&self, file: SourceFile, span: Span) -> Range {
        Range { start: self.position(file, span.start as usize), end: self.position(file, span.end as usize) }
    }

    pub fn offset(&self, file: SourceFile, pos: Position) -> usize {
        self.line_index(file).offset_of_utf16(self.text(file), pos.line, pos.character)
    }

    pub fn span_of(&self, file: SourceFile, range: Range) -> Span {
        let s = self.offset(file, range.start);
        let e = self.offset(file, range.end);
        Span::new(s.min(e), s.max(e))
    }

    pub fn location(&self, file: SourceFile, span: Span) -> Option<Location> {
        Some(Location { uri: self.uri(file)?, range: self.range(file, span) })
    }

    /// The file a diagnostic label names (`None`: the diagnostic's own file).
    pub fn label_file(&self, own: SourceFile, other: Option<&str>) -> SourceFile {
        match other {
            None => own,
            Some(p) => self.db.file(Path::new(p)),
        }
    }

    /// Every file the server can see: open documents, the files they
    /// import, and the `*.mcl` files of the workspace folders (not the
    /// standard library), without duplicates, in a stable order.
    pub fn universe(&self) -> Vec<SourceFile> {
        let mut seen = std::collections::HashSet::new();
        let mut out = Vec::new();
        let mut open: Vec<&PathBuf> = self.world.docs.keys().collect();
        open.sort();
        let std = self.db.stdlib();
        for p in open {
            let f = self.db.file(p);
            for &g in &program(self.db, f).files {
                if g != std && seen.insert(g) {
                    out.push(g);
                }
            }
        }
        for p in self.world.workspace_files.iter() {
            if Some(p) == self.world.std_copy.as_ref() {
                continue;
            }
            let f = self.db.file(p);
            if f.text(self.db).is_some() && seen.insert(f) {
                out.push(f);
            }
        }
        out
    }

    /// The files whose diagnostics the server publishes: open documents and
    /// the files they import (not the standard library).
    pub fn diagnosed_files(&self) -> Vec<SourceFile> {
        let mut seen = std::collections::HashSet::new();
        let mut out = Vec::new();
        let mut open: Vec<&PathBuf> = self.world.docs.keys().collect();
        open.sort();
        let std = self.db.stdlib();
        for p in open {
            if Some(p) == self.world.std_copy.as_ref() {
                continue; // the standard library, opened from its copy
            }
            if bridge::is_bridge_like(p) {
                continue; // a ROS 2 bridge file (TOML), checked by `bridge`
            }
            let f = self.db.file(p);
            for &g in &program(self.db, f).files {
                if g != std && g.text(self.db).is_some() && seen.insert(g) {
                    out.push(g);
                }
            }
        }
        out
    }
}

/// Parses `text` as a URI (for tests and fixtures).
pub fn uri(text: &str) -> Uri {
    Uri::from_str(text).expect("valid URI")
}

#[cfg(test)]
pub(crate) mod fixture;
#[cfg(test)]
mod tests;

/// `text` (written with `\n`) in the line ends of `like` (`\r\n` if it has
/// one, else a lone `\r` if it has one and no `\n`), and those line ends.
pub fn with_line_ends(text: &str, like: &str) -> (String, &'static str) {
    let eol = if like.contains("\r\n") {
        "\r\n"
    } else if like.contains('\r') && !like.contains('\n') {
        "\r"
    } else {
        "\n"
    };
    if eol == "\n" {
        (text.to_string(), eol)
    } else {
        (text.replace("\r\n", "\n").replace('\n', eol), eol)
    }
}
