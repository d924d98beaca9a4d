//! The ROS 2 bridge file in the editor (docs/ros2.md, *In the editor*): when
//! the client names a bridge file (`initializationOptions.ros2Bridge`, or
//! the setting `mcl.ros2Bridge`), its errors against the vehicle of the open
//! MCL documents (a primitive, command, event or parameter the vehicle
//! lacks, a field the message type lacks, ...) are published on the bridge
//! file's URI, each at its line and column, by `mcl_ros2::bridge` (the
//! sans-IO part of mcl-ros2, without DDS).

use super::Analysis;
use mcl_compiler::Db;
use mcl_ros2::bridge::{load_text, vehicle_of, BridgeError};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use tower_lsp_server::ls_types::{Diagnostic, DiagnosticSeverity, NumberOrString, Position, Range};

/// The diagnostics code of every bridge error.
pub const CODE: &str = "ros2";

/// The bridge file named by the client's options (`{"ros2Bridge": PATH}` or
/// `{"mcl": {"ros2Bridge": PATH}}`), relative to `root`.
pub fn configured(options: &serde_json::Value, root: Option<&Path>) -> Option<PathBuf> {
    let p = options.get("ros2Bridge").or_else(|| options.get("mcl")?.get("ros2Bridge"))?.as_str()?;
    if p.is_empty() {
        return None;
    }
    let p = Path::new(p);
    let full = match root {
        Some(r) if p.is_relative() => r.join(p),
        _ => p.to_path_buf(),
    };
    Some(mcl_compiler::db::normalize(&full))
}

/// Whether a document is a bridge file, never MCL (not diagnosed as MCL).
pub fn is_bridge_like(path: &Path) -> bool {
    path.extension().is_some_and(|x| x == "toml")
}

/// The errors of `bridge` (the editor's text when it is open, else the
/// file's) against the vehicle of the open MCL documents, by the file they
/// are in (the bridge file, or an interface definition it loads). Nothing
/// while no MCL document is open: there is no vehicle to check against.
pub fn diagnostics(a: &Analysis<'_>, bridge: &Path) -> BTreeMap<PathBuf, Vec<Diagnostic>> {
    let roots: Vec<_> = a
        .world
        .docs
        .keys()
        .filter(|p| p.extension().is_some_and(|x| x == "mcl") && Some(*p) != a.world.std_copy.as_ref())
        .map(|p| a.db.file(p))
        .collect();
    let mut out = BTreeMap::new();
    if roots.is_empty() {
        return out;
    }
    let open: Option<String> = match a.world.docs.get(bridge) {
        Some(_) => a.db.file(bridge).text(a.db).as_deref().map(|t| t.to_string()),
        None => None,
    };
    // Not open: the bounded reader (a regular file only, never a FIFO).
    let text = match open {
        Some(t) => Ok(t),
        None => mcl_net::input::read_source(bridge).map_err(|e| e.to_string()),
    };
    let text = match text {
        Ok(t) => t,
        Err(e) => {
            let d = BridgeError {
                file: bridge.to_path_buf(),
                line: 1,
                column: 1,
                message: format!("cannot read the ROS 2 bridge file: {e}"),
            };
            out.insert(bridge.to_path_buf(), vec![to_lsp(&d, None)]);
            return out;
        }
    };
    out.insert(bridge.to_path_buf(), Vec::new());
    let vehicle = vehicle_of(a.db, &roots);
    for e in load_text(bridge, &text, &vehicle).err().unwrap_or_default() {
        let file = mcl_compiler::db::normalize(&e.file);
        let same = file == bridge;
        out.entry(file).or_default().push(to_lsp(&e, same.then_some(&text[..])));
    }
    out
}

/// A bridge error as an LSP diagnostic: from its column to the end of its
/// line (of `text` when known; columns count characters, which are UTF-16
/// units in the ASCII of TOML keys and values).
fn to_lsp(e: &BridgeError, text: Option<&str>) -> Diagnostic {
    let line = e.line.saturating_sub(1) as u32;
    let start = e.column.saturating_sub(1) as u32;
    let end = text
        .and_then(|t| t.lines().nth(line as usize))
        .map(|l| l.encode_utf16().count() as u32)
        .filter(|&n| n > start)
        .unwrap_or(start + 1);
    Diagnostic {
        range: Range { start: Position { line, character: start }, end: Position { line, character: end } },
        severity: Some(DiagnosticSeverity::ERROR),
        code: Some(NumberOrString::String(CODE.to_string())),
        source: Some(super::diagnostics::SOURCE.to_string()),
        message: e.message.clone(),
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn the_bridge_is_named_by_either_option_relative_to_the_root() {
        let root = Path::new("/ws");
        assert_eq!(configured(&json!({"ros2Bridge": "b.toml"}), Some(root)), Some(PathBuf::from("/ws/b.toml")));
        assert_eq!(configured(&json!({"mcl": {"ros2Bridge": "/x/b.toml"}}), Some(root)), Some("/x/b.toml".into()));
        assert_eq!(configured(&json!({"ros2Bridge": ""}), Some(root)), None);
        assert_eq!(configured(&json!({"ros2Bridge": 3}), Some(root)), None);
        assert_eq!(configured(&json!(null), Some(root)), None);
    }

    #[test]
    fn an_error_spans_the_rest_of_its_line() {
        let e = BridgeError { file: "b.toml".into(), line: 2, column: 3, message: "m".into() };
        let d = to_lsp(&e, Some("a\nx = 123\n"));
        assert_eq!((d.range.start, d.range.end), (Position::new(1, 2), Position::new(1, 7)));
        let d = to_lsp(&e, None);
        assert_eq!(d.range.end, Position::new(1, 3));
    }
}
