//! The mutable side of the server: the salsa database and the open
//! documents. Edits are applied here, in the order the client sent them, by
//! one thread; readers take snapshots (`Database::clone`) that salsa cancels
//! when the next edit is applied.

use crate::analysis::{path_of_uri, DocInfo, World};
use mcl_compiler::Database;
use mcl_syntax::LineIndex;
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard};
use tower_lsp_server::ls_types::{FileChangeType, FileEvent, TextDocumentContentChangeEvent, Uri};

/// A change of the server's inputs, in protocol order.
#[derive(Debug)]
pub enum Edit {
    Open {
        uri: Uri,
        version: i32,
        text: String,
    },
    Change {
        uri: Uri,
        version: i32,
        changes: Vec<TextDocumentContentChangeEvent>,
    },
    Close {
        uri: Uri,
    },
    Watched {
        changes: Vec<FileEvent>,
    },
    /// The `*.mcl` files of the workspace folders (see [`scan_workspace`]).
    Workspace {
        files: Vec<PathBuf>,
    },
}

/// A read-only view: never keep one across an `.await`, and drop it soon:
/// the next edit waits until every snapshot is gone.
pub struct Snapshot {
    pub db: Database,
    pub world: Arc<World>,
    pub generation: u64,
}

pub struct HostState {
    pub db: Database,
    pub world: Arc<World>,
    /// Incremented by every applied batch of edits.
    pub generation: u64,
    /// Files changed by edits whose diagnostics are not yet published, with
    /// the generation that changed them.
    pub pending: Vec<(u64, PathBuf)>,
    /// Documents closed since the last diagnostics pass (to clear theirs).
    pub closed: Vec<(u64, Uri)>,
}

pub struct Host {
    state: Mutex<HostState>,
}

impl Default for Host {
    fn default() -> Self {
        Self::new()
    }
}

/// The most files taken from the workspace folders.
const MAX_WORKSPACE_FILES: usize = 5_000;

impl Host {
    pub fn new() -> Self {
        Self::with_std_copy(crate::analysis::materialize_stdlib())
    }

    /// A host that shows the standard library from `std_copy` (if any).
    pub fn with_std_copy(std_copy: Option<PathBuf>) -> Self {
        let world = World { std_copy, ..Default::default() };
        Host {
            state: Mutex::new(HostState {
                db: Database::new(),
                world: Arc::new(world),
                generation: 0,
                pending: Vec::new(),
                closed: Vec::new(),
            }),
        }
    }

    pub fn lock(&self) -> MutexGuard<'_, HostState> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    pub fn snapshot(&self) -> Snapshot {
        let s = self.lock();
        Snapshot { db: s.db.clone(), world: s.world.clone(), generation: s.generation }
    }

    /// Applies a batch of edits, in order. Waits for running readers to
    /// notice their cancellation and drop their snapshots.
    pub fn apply(&self, edits: Vec<Edit>) {
        let mut guard = self.lock();
        let s = &mut *guard;
        s.generation += 1;
        let generation = s.generation;
        for edit in edits {
            match edit {
                Edit::Open { uri, version, text } => {
                    let path = path_of_uri(&uri);
                    let world = Arc::make_mut(&mut s.world);
                    world.by_uri.insert(uri.as_str().to_string(), path.clone());
                    world.docs.insert(path.clone(), DocInfo { uri, path: path.clone(), version });
                    s.db.set_text(&path, text);
                    s.pending.push((generation, path));
                }
                Edit::Change { uri, version, changes } => {
                    let path = s.world.path_of(&uri);
                    if !s.world.docs.contains_key(&path) {
                        continue; // not open: nothing to change
                    }
                    let file = mcl_compiler::Db::file(&s.db, &path);
                    let mut text: String = file.text(&s.db).as_deref().unwrap_or("").to_string();
                    for c in changes {
                        apply_change(&mut text, c);
                    }
                    let world = Arc::make_mut(&mut s.world);
                    if let Some(d) = world.docs.get_mut(&path) {
                        d.version = version;
                    }
                    s.db.set_text(&path, text);
                    s.pending.push((generation, path));
                }
                Edit::Close { uri } => {
                    let path = s.world.path_of(&uri);
                    let world = Arc::make_mut(&mut s.world);
                    world.docs.remove(&path);
                    world.by_uri.remove(uri.as_str());
                    s.db.reload(&path);
                    s.pending.push((generation, path));
                    s.closed.push((generation, uri));
                }
                Edit::Watched { changes } => {
                    for ev in changes {
                        let path = path_of_uri(&ev.uri);
                        if s.world.docs.contains_key(&path) {
                            continue; // the editor's text wins
                        }
                        let is_mcl = path.extension().is_some_and(|x| x == "mcl");
                        let world = Arc::make_mut(&mut s.world);
                        if is_mcl && ev.typ == FileChangeType::CREATED && !world.workspace_files.contains(&path) {
                            Arc::make_mut(&mut world.workspace_files).push(path.clone());
                        }
                        if ev.typ == FileChangeType::DELETED {
                            Arc::make_mut(&mut world.workspace_files).retain(|p| p != &path);
                        }
                        s.db.reload(&path);
                        s.pending.push((generation, path));
                    }
                }
                Edit::Workspace { files } => {
                    Arc::make_mut(&mut s.world).workspace_files = Arc::new(files);
                }
            }
        }
    }
}

/// Applies one content change (a range in UTF-16 positions, or the whole text).
pub fn apply_change(text: &mut String, change: TextDocumentContentChangeEvent) {
    match change.range {
        None => *text = change.text,
        Some(r) => {
            let idx = LineIndex::new(text);
            let s = idx.offset_of_utf16(text, r.start.line, r.start.character);
            let e = idx.offset_of_utf16(text, r.end.line, r.end.character);
            let (s, e) = (s.min(e), s.max(e));
            text.replace_range(s..e, &change.text);
        }
    }
}

/// The `*.mcl` files under the workspace folders (sorted, without hidden
/// folders and build output; at most 5,000 files, 12 levels and 5 seconds).
pub fn scan_workspace(roots: &[PathBuf]) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut seen = HashSet::new();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(5);
    for r in roots {
        walk(r, &mut files, &mut seen, 0, deadline);
    }
    files
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>, seen: &mut HashSet<PathBuf>, depth: usize, deadline: std::time::Instant) {
    if depth > 12 || out.len() >= MAX_WORKSPACE_FILES || std::time::Instant::now() > deadline {
        return;
    }
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    let mut entries: Vec<_> = rd.filter_map(Result::ok).collect();
    entries.sort_by_key(|e| e.file_name());
    for e in entries {
        let path = e.path();
        let name = e.file_name().to_string_lossy().into_owned();
        let Ok(ft) = e.file_type() else { continue };
        if ft.is_dir() {
            if !name.starts_with('.') && name != "target" && name != "node_modules" {
                walk(&path, out, seen, depth + 1, deadline);
            }
        } else if path.extension().is_some_and(|x| x == "mcl") && out.len() < MAX_WORKSPACE_FILES {
            let p = mcl_compiler::db::normalize(&path);
            if seen.insert(p.clone()) {
                out.push(p);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::{diagnostics, Analysis};
    use std::panic::AssertUnwindSafe;
    use std::str::FromStr;
    use tower_lsp_server::ls_types::{Position, Range};

    fn uri() -> Uri {
        Uri::from_str("file:///host-test/a.mcl").unwrap()
    }

    fn change(l1: u32, c1: u32, l2: u32, c2: u32, text: &str) -> TextDocumentContentChangeEvent {
        TextDocumentContentChangeEvent {
            range: Some(Range { start: Position::new(l1, c1), end: Position::new(l2, c2) }),
            range_length: None,
            text: text.into(),
        }
    }

    fn text_of(host: &Host) -> String {
        let snap = host.snapshot();
        let f = mcl_compiler::Db::file(&snap.db, &snap.world.path_of(&uri()));
        f.text(&snap.db).as_deref().unwrap_or("").to_string()
    }

    #[test]
    fn incremental_changes_apply_in_order_and_clamp() {
        let host = Host::with_std_copy(None);
        host.apply(vec![Edit::Open { uri: uri(), version: 1, text: "ab\ncd\n".into() }]);
        host.apply(vec![
            Edit::Change { uri: uri(), version: 2, changes: vec![change(0, 1, 0, 1, "X"), change(1, 0, 1, 2, "é")] },
            Edit::Change { uri: uri(), version: 3, changes: vec![change(1, 1, 1, 1, "!")] },
        ]);
        assert_eq!(text_of(&host), "aXb\né!\n");
        // Positions past the end are clamped, a range given backwards is turned around.
        host.apply(vec![Edit::Change { uri: uri(), version: 4, changes: vec![change(9, 9, 0, 1, "")] }]);
        assert_eq!(text_of(&host), "a");
        assert_eq!(host.snapshot().world.version_of(&host.snapshot().world.path_of(&uri())), Some(4));
        // Changes to a document that is not open are ignored.
        let other = Uri::from_str("file:///host-test/b.mcl").unwrap();
        host.apply(vec![Edit::Change { uri: other, version: 1, changes: vec![change(0, 0, 0, 0, "x")] }]);
        host.apply(vec![Edit::Close { uri: uri() }]);
        assert!(host.snapshot().world.docs.is_empty());
    }

    #[test]
    fn a_pending_edit_cancels_readers() {
        let host = Arc::new(Host::with_std_copy(None));
        let text = mcl_syntax::gen::program(600, 1);
        host.apply(vec![Edit::Open { uri: uri(), version: 1, text: text.clone() }]);
        let snap = host.snapshot();
        let file = mcl_compiler::Db::file(&snap.db, &snap.world.path_of(&uri()));
        let writer = {
            let host = host.clone();
            let text = format!("{text}\nmission : nope {{ Nope() }}\n");
            std::thread::spawn(move || {
                host.apply(vec![Edit::Change {
                    uri: uri(),
                    version: 2,
                    changes: vec![TextDocumentContentChangeEvent { range: None, range_length: None, text }],
                }])
            })
        };
        // The reader runs until the writer's cancellation reaches it.
        let started = std::time::Instant::now();
        loop {
            let r = salsa::Cancelled::catch(AssertUnwindSafe(|| {
                diagnostics::full(&Analysis::new(&snap.db, &snap.world), file).len()
            }));
            match r {
                Err(_) => break,
                Ok(n) => assert_eq!(n, 0),
            }
            assert!(started.elapsed().as_secs() < 20, "never cancelled");
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        drop(snap); // lets the write proceed
        writer.join().unwrap();
        let snap = host.snapshot();
        let d = diagnostics::full(&Analysis::new(&snap.db, &snap.world), file);
        assert_eq!(d.len(), 1, "{d:?}");
        assert_eq!(snap.world.version_of(&snap.world.path_of(&uri())), Some(2));
    }
}
