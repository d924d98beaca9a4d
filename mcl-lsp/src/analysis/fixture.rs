//! Test fixtures: a few in-memory files, one of which may hold the cursor
//! marker `$0`, in a database the way the server holds open documents.

use super::{Analysis, DocInfo, World};
use mcl_compiler::{Database, Db, SourceFile};
use mcl_syntax::LineIndex;
use std::path::PathBuf;
use tower_lsp_server::ls_types::{Location, TextEdit, Uri, WorkspaceEdit};

pub const ROOT: &str = "/fixture";

pub struct Fixture {
    pub db: Database,
    pub world: World,
    pub cursor: Option<(PathBuf, usize)>,
}

impl Fixture {
    /// `files`: `(name, text)`; the `$0` in one text marks the cursor.
    pub fn new(files: &[(&str, &str)]) -> Fixture {
        let mut db = Database::new();
        let mut world = World::default();
        let mut cursor = None;
        for (name, text) in files {
            let path = PathBuf::from(format!("{ROOT}/{name}"));
            let mut text = text.to_string();
            if let Some(i) = text.find("$0") {
                text.replace_range(i..i + 2, "");
                cursor = Some((path.clone(), i));
            }
            db.set_text(&path, text);
            let uri = Uri::from_file_path(&path).unwrap();
            world.by_uri.insert(uri.as_str().to_string(), path.clone());
            world.docs.insert(path.clone(), DocInfo { uri, path, version: 1 });
        }
        Fixture { db, world, cursor }
    }

    pub fn analysis(&self) -> Analysis<'_> {
        Analysis::new(&self.db, &self.world)
    }

    pub fn file(&self, name: &str) -> SourceFile {
        self.db.file(&PathBuf::from(format!("{ROOT}/{name}")))
    }

    pub fn cursor(&self) -> (SourceFile, usize) {
        let (p, o) = self.cursor.clone().expect("a $0 cursor");
        (self.db.file(&p), o)
    }

    fn name_of(uri: &Uri) -> String {
        let s = uri.as_str();
        s.rsplit('/').next().unwrap_or(s).to_string()
    }

    fn text_of_uri(&self, uri: &Uri) -> String {
        let p = self.world.path_of(uri);
        self.db.file(&p).text(&self.db).as_deref().unwrap_or("").to_string()
    }

    /// `file:line:col: text` (1-based), with the text the location covers.
    pub fn show(&self, loc: &Location) -> String {
        let text = self.text_of_uri(&loc.uri);
        let idx = LineIndex::new(&text);
        let s = idx.offset_of_utf16(&text, loc.range.start.line, loc.range.start.character);
        let e = idx.offset_of_utf16(&text, loc.range.end.line, loc.range.end.character);
        format!(
            "{}:{}:{}: {}",
            Self::name_of(&loc.uri),
            loc.range.start.line + 1,
            loc.range.start.character + 1,
            &text[s..e]
        )
    }

    /// The texts of the files a workspace edit touches, after the edit.
    pub fn apply(&self, edit: &WorkspaceEdit) -> Vec<(String, String)> {
        let mut out = Vec::new();
        let mut changes: Vec<_> = edit.changes.iter().flatten().collect();
        changes.sort_by_key(|(u, _)| u.as_str().to_string());
        for (uri, edits) in changes {
            out.push((Self::name_of(uri), apply_edits(&self.text_of_uri(uri), edits)));
        }
        out
    }
}

pub fn apply_edits(text: &str, edits: &[TextEdit]) -> String {
    let idx = LineIndex::new(text);
    let mut spans: Vec<(usize, usize, &str)> = edits
        .iter()
        .map(|e| {
            let s = idx.offset_of_utf16(text, e.range.start.line, e.range.start.character);
            let t = idx.offset_of_utf16(text, e.range.end.line, e.range.end.character);
            (s, t, e.new_text.as_str())
        })
        .collect();
    spans.sort_by_key(|(s, e, _)| std::cmp::Reverse((*s, *e)));
    let mut out = text.to_string();
    for (s, e, t) in spans {
        out.replace_range(s..e, t);
    }
    out
}

/// A small vehicle shared by the tests.
pub const VEHICLE: &str = r#"actions {
    enableGoto = GotoPrimitive( c: enable, v: way-point );
    disableGoto = GotoPrimitive( c: disable );
    enableDepth = DepthPrimitive( c: enable, v: depth, v: mode );
    disableDepth = DepthPrimitive( c: disable );
}

events {
    eventGotoOk; eventGotoFail;
    eventDepthOk; eventDepthFail;
}

tasks {
    // Go to one way-point.
    Goto( way-point ): AchieveOneGoal {
        a: enableGoto -> T0;
        a: disableGoto -> T1, T6, T7;
        e: eventGotoOk -> T2;
        e: eventGotoFail -> T3;
    }
    Depth( depth, mode ): AchieveOneGoal {
        a: enableDepth -> T0;
        a: disableDepth -> T1, T6, T7;
        e: eventDepthOk -> T2;
        e: eventDepthFail -> T3;
    }
    Void(): Instant { }
}
"#;
