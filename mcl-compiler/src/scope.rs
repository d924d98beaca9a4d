//! Name resolution: the definitions visible in a program.

use crate::db::{Db, SourceFile};
use crate::queries::{chunk_text, file_items, item_start, local_item, parse_item, program, whole_file, ChunkKey};
use mcl_syntax::ast::SourceFile as SourceFileAst;
use mcl_syntax::ast::*;
use mcl_syntax::{Shift, Span};
use rustc_hash::FxHashMap;

/// What a name defines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum DefKind {
    Action,
    Event,
    Pattern,
    Task,
    Mission,
}

impl DefKind {
    pub fn as_str(self) -> &'static str {
        match self {
            DefKind::Action => "action",
            DefKind::Event => "event",
            DefKind::Pattern => "pattern",
            DefKind::Task => "task",
            DefKind::Mission => "mission",
        }
    }
}

/// Where a definition is: its file, the index of its part in that file
/// (`queries::file_items`: 0 is the prelude, then one part per item) and its
/// index inside the item (for blocks that hold several definitions).
///
/// `name_span` is absolute in [`scope`], and relative to the item's start in
/// [`local_scope`] (`local` tells which); the accessors ([`task`], ...) give
/// the node with spans of the same kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DefId {
    pub kind: DefKind,
    pub file: SourceFile,
    pub item: u32,
    pub index: u32,
    pub name_span: Span,
    /// Defined by the standard library (programs may override it).
    pub in_stdlib: bool,
    /// `name_span` and the accessors' nodes are relative to the item's start.
    pub local: bool,
}

/// Every top-level definition of a program, by kind and name, in program
/// order (imported files first), duplicates included.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Scope {
    pub defs: FxHashMap<(DefKind, String), Vec<DefId>>,
}

impl Scope {
    /// The definitions of `name` as a `kind` (more than one is a duplicate).
    pub fn get(&self, kind: DefKind, name: &str) -> &[DefId] {
        self.defs.get(&(kind, name.to_string())).map_or(&[], Vec::as_slice)
    }
    /// The definition `name` refers to: the first one of the program, or the
    /// standard library's when the program defines none.
    pub fn first(&self, kind: DefKind, name: &str) -> Option<DefId> {
        let defs = self.get(kind, name);
        defs.iter().find(|d| !d.in_stdlib).or(defs.first()).copied()
    }
    /// All names defined as `kind`.
    pub fn names(&self, kind: DefKind) -> impl Iterator<Item = &str> {
        self.defs.keys().filter(move |(k, _)| *k == kind).map(|(_, n)| n.as_str())
    }
}

/// The scope of the program rooted at `root`, with absolute spans (for
/// navigation and compilation).
#[salsa::tracked(returns(ref))]
pub fn scope(db: &dyn Db, root: SourceFile) -> Scope {
    let mut out = local_scope(db, root).clone();
    for ids in out.defs.values_mut() {
        for id in ids {
            id.name_span.shift(item_start(db, id.file, id.item));
            id.local = false;
        }
    }
    out
}

/// The scope of the program rooted at `root`, with spans relative to their
/// items: it stays equal while no definition changes (an edit inside a
/// mission body, text moved), so the checks that read it are reused.
#[salsa::tracked(returns(ref))]
pub fn local_scope(db: &dyn Db, root: SourceFile) -> Scope {
    let mut scope = Scope::default();
    for &file in &program(db, root).files {
        for (id, name) in file_defs(db, file) {
            scope.defs.entry((id.kind, name.clone())).or_default().push(*id);
        }
    }
    scope
}

/// The definitions of one file, with spans relative to their items.
#[salsa::tracked(returns(ref))]
pub fn file_defs(db: &dyn Db, file: SourceFile) -> Vec<(DefId, String)> {
    let in_stdlib = file == db.stdlib();
    let mut out = Vec::new();
    for (i, c) in file_items(db, file).iter().enumerate() {
        let Some(item) = parse_item(db, c.text).file.items.first() else { continue };
        let mut emit = |kind, index: usize, n: &Name| {
            out.push((
                DefId { kind, file, item: i as u32, index: index as u32, name_span: n.span, in_stdlib, local: true },
                n.text.clone(),
            ))
        };
        match item {
            Item::Actions(b) => b.actions.iter().enumerate().for_each(|(j, a)| emit(DefKind::Action, j, &a.name)),
            Item::Events(b) => b.events.iter().enumerate().for_each(|(j, e)| emit(DefKind::Event, j, e)),
            Item::Patterns(b) => b.patterns.iter().enumerate().for_each(|(j, p)| emit(DefKind::Pattern, j, &p.name)),
            Item::Tasks(b) => b.tasks.iter().enumerate().for_each(|(j, t)| emit(DefKind::Task, j, &t.name)),
            Item::Mission(m) => {
                if let Some(n) = &m.name {
                    emit(DefKind::Mission, 0, n);
                }
            }
            Item::Import(_) | Item::Constraints(_) | Item::Planning(_) | Item::PddlMap(_) => {}
        }
    }
    out
}

/// Calls `f` for every top-level definition of one file (absolute spans).
pub fn for_each_def(db: &dyn Db, file: SourceFile, mut f: impl FnMut(DefId, &str)) {
    for (id, name) in file_defs(db, file) {
        let mut id = *id;
        id.name_span.shift(item_start(db, file, id.item));
        id.local = false;
        f(id, name);
    }
}

/// The item a definition is in, with spans of the definition's kind.
fn item_of(db: &dyn Db, id: DefId) -> Option<&Item> {
    if id.local {
        return local_item(db, id.file, id.item);
    }
    let w = whole_file(db, id.file);
    let i = (*w.item_of_part.get(id.item as usize)?)?;
    w.parse.file.items.get(i as usize)
}

/// The names of the missions of one file, in source order (one per
/// `Item::Mission`): a named mission's (or operator's) name; an anonymous
/// mission is `mission` when it is the file's only one, otherwise
/// `mission1`, `mission2`, ... by its rank among the anonymous missions
/// (skipping a number that a named mission already uses; only a file with
/// E0114, which the editor still names, has several). Every tool that
/// names a mission uses this one function: the checker's messages, the
/// compiled nets and their PNML file names, `mcl run --mission` and traces.
pub fn mission_names(file: &SourceFileAst) -> Vec<String> {
    let missions: Vec<&Mission> = file
        .items
        .iter()
        .filter_map(|i| match i {
            Item::Mission(m) => Some(m),
            _ => None,
        })
        .collect();
    let anonymous = missions.iter().filter(|m| m.name.is_none()).count();
    let taken = |s: &str| missions.iter().any(|m| m.name.as_ref().is_some_and(|n| n.text == s));
    let mut rank = 0;
    missions
        .iter()
        .map(|m| match &m.name {
            Some(n) => n.text.clone(),
            None if anonymous == 1 => "mission".to_string(),
            None => loop {
                rank += 1;
                let name = format!("mission{rank}");
                if !taken(&name) {
                    break name;
                }
            },
        })
        .collect()
}

/// Whether a definition has a syntax error inside `span` (the span of its
/// node, of the same kind as `id`'s spans). The checks of a broken
/// definition, and of its uses, would only repeat that error in other words:
/// they are skipped (the definition still defines its name).
pub fn is_broken(db: &dyn Db, id: DefId, span: Span) -> bool {
    // Through `chunk_text`, not `file_items`: a check of another item that
    // asks must not depend on where the items are (it would rerun on every edit).
    let Some(text) = *chunk_text(db, ChunkKey::new(db, id.file, id.item)) else { return false };
    let off = if id.local { 0 } else { item_start(db, id.file, id.item) };
    parse_item(db, text)
        .errors
        .iter()
        .any(|e| e.is_error() && e.span.start + off >= span.start && e.span.start + off <= span.end)
}

/// Typed access to the syntax node of a definition.
pub fn action(db: &dyn Db, id: DefId) -> Option<&ActionDef> {
    match item_of(db, id)? {
        Item::Actions(b) => b.actions.get(id.index as usize),
        _ => None,
    }
}

pub fn pattern(db: &dyn Db, id: DefId) -> Option<&Pattern> {
    match item_of(db, id)? {
        Item::Patterns(b) => b.patterns.get(id.index as usize),
        _ => None,
    }
}

pub fn task(db: &dyn Db, id: DefId) -> Option<&TaskDef> {
    match item_of(db, id)? {
        Item::Tasks(b) => b.tasks.get(id.index as usize),
        _ => None,
    }
}

pub fn mission(db: &dyn Db, id: DefId) -> Option<&Mission> {
    match item_of(db, id)? {
        Item::Mission(m) => Some(m),
        _ => None,
    }
}

/// Every mission of a program (named or not), with its file; spans are
/// relative to each mission's start (the checks compare names and labels).
pub fn missions(db: &dyn Db, root: SourceFile) -> Vec<(SourceFile, &Mission)> {
    let mut out = Vec::new();
    for &file in &program(db, root).files {
        for &part in mission_parts(db, file) {
            if let Some(Item::Mission(m)) = local_item(db, file, part) {
                out.push((file, m));
            }
        }
    }
    out
}

/// The parts of a file that are missions (equal across edits inside them).
#[salsa::tracked(returns(ref))]
pub fn mission_parts(db: &dyn Db, file: SourceFile) -> Vec<u32> {
    let items = file_items(db, file).iter().enumerate();
    items
        .filter(|(_, c)| matches!(parse_item(db, c.text).file.items.first(), Some(Item::Mission(_))))
        .map(|(i, _)| i as u32)
        .collect()
}

/// The missions without a name of a file that has several missions (E0114):
/// each one's part and the span of its keyword, relative to the part. Empty
/// when the file has at most one mission. A mission whose header has a
/// syntax error is left out: its name may be what the error is about.
/// Equal across edits inside mission bodies.
#[salsa::tracked(returns(ref))]
pub fn unnamed_missions(db: &dyn Db, file: SourceFile) -> Vec<(u32, Span)> {
    let parts = mission_parts(db, file);
    if parts.len() < 2 {
        return Vec::new();
    }
    let mut out = Vec::new();
    for &part in parts {
        let Some(text) = *chunk_text(db, ChunkKey::new(db, file, part)) else { continue };
        let parsed = parse_item(db, text);
        let Some(Item::Mission(m)) = parsed.file.items.first() else { continue };
        let (start, end) = (m.keyword_span.start, m.body.span.start);
        let broken = parsed.errors.iter().any(|e| e.is_error() && e.span.start >= start && e.span.start <= end);
        if m.name.is_none() && !broken {
            out.push((part, m.keyword_span));
        }
    }
    out
}

/// The net of a pattern: written in MCL, or read from its PNML file. `Err`
/// holds why the PNML file could not be used.
pub fn pattern_net(db: &dyn Db, id: DefId) -> Option<Result<&PatternNet, &String>> {
    let p = pattern(db, id)?;
    Some(match &p.body {
        PatternBody::Net(n) => Ok(n),
        PatternBody::File { path, .. } => {
            let full = crate::queries::resolve_relative(db, id.file, path);
            crate::queries::pnml_pattern(db, db.file(&full)).as_ref()
        }
    })
}
