//! Every diagnostic code, with its one-line title and its long explanation
//! (`mcl explain CODE`). Syntax codes are defined in `mcl_syntax::diag::codes`.

pub use mcl_syntax::diag::codes::*;

// Name resolution.
pub const UNDEFINED_TASK: &str = "E0101";
pub const UNDEFINED_ACTION: &str = "E0102";
pub const UNDEFINED_EVENT: &str = "E0103";
pub const UNDEFINED_PATTERN: &str = "E0104";
pub const UNDEFINED_NODE: &str = "E0105";
pub const NOT_A_TRANSITION: &str = "E0106";
pub const DUPLICATE_DEFINITION: &str = "E0110";
pub const DUPLICATE_NODE: &str = "E0111";
pub const DUPLICATE_LABEL: &str = "E0112";
pub const DUPLICATE_PARAMETER: &str = "E0113";
pub const UNNAMED_MISSIONS: &str = "E0114";

// Tasks and patterns.
pub const ARITY: &str = "E0201";
pub const ACTION_PARAM_NOT_IN_HEADER: &str = "E0202";
pub const EVENT_BOUND_TWICE: &str = "E0204";
pub const INTERFACE: &str = "E0205";
pub const DELAY_PARAM_NOT_IN_HEADER: &str = "E0206";
pub const BAD_ARC: &str = "E0207";
pub const TRANSITION_TWO_EVENTS: &str = "E0208";
pub const BAD_NUMBER_IN_PATTERN: &str = "E0209";
pub const PNML_NOT_FOUND: &str = "E0210";
pub const TIMED_AND_EVENT: &str = "E0211";
pub const INTERFACE_MISMATCH: &str = "E0212";
pub const EVENTS_WITHOUT_ACTION: &str = "W0213";

// Missions.
pub const MIXED_PARALLEL: &str = "E0301";
pub const BAD_DELAY_ARGUMENT: &str = "E0302";
pub const MONITOR_SHARES_TASK: &str = "W0303";

// Building blocks.
pub const BLOCK_PROPERTY: &str = "E0601";
pub const PREMATURE_TRANSITION: &str = "W0602";

// Constraints.
pub const UNKNOWN_MISSION: &str = "E0401";
pub const UNKNOWN_LABEL: &str = "E0402";
pub const AMBIGUOUS_LABEL: &str = "E0403";
pub const CONSTRAINT_BOUND: &str = "E0404";
pub const CONSTRAINT_ARITY: &str = "E0405";
pub const CONSTRAINT_ON_OPERATOR: &str = "E0409";
/// Reported by the coordination analysis (`mcl_coord::check`), not by `check_file`.
pub const DEADLOCKING_CONSTRAINTS: &str = "E0406";
/// Reported by the coordination analysis (`mcl_coord::check`), not by `check_file`.
pub const COORDINATION_INCONCLUSIVE: &str = "W0407";
/// Reported by the coordination analysis (`mcl_coord::check`), not by `check_file`.
pub const CONFLICTING_CONSTRAINTS: &str = "E0408";

/// Codes that `check_file` never produces: the coordination analysis of
/// `mcl-coord` reports them (its tests check their explanations).
pub const COORDINATION: &[&str] = &[DEADLOCKING_CONSTRAINTS, COORDINATION_INCONCLUSIVE, CONFLICTING_CONSTRAINTS];
/// `mcl compile --link-report --frame-bytes N`: a coordination message does
/// not fit a frame of the acoustic link (`mcl_coord::link_report`).
pub const FRAME_TOO_SMALL: &str = "E0410";

/// Codes of the link report, never produced by `check_file` nor by the
/// coordination analysis (`mcl-coord/tests/link_report.rs` checks their
/// explanations).
pub const LINK: &[&str] = &[FRAME_TOO_SMALL];

// Planning (`planning { ... }`, `pddl_map { ... }`).
pub const PLAN_UNKNOWN_TYPE: &str = "E0701";
pub const PLAN_UNBOUND: &str = "E0702";
pub const PLAN_UNKNOWN_ATTRIBUTE: &str = "E0703";
pub const PLAN_RELATION_ARITY: &str = "E0704";
pub const PLAN_MISSION: &str = "E0705";
pub const PLAN_DUPLICATE: &str = "E0706";
pub const PLAN_MAP_PARAMETER: &str = "E0707";
pub const PLAN_NEVER_HOLDS: &str = "W0708";

// Imports.
pub const IMPORT_NOT_FOUND: &str = "E0501";
/// The codes of a name that is not defined: not reported while an import
/// of the program cannot be read, since that file may define it.
pub const UNDEFINED_NAMES: &[&str] =
    &[UNDEFINED_TASK, UNDEFINED_ACTION, UNDEFINED_EVENT, UNDEFINED_PATTERN, UNKNOWN_MISSION, PLAN_UNKNOWN_TYPE];
pub const IMPORT_CYCLE: &str = "E0502";

// Warnings.
pub const UNUSED: &str = "W0901";
pub const UNUSED_PARAMETER: &str = "W0902";

/// A code with its title and its long explanation (Markdown).
pub struct CodeInfo {
    pub code: &'static str,
    pub title: &'static str,
    pub explanation: &'static str,
}

macro_rules! registry {
    ($($code:literal => $title:literal),* $(,)?) => {
        /// All codes, sorted.
        pub const ALL: &[CodeInfo] = &[
            $(CodeInfo { code: $code, title: $title, explanation: include_str!(concat!("../explain/", $code, ".md")) }),*
        ];
    };
}

registry! {
    "E0001" => "unexpected character",
    "E0002" => "unterminated string",
    "E0003" => "unterminated block comment",
    "E0004" => "malformed number",
    "E0010" => "unexpected token",
    "E0011" => "unclosed delimiter",
    "E0012" => "unmatched closing delimiter",
    "E0013" => "empty block",
    "E0014" => "action without exactly one command",
    "W0015" => "non-canonical spelling",
    "E0016" => "nesting too deep",
    "E0101" => "undefined task",
    "E0102" => "undefined action",
    "E0103" => "undefined event",
    "E0104" => "undefined pattern",
    "E0105" => "undefined place or transition in an arc",
    "E0106" => "binding to something that is not a transition of the pattern",
    "E0110" => "duplicate definition",
    "E0111" => "duplicate place or transition",
    "E0112" => "duplicate label",
    "E0113" => "duplicate parameter",
    "E0114" => "a mission without a name in a file with several missions",
    "E0201" => "wrong number of arguments",
    "E0202" => "action parameter missing from the task header",
    "E0204" => "event bound to two transitions",
    "E0205" => "pattern without the common interface",
    "E0206" => "delay parameter missing from the task header",
    "E0207" => "arc between two places or two transitions",
    "E0208" => "transition bound to two events",
    "E0209" => "invalid number in a pattern",
    "E0210" => "PNML pattern file not found",
    "E0211" => "transition both timed and bound to an event",
    "E0212" => "interface id of an arc end does not match its declaration",
    "W0213" => "a task that waits for events but sends no action",
    "E0301" => "`and` and `or` mixed in one parallel",
    "E0302" => "a delay argument that is not a positive number of seconds",
    "W0303" => "a task called both in a monitor's watched block and in its condition",
    "E0401" => "constraint names an unknown mission",
    "E0402" => "constraint names an unknown label",
    "E0403" => "ambiguous label in a constraint",
    "E0404" => "misplaced or missing bound",
    "E0405" => "wrong number of calls in a constraint",
    "E0406" => "constraints that deadlock",
    "W0407" => "coordination analysis inconclusive",
    "E0408" => "constraints that conflict by construction",
    "E0409" => "constraint names a planning operator",
    "E0410" => "coordination message larger than the link's frame",
    "E0501" => "imported file not found",
    "E0502" => "import cycle",
    "E0601" => "building block that breaks the block properties",
    "W0602" => "a transition left without an event fires before the event it competes with",
    "E0701" => "unknown planning type",
    "E0702" => "unknown entity or unbound variable in planning",
    "E0703" => "unknown attribute or function in planning",
    "E0704" => "relation or function used with the wrong number of entities",
    "E0705" => "planning operator runs an unknown mission or with the wrong arity",
    "E0706" => "duplicate planning definition",
    "E0707" => "mapping argument that is not a parameter of the mapping",
    "W0708" => "planning relation that never holds, spelt like one that does",
    "W0901" => "unused definition",
    "W0902" => "unused mission parameter",
}

/// Looks a code up (case-insensitive, `e101` and `E0101` both work).
pub fn lookup(code: &str) -> Option<&'static CodeInfo> {
    let c = code.trim().to_ascii_uppercase();
    let normalized = match (c.chars().next(), c.get(1..).and_then(|d| d.parse::<u32>().ok())) {
        (Some(l @ ('E' | 'W')), Some(n)) => format!("{l}{n:04}"),
        _ => c,
    };
    ALL.iter().find(|i| i.code == normalized)
}
