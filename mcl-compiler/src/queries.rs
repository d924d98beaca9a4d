//! Tracked queries over source files: items, parsing, line indexes, imports.
//!
//! A file is parsed item by item: [`file_items`] cuts its text into top-level
//! items (cheap: a lexer pass), and [`parse_item`] parses one item's text,
//! with spans relative to the item's start. An item is keyed by its text
//! alone ([`ItemText`]), so an edit inside one mission reparses that mission
//! only, and moving an item (text inserted before it) reparses nothing.
//! [`parse`] assembles the whole file with absolute spans for the consumers
//! that want a file (compilation, navigation, formatting).

use crate::codes;
use crate::db::{normalize, Db, SourceFile};
use crate::diagnostics::FileDiagnostic;
use mcl_syntax::ast::Item;
use mcl_syntax::lexer::Kw;
use mcl_syntax::{Diagnostic, LineIndex, Parse, Shift, Span};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// The text of one top-level item, and the keyword of the item after it (the
/// parser reports what follows an unfinished item). Equal texts are one key.
#[salsa::interned(debug)]
pub struct ItemText<'db> {
    #[returns(ref)]
    pub text: String,
    pub next: Option<(Kw, u32)>,
}

/// One part of a file as cut by [`file_items`]: its text and where it starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, salsa::SalsaValue)]
pub struct Chunk<'db> {
    pub start: u32,
    pub text: ItemText<'db>,
}

/// The parts of a file: the prelude (what comes before the first item),
/// then one part per top-level item (`mcl_syntax::split_items`).
///
/// After an edit, the cut starts from the file's previous cut
/// ([`mcl_syntax::split_items_edit`]: only the text around the edit is
/// lexed again), and unchanged items are interned without copying.
#[salsa::tracked(returns(ref))]
pub fn file_items<'db>(db: &'db dyn Db, file: SourceFile) -> Vec<Chunk<'db>> {
    let Some(text) = file.text(db) else { return vec![Chunk { start: 0, text: ItemText::new(db, "", None) }] };
    let bounds = split_with_last(file.path(db), text);
    bounds
        .iter()
        .map(|b| Chunk { start: b.start as u32, text: ItemText::new(db, &text[b.start..b.end], b.next) })
        .collect()
}

/// The last cut of each file path, as a starting point for the next cut of
/// that path. Any text with its own cut will do as a starting point
/// (`split_items_edit` gives the cut of the new text, whatever the old one),
/// so sharing it between databases is harmless.
type LastSplits = rustc_hash::FxHashMap<PathBuf, (Arc<str>, Arc<[mcl_syntax::ItemBounds]>)>;
static LAST_SPLIT: std::sync::LazyLock<Mutex<LastSplits>> = std::sync::LazyLock::new(Default::default);

fn split_with_last(path: &Path, text: &Arc<str>) -> Arc<[mcl_syntax::ItemBounds]> {
    let last = LAST_SPLIT.lock().unwrap_or_else(|e| e.into_inner()).get(path).cloned();
    let bounds: Arc<[_]> = match last {
        Some((old, items)) if Arc::ptr_eq(&old, text) => return items,
        Some((old, items)) => mcl_syntax::split_items_edit(&old, &items, text).into(),
        None => mcl_syntax::split_items(text).into(),
    };
    let mut map = LAST_SPLIT.lock().unwrap_or_else(|e| e.into_inner());
    if map.len() >= 256 && !map.contains_key(path) {
        map.clear();
    }
    map.insert(path.to_path_buf(), (text.clone(), bounds.clone()));
    bounds
}

/// The syntax tree of one item (spans relative to the item's start). Kept
/// for the most recently used items only.
#[salsa::tracked(returns(ref), lru = 4096)]
pub fn parse_item<'db>(db: &'db dyn Db, item: ItemText<'db>) -> Parse {
    mcl_syntax::parse_item(item.text(db), *item.next(db))
}

/// Part `index` of a file, by position.
#[salsa::interned(debug)]
pub struct ChunkKey<'db> {
    pub file: SourceFile,
    pub index: u32,
}

/// The text of part `index` of `file`. Queries that reach a definition by
/// its position (file, part) read this: it stays equal (and salsa keeps
/// their results) when another part changes.
#[salsa::tracked]
pub fn chunk_text<'db>(db: &'db dyn Db, key: ChunkKey<'db>) -> Option<ItemText<'db>> {
    file_items(db, *key.file(db)).get(*key.index(db) as usize).map(|c| c.text)
}

/// The item of part `index` of `file`, with spans relative to the part's
/// start (`None` for the prelude or a part that is not a valid item).
pub fn local_item(db: &dyn Db, file: SourceFile, index: u32) -> Option<&Item> {
    let text = (*chunk_text(db, ChunkKey::new(db, file, index)))?;
    parse_item(db, text).file.items.first()
}

/// Where part `index` of `file` starts (0 if there is no such part).
pub fn item_start(db: &dyn Db, file: SourceFile, index: u32) -> u32 {
    file_items(db, file).get(index as usize).map_or(0, |c| c.start)
}

/// A whole file's parse, assembled from its items, with absolute spans.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WholeFile {
    pub parse: Parse,
    /// For each part of [`file_items`], the index of its item in `parse.file.items`.
    pub item_of_part: Vec<Option<u32>>,
}

/// The whole file's tree; see [`parse`]. Kept for the most recently used files only.
#[salsa::tracked(returns(ref), lru = 256)]
pub fn whole_file(db: &dyn Db, file: SourceFile) -> WholeFile {
    let mut out = WholeFile {
        parse: Parse { file: Default::default(), comments: Vec::new(), errors: Vec::new() },
        item_of_part: Vec::new(),
    };
    for c in file_items(db, file) {
        let p = parse_item(db, c.text);
        out.item_of_part.push((!p.file.items.is_empty()).then_some(out.parse.file.items.len() as u32));
        for mut item in p.file.items.iter().cloned() {
            item.shift(c.start);
            out.parse.file.items.push(item);
        }
        for mut x in p.comments.iter().copied() {
            x.shift(c.start);
            out.parse.comments.push(x);
        }
    }
    out.parse.errors = syntax_errors(db, file).clone();
    out
}

/// The part of [`file_items`] that holds item `item` of [`parse`]'s tree.
pub fn part_of_item(db: &dyn Db, file: SourceFile, item: u32) -> Option<u32> {
    whole_file(db, file).item_of_part.iter().position(|x| *x == Some(item)).map(|p| p as u32)
}

/// The syntax tree of a file with absolute spans (an empty tree for a file
/// that cannot be read): the same as `mcl_syntax::parse` of its text.
pub fn parse(db: &dyn Db, file: SourceFile) -> &Parse {
    &whole_file(db, file).parse
}

/// The lexical and syntax errors of a file (absolute spans), in source order.
#[salsa::tracked(returns(ref))]
pub fn syntax_errors(db: &dyn Db, file: SourceFile) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    for c in file_items(db, file) {
        for mut d in parse_item(db, c.text).errors.iter().cloned() {
            d.shift(c.start);
            out.push(d);
        }
    }
    out.sort_by_key(|d| (d.span.start, d.span.end));
    out
}

/// Line/column conversion for a file.
#[salsa::tracked(returns(ref))]
pub fn line_index(db: &dyn Db, file: SourceFile) -> LineIndex {
    LineIndex::new(file.text(db).as_deref().unwrap_or(""))
}

/// One `import` of a file, resolved to its target.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ResolvedImport {
    pub target: SourceFile,
    /// The path as written in the file.
    pub written: String,
    pub path: PathBuf,
    pub path_span: Span,
    pub span: Span,
}

/// Resolves a path written in `file` relative to `file`'s folder.
pub fn resolve_relative(db: &dyn Db, file: SourceFile, written: &str) -> PathBuf {
    let base = file.path(db).parent().map(Path::to_path_buf).unwrap_or_default();
    normalize(&base.join(written))
}

/// The imports of one file, in source order.
#[salsa::tracked(returns(ref))]
pub fn imports(db: &dyn Db, file: SourceFile) -> Vec<ResolvedImport> {
    let mut out = Vec::new();
    for c in file_items(db, file) {
        if let Some(Item::Import(i)) = parse_item(db, c.text).file.items.first() {
            let path = resolve_relative(db, file, &i.path);
            let (mut path_span, mut span) = (i.path_span, i.span);
            path_span.shift(c.start);
            span.shift(c.start);
            out.push(ResolvedImport { target: db.file(&path), written: i.path.clone(), path, path_span, span });
        }
    }
    out
}

/// A program: a root file and every file it imports, transitively.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Program {
    pub root: SourceFile,
    /// The standard library first, then imported files before the files that
    /// import them; the root is last.
    pub files: Vec<SourceFile>,
    /// Import errors located in the root file (missing files, cycles through the root).
    pub diagnostics: Vec<FileDiagnostic>,
}

/// What an import that cannot be read leaves unchecked (see `check_file`).
const UNCHECKED_NAMES: &str = "until it is read, names that it may define are not checked: \
     uses of undefined tasks, actions, events, patterns, missions and planning types are not reported";

/// The program rooted at `root`.
#[salsa::tracked(returns(ref))]
pub fn program(db: &dyn Db, root: SourceFile) -> Program {
    let mut files = Vec::new();
    let mut seen = rustc_hash::FxHashSet::default();
    let std = db.stdlib();
    if root != std {
        files.push(std);
        seen.insert(std);
    }
    post_order(db, root, &mut seen, &mut files);
    let mut diagnostics = Vec::new();
    for imp in imports(db, root) {
        if imp.target.text(db).is_none() {
            diagnostics
                .push(FileDiagnostic { file: root, diag: unreadable_import(db, imp).with_note(UNCHECKED_NAMES) });
            continue;
        }
        if imp.target == root {
            diagnostics.push(FileDiagnostic {
                file: root,
                diag: Diagnostic::error(codes::IMPORT_CYCLE, "a file cannot import itself", imp.path_span),
            });
            continue;
        }
        if let Some(path) = path_to(db, imp.target, root) {
            let mut names = vec![file_name(db, root), file_name(db, imp.target)];
            names.extend(path.iter().skip(1).map(|f| file_name(db, *f)));
            diagnostics.push(FileDiagnostic {
                file: root,
                diag: Diagnostic::error(codes::IMPORT_CYCLE, "import cycle", imp.path_span)
                    .with_label(imp.path_span, "this import leads back to this file")
                    .with_note(format!("cycle: {}", names.join(" -> ")))
                    .with_help("move the shared definitions into a file that both import"),
            });
        }
    }
    Program { root, files, diagnostics }
}

/// E0501 for an import whose file cannot be read, saying why.
fn unreadable_import(db: &dyn Db, imp: &ResolvedImport) -> Diagnostic {
    use mcl_net::input::Reason;
    let shown = &imp.written;
    let error = |message: String| Diagnostic::error(codes::IMPORT_NOT_FOUND, message, imp.path_span);
    match imp.target.unreadable(db) {
        None | Some(Reason::NotFound) => error(format!("cannot find the imported file `{shown}`"))
            .with_label(imp.path_span, "no readable file at this path")
            .with_help("import paths are relative to the folder of the importing file"),
        Some(Reason::Folder) => {
            error(format!("cannot import `{shown}`: it is a folder")).with_help("import one `.mcl` file")
        }
        Some(r @ Reason::NotRegular(_)) => {
            error(format!("cannot import `{shown}`: {r}")).with_help("import a regular `.mcl` file")
        }
        Some(r @ Reason::TooLarge { .. }) => error(format!("cannot import `{shown}`: {r}"))
            .with_help("split the file: a source file holds at most 16 MiB"),
        Some(r @ Reason::NotUtf8) => error(format!("cannot import `{shown}`: {r}")).with_help("save the file as UTF-8"),
        Some(r @ Reason::Io(_)) => error(format!("cannot import `{shown}`: {r}")),
    }
}

fn file_name(db: &dyn Db, f: SourceFile) -> String {
    f.path(db).file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
}

fn post_order(db: &dyn Db, f: SourceFile, seen: &mut rustc_hash::FxHashSet<SourceFile>, out: &mut Vec<SourceFile>) {
    if !seen.insert(f) {
        return;
    }
    for imp in imports(db, f) {
        if imp.target.text(db).is_some() {
            post_order(db, imp.target, seen, out);
        }
    }
    out.push(f);
}

/// A shortest import path `from -> ... -> to` (both included), if any.
fn path_to(db: &dyn Db, from: SourceFile, to: SourceFile) -> Option<Vec<SourceFile>> {
    let mut prev = rustc_hash::FxHashMap::default();
    let mut queue = std::collections::VecDeque::from([from]);
    prev.insert(from, from);
    while let Some(f) = queue.pop_front() {
        if f == to {
            let mut path = vec![f];
            let mut cur = f;
            while cur != from {
                cur = prev[&cur];
                path.push(cur);
            }
            path.reverse();
            return Some(path);
        }
        for imp in imports(db, f) {
            if imp.target.text(db).is_some() && !prev.contains_key(&imp.target) {
                prev.insert(imp.target, f);
                queue.push_back(imp.target);
            }
        }
    }
    None
}

/// A pattern read from a PNML file (`P_X : file.xml;`), as a pattern net.
/// Node names are the PNML names when they are MCL identifiers, else the
/// ids; places named begin/abort/ok/fail without MCL data are on interface 1.
/// Spans are empty: diagnostics point at the import in the MCL file.
#[salsa::tracked(returns(ref))]
pub fn pnml_pattern(db: &dyn Db, file: SourceFile) -> Result<mcl_syntax::ast::PatternNet, String> {
    use mcl_syntax::ast::{ArcDef, Delay as AstDelay, Name, NodeRef, Number, PatternNet, PlaceDef, TransitionDef};
    let Some(text) = file.text(db) else {
        return Err(match file.unreadable(db) {
            Some(r) => format!("cannot read `{}`: {r}", file.path(db).display()),
            None => format!("cannot read `{}`", file.path(db).display()),
        });
    };
    let net = mcl_net::read_pnml(text).map_err(|e| format!("{}: {e}", file.path(db).display()))?;
    let is_ident = |s: &str| {
        let mut c = s.chars();
        c.next().is_some_and(|f| f.is_ascii_alphabetic() || f == '_' || f == '$')
            && c.all(|x| x.is_ascii_alphanumeric() || "_$-/".contains(x))
    };
    let name_of = |id: &str, name: &str| if is_ident(name) { name.to_string() } else { id.to_string() };
    let nm = |text: String| Name { text, span: Span::default() };
    let num = |v: String| Number { text: v, span: Span::default() };
    let mut pn = PatternNet::default();
    for p in net.places() {
        let name = name_of(&p.id, &p.name);
        let iface = if p.interface != 0 {
            p.interface
        } else if ["begin", "abort", "ok", "fail"].contains(&name.as_str()) {
            1
        } else {
            0
        };
        pn.places.push(PlaceDef {
            name: nm(name),
            interface: (iface != 0).then(|| num(iface.to_string())),
            tokens: (p.initial != 0).then(|| num(p.initial.to_string())),
            span: Span::default(),
        });
    }
    for t in net.transitions() {
        let delay = match &t.kind {
            mcl_net::TransitionKind::Timed(mcl_net::Delay::Fixed(s)) => Some(AstDelay::Fixed(num(s.to_string()))),
            mcl_net::TransitionKind::Timed(mcl_net::Delay::Param(p)) => Some(AstDelay::Param(nm(p.clone()))),
            _ => None,
        };
        pn.transitions.push(TransitionDef {
            name: nm(name_of(&t.id, &t.name)),
            interface: None,
            delay,
            span: Span::default(),
        });
    }
    let place_name = |p: mcl_net::PlaceId| net.place(p).map(|x| name_of(&x.id, &x.name)).unwrap_or_default();
    let trans_name = |t: mcl_net::TransitionId| net.transition(t).map(|x| name_of(&x.id, &x.name)).unwrap_or_default();
    for a in net.arcs() {
        let (s, d, w) = match *a {
            mcl_net::Arc::Input { place, transition, weight } => (place_name(place), trans_name(transition), weight),
            mcl_net::Arc::Output { transition, place, weight } => (trans_name(transition), place_name(place), weight),
        };
        pn.arcs.push(ArcDef {
            source: NodeRef { name: nm(s), interface: None },
            target: NodeRef { name: nm(d), interface: None },
            weight: (w != 1).then(|| num(w.to_string())),
            span: Span::default(),
        });
    }
    Ok(pn)
}
