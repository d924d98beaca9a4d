//! The error-tolerant parser.
//!
//! Parsing runs in two passes. First the token stream is *balanced*: every
//! `{`, `(` and `[` gets its closing delimiter, inserting the missing ones
//! (one error at the unclosed opener) and dropping stray closers (one error
//! each), the way rustc builds token trees. A top-level keyword (`mission`,
//! `tasks`, ...) found inside an open block closes it, so a forgotten `}` is
//! reported once instead of swallowing the rest of the file. Then a chumsky
//! grammar runs on the balanced stream and recovers at statement, definition
//! and item boundaries.
//!
//! One file per job: `items.rs` cuts a file into its top-level items,
//! `balance.rs` balances delimiters and bounds the nesting, `grammar.rs` is
//! the chumsky grammar of the language (its errors as diagnostics in
//! `errors.rs`, the planning blocks in `planning.rs`), and `spelling.rs`
//! warns about accepted non-canonical spellings.

mod balance;
mod errors;
mod grammar;
mod items;
mod planning;
mod spelling;

pub use balance::MAX_NESTING;
pub use items::{split_items, split_items_edit, ItemBounds};

use crate::ast::SourceFile;
use crate::diag::{codes, Diagnostic};
use crate::lexer::{Comment, Kw, Token};
use chumsky::span::SimpleSpan;

/// The result of parsing one file: always a tree, plus comments and errors.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Parse {
    pub file: SourceFile,
    pub comments: Vec<Comment>,
    /// Lexical and syntax errors (and warnings for non-canonical spellings), in source order.
    pub errors: Vec<Diagnostic>,
}

/// Parses a whole file. Never panics and never gives up.
pub fn parse(src: &str) -> Parse {
    parse_with(src, None, true)
}

/// Parses one part of a file as cut by [`split_items`] (`src` is the part's
/// text, `next` its `next`), with spans relative to the part's start.
pub fn parse_item(src: &str, next: Option<(Kw, u32)>) -> Parse {
    parse_with(src, next, true)
}

/// `quick`: try the quick pass first (always, but in a test that compares
/// it with the rich pass alone).
fn parse_with(src: &str, next: Option<(Kw, u32)>, quick: bool) -> Parse {
    let lexed = crate::lexer::lex_before(src, next.is_some());
    let mut errors = lexed.errors;
    let why = if next.is_some() { "before the next item" } else { "at the end of the file" };
    let mut deep_regions = Vec::new();
    let tokens = balance::balance(lexed.tokens, src, &mut errors, why, &mut deep_regions);
    let len = src.len();
    let mut input: Vec<(Token<'_>, SimpleSpan)> =
        tokens.iter().map(|(t, s)| (*t, SimpleSpan::from(s.range()))).collect();
    // The next item's keyword follows, as it does in the whole file, so that
    // an error at the item's end says what comes next.
    let mut end = len;
    if let Some((k, klen)) = next {
        end = len + klen as usize;
        input.push((Token::Kw(k), SimpleSpan::from(len..end)));
    }
    let eoi = SimpleSpan::from(end..end);
    let item_end = if next.is_some() { len } else { usize::MAX };
    let (file, parse_errors) = grammar::run(&input, eoi, next.is_some(), item_end, quick);
    errors.extend(parse_errors);
    // What a too-deep construct left (an opener and its closer, a keyword)
    // does not parse: those errors are follow-ups of the nesting error.
    if !deep_regions.is_empty() {
        errors.retain(|d| {
            d.code == codes::NESTING_TOO_DEEP
                || !deep_regions.iter().any(|r| r.start <= d.span.start && d.span.start <= r.end)
        });
    }
    let file = file.unwrap_or_default();
    spelling::lint_spellings(&file, &mut errors);
    errors.sort_by_key(|d| (d.span.start, d.span.end));
    errors.dedup();
    Parse { file, comments: lexed.comments, errors }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quick pass gives the tree of the rich pass (and no error where
    /// the rich pass finds none): on the examples, the malformed corpus and
    /// generated programs, whole files and item by item.
    #[test]
    fn the_quick_pass_gives_the_rich_pass_tree() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut texts: Vec<String> = (0..4).map(|seed| crate::gen::program(400, seed)).collect();
        for dir in [root.join("../examples"), root.join("../examples/planning"), root.join("tests/bad")] {
            let mut paths: Vec<_> = std::fs::read_dir(&dir).expect("corpus").flatten().map(|e| e.path()).collect();
            paths.sort();
            for p in paths.iter().filter(|p| p.extension().is_some_and(|e| e == "mcl")) {
                texts.push(std::fs::read_to_string(p).expect("readable"));
            }
        }
        assert!(texts.len() > 20);
        let mut without_errors = 0;
        for text in &texts {
            let rich = parse_with(text, None, false);
            assert_eq!(parse_with(text, None, true), rich);
            without_errors += usize::from(rich.errors.is_empty());
            for b in split_items(text) {
                let part = &text[b.start..b.end];
                assert_eq!(parse_with(part, b.next, true), parse_with(part, b.next, false));
            }
        }
        assert!(without_errors >= 8, "{without_errors} texts without errors");
    }
}
