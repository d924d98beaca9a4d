//! The control-structure tree of a mission as plain data (`GET
//! /api/tree`): the page draws it with the states of its calls, matched by
//! mission and line. The binary builds it from the syntax tree
//! (`src/cmd/monitor.rs`, from mcl-compiler's `structure_tree`); this crate knows nothing of the language.

use serde::Serialize;

/// One mission's tree.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MissionTree {
    /// The mission's name (`mission` for an anonymous one), as on records.
    pub mission: String,
    /// The file it is written in, as records name it (`src`).
    pub file: String,
    /// Its body.
    pub root: Node,
}

/// A control structure or a call.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Node {
    /// `call`, `sequence`, `parallel-or`, `parallel-and`, `try-catch`,
    /// `monitor`, `while`, `if-then`, `if-then-else`, `not`.
    pub kind: String,
    /// A call as written (`Altitude(altitude, timeout, "keep")`, label
    /// included); empty for a structure.
    pub text: String,
    /// Its 1-based line.
    pub line: u32,
    /// Its parts, each named by the role it plays (`try`, `catch`, `branch
    /// 1`, `watched`, `condition 1`, `do 1`, ...; a sequence numbers them).
    pub children: Vec<(String, Node)>,
}
