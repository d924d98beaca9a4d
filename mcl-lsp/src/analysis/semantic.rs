//! Semantic tokens (full document) and inlay hints (parameter names at calls).

use super::index::{occurrences, pattern_def, written_net, Occ, Role};
use super::Analysis;
use mcl_compiler::scope::{self, DefKind};
use mcl_compiler::SourceFile;
use mcl_syntax::ast::*;
use mcl_syntax::lexer::{lex, Token};
use mcl_syntax::visit::walk_block;
use mcl_syntax::Span;
use std::collections::HashMap;
use tower_lsp_server::ls_types::{
    InlayHint, InlayHintKind, InlayHintLabel, SemanticToken, SemanticTokenModifier, SemanticTokenType,
    SemanticTokensLegend,
};

/// Token types, in legend order.
pub const TYPES: &[SemanticTokenType] = &[
    SemanticTokenType::KEYWORD,     // 0
    SemanticTokenType::COMMENT,     // 1
    SemanticTokenType::STRING,      // 2
    SemanticTokenType::NUMBER,      // 3
    SemanticTokenType::OPERATOR,    // 4
    SemanticTokenType::FUNCTION,    // 5 task
    SemanticTokenType::METHOD,      // 6 action
    SemanticTokenType::EVENT,       // 7 event
    SemanticTokenType::TYPE,        // 8 pattern
    SemanticTokenType::NAMESPACE,   // 9 mission
    SemanticTokenType::VARIABLE,    // 10 place
    SemanticTokenType::PROPERTY,    // 11 transition
    SemanticTokenType::PARAMETER,   // 12 parameter
    SemanticTokenType::DECORATOR,   // 13 label
    SemanticTokenType::CLASS,       // 14 primitive
    SemanticTokenType::ENUM_MEMBER, // 15 command, symbolic value
];

pub const MODIFIERS: &[SemanticTokenModifier] =
    &[SemanticTokenModifier::DECLARATION, SemanticTokenModifier::DEFAULT_LIBRARY];

const DECL: u32 = 1;
const STD: u32 = 2;

pub fn legend() -> SemanticTokensLegend {
    SemanticTokensLegend { token_types: TYPES.to_vec(), token_modifiers: MODIFIERS.to_vec() }
}

fn def_type(k: DefKind) -> u32 {
    match k {
        DefKind::Task => 5,
        DefKind::Action => 6,
        DefKind::Event => 7,
        DefKind::Pattern => 8,
        DefKind::Mission => 9,
    }
}

fn classify(a: &Analysis<'_>, file: SourceFile, occ: &Occ) -> Option<(u32, u32)> {
    Some(match &occ.role {
        Role::Def(k) => (def_type(*k), DECL),
        Role::Ref(k) => {
            let std = scope::scope(a.db, file).first(*k, &occ.name).is_some_and(|d| d.in_stdlib);
            (def_type(*k), if std { STD } else { 0 })
        }
        Role::PlaceDef { .. } => (10, DECL),
        Role::TransitionDef { .. } => (11, DECL),
        Role::ArcEnd { pattern } => {
            let net = written_net(a.db, pattern_def(a.db, file, *pattern)?)?;
            if net.places.iter().any(|p| p.name.text == occ.name) {
                (10, 0)
            } else {
                (11, 0)
            }
        }
        Role::BindingTransition { .. } => (11, 0),
        Role::LabelDef { .. } => (13, DECL),
        Role::LabelRef { .. } => (13, 0),
        Role::TaskParam { .. } | Role::MissionParam { .. } => (12, DECL),
        Role::ParamUse { .. } | Role::ActionParam | Role::DelayParam => (12, 0),
        Role::Symbolic | Role::Command => (15, 0),
        Role::Primitive => (14, 0),
        Role::Structure(_) | Role::ConstraintKeyword(_) => (0, 0),
    })
}

const CONTEXTUAL: &[&str] = &["mutex", "order", "sync", "_mutex_", "_order_", "_sync_", "at"];

/// The tokens of a file as `(span, type, modifiers)`, in source order.
pub fn classified(a: &Analysis<'_>, file: SourceFile) -> Vec<(Span, u32, u32)> {
    let text = a.text(file);
    let occs = occurrences(a.db, file);
    let by_start: HashMap<u32, &Occ> = occs.iter().map(|o| (o.span.start, o)).collect();
    let lexed = lex(text);
    let mut out = Vec::with_capacity(lexed.tokens.len() / 2);
    let toks = &lexed.tokens;
    for (i, (tok, span)) in toks.iter().enumerate() {
        let class = match tok {
            Token::Kw(_) => Some((0, 0)),
            Token::Str(_) => Some((2, 0)),
            Token::Num(_) => Some((3, 0)),
            Token::Arrow | Token::Cmp(_) => Some((4, 0)),
            Token::Ident(word) => match by_start.get(&span.start) {
                Some(o) => classify(a, file, o),
                None => {
                    let before_colon = matches!(toks.get(i + 1), Some((Token::Colon, _)));
                    if (before_colon && matches!(*word, "a" | "e" | "c" | "v")) || CONTEXTUAL.contains(word) {
                        Some((0, 0))
                    } else {
                        None
                    }
                }
            },
            _ => None,
        };
        if let Some((t, m)) = class {
            out.push((*span, t, m));
        }
    }
    for c in &mcl_compiler::queries::parse(a.db, file).comments {
        out.push((c.span, 1, 0));
    }
    out.sort_by_key(|(s, _, _)| s.start);
    out
}

/// The tokens, encoded as the protocol wants them (relative positions,
/// UTF-16 lengths, one token per line for multi-line comments).
pub fn semantic_tokens(a: &Analysis<'_>, file: SourceFile) -> Vec<SemanticToken> {
    let text = a.text(file);
    let idx = a.line_index(file);
    let mut out = Vec::new();
    let (mut prev_line, mut prev_col) = (0u32, 0u32);
    for (span, ty, mods) in classified(a, file) {
        // Split multi-line tokens (block comments) into one token per line.
        let mut start = span.start as usize;
        let end = (span.end as usize).min(text.len());
        while start < end {
            let line_end = text[start..end].find(['\n', '\r']).map_or(end, |i| start + i);
            let (line, col) = idx.utf16_position(text, start);
            let len: u32 = text.get(start..line_end).map_or(0, |s| s.chars().map(|c| c.len_utf16() as u32).sum());
            if len > 0 {
                let delta_line = line - prev_line;
                let delta_start = if delta_line == 0 { col - prev_col } else { col };
                out.push(SemanticToken {
                    delta_line,
                    delta_start,
                    length: len,
                    token_type: ty,
                    token_modifiers_bitset: mods,
                });
                prev_line = line;
                prev_col = col;
            }
            start = line_end + if text[line_end..].starts_with("\r\n") { 2 } else { 1 };
        }
    }
    out
}

/// Parameter names before the arguments of calls inside `range`.
pub fn inlay_hints(a: &Analysis<'_>, file: SourceFile, range: Span) -> Vec<InlayHint> {
    let ast = a.ast(file);
    let sc = scope::scope(a.db, file);
    let mut out = Vec::new();
    for item in &ast.items {
        let Item::Mission(m) = item else { continue };
        if m.span.end < range.start || m.span.start > range.end {
            continue;
        }
        walk_block(&m.body, &mut |s| {
            let StmtKind::Call(c) = &s.kind else { return };
            if c.span.end < range.start || c.span.start > range.end {
                return;
            }
            let Some(t) = sc.first(DefKind::Task, &c.name.text).and_then(|id| scope::task(a.db, id)) else { return };
            for (arg, p) in c.args.iter().zip(&t.params) {
                if matches!(&arg.kind, ValueKind::Ident(n) if n.text == p.text) || matches!(arg.kind, ValueKind::Error)
                {
                    continue;
                }
                out.push(InlayHint {
                    position: a.position(file, arg.span.start as usize),
                    label: InlayHintLabel::String(format!("{}:", p.text)),
                    kind: Some(InlayHintKind::PARAMETER),
                    text_edits: None,
                    tooltip: None,
                    padding_left: None,
                    padding_right: Some(true),
                    data: None,
                });
            }
        });
    }
    out
}
