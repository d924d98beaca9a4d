//! Name resolution: the definitions visible in a program.

use crate::db::{Db, SourceFile};
use crate::queries::{parse, program};
use mcl_syntax::ast::*;
use mcl_syntax::Span;
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

/// Where a definition is: its file, the index of its item in that file and
/// its index inside the item (for blocks that hold several definitions).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DefId {
    pub kind: DefKind,
    pub file: SourceFile,
    pub item: u32,
    pub index: u32,
    pub name_span: Span,
    /// Defined by the standard library (programs may override it).
    pub in_stdlib: bool,
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

/// The scope of the program rooted at `root`.
#[salsa::tracked(returns(ref))]
pub fn scope(db: &dyn Db, root: SourceFile) -> Scope {
    let mut scope = Scope::default();
    for &file in &program(db, root).files {
        for_each_def(db, file, |id, name| scope.defs.entry((id.kind, name.to_string())).or_default().push(id));
    }
    scope
}

/// Calls `f` for every top-level definition of one file.
pub fn for_each_def(db: &dyn Db, file: SourceFile, mut f: impl FnMut(DefId, &str)) {
    let ast = &parse(db, file).file;
    let in_stdlib = file == db.stdlib();
    for (i, item) in ast.items.iter().enumerate() {
        let mk = |kind, index: usize, n: &Name| {
            (DefId { kind, file, item: i as u32, index: index as u32, name_span: n.span, in_stdlib }, n.text.clone())
        };
        let mut emit = |(id, name): (DefId, String)| f(id, &name);
        match item {
            Item::Actions(b) => b.actions.iter().enumerate().for_each(|(j, a)| emit(mk(DefKind::Action, j, &a.name))),
            Item::Events(b) => b.events.iter().enumerate().for_each(|(j, e)| emit(mk(DefKind::Event, j, e))),
            Item::Patterns(b) => {
                b.patterns.iter().enumerate().for_each(|(j, p)| emit(mk(DefKind::Pattern, j, &p.name)))
            }
            Item::Tasks(b) => b.tasks.iter().enumerate().for_each(|(j, t)| emit(mk(DefKind::Task, j, &t.name))),
            Item::Mission(m) => {
                if let Some(n) = &m.name {
                    emit(mk(DefKind::Mission, 0, n));
                }
            }
            Item::Import(_) | Item::Constraints(_) => {}
        }
    }
}

/// Typed access to the syntax node of a definition.
pub fn action(db: &dyn Db, id: DefId) -> Option<&ActionDef> {
    match parse(db, id.file).file.items.get(id.item as usize)? {
        Item::Actions(b) => b.actions.get(id.index as usize),
        _ => None,
    }
}

pub fn pattern(db: &dyn Db, id: DefId) -> Option<&Pattern> {
    match parse(db, id.file).file.items.get(id.item as usize)? {
        Item::Patterns(b) => b.patterns.get(id.index as usize),
        _ => None,
    }
}

pub fn task(db: &dyn Db, id: DefId) -> Option<&TaskDef> {
    match parse(db, id.file).file.items.get(id.item as usize)? {
        Item::Tasks(b) => b.tasks.get(id.index as usize),
        _ => None,
    }
}

pub fn mission(db: &dyn Db, id: DefId) -> Option<&Mission> {
    match parse(db, id.file).file.items.get(id.item as usize)? {
        Item::Mission(m) => Some(m),
        _ => None,
    }
}

/// Every mission of a program (named or not), with its file.
pub fn missions(db: &dyn Db, root: SourceFile) -> Vec<(SourceFile, &Mission)> {
    let mut out = Vec::new();
    for &file in &program(db, root).files {
        for item in &parse(db, file).file.items {
            if let Item::Mission(m) = item {
                out.push((file, m));
            }
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
