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

use crate::ast::*;
use crate::diag::{codes, Diagnostic};
use crate::lexer::{unescape, Comment, Kw, Token};
use crate::span::Span;
use chumsky::cache::{Cache, Cached};
use chumsky::error::{EmptyErr, RichPattern, RichReason};
use chumsky::input::{Input, MappedInput, ValueInput};
use chumsky::inspector::SimpleState;
use chumsky::label::LabelError;
use chumsky::prelude::*;

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

/// The bounds of one top-level item of a file, as found by [`split_items`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ItemBounds {
    /// Byte offset of the item's first token (0 for the prelude).
    pub start: usize,
    /// Byte offset of the next item's first token, or the file's length.
    pub end: usize,
    /// The keyword that starts the next item and its length as written
    /// (`None` for the last item): [`parse_item`] needs it to report what
    /// follows the item exactly as [`parse`] does.
    pub next: Option<(Kw, u32)>,
}

/// Splits a file into its top-level items: the prelude (whatever comes
/// before the first item: trivia, or text that is no item), then one part per
/// item, from its keyword to the next item's keyword. Item boundaries are the
/// ones of [`parse`]: a top-level keyword at depth 0, or one that closes the
/// open blocks (delimiter balancing). Parsing every part with [`parse_item`]
/// and shifting the results by `start` gives what [`parse`] gives (tested on
/// the corpus and on random and mutated programs).
pub fn split_items(src: &str) -> Vec<ItemBounds> {
    let mut out = vec![ItemBounds { start: 0, end: src.len(), next: None }];
    split_from(src, 0, &mut out, |_, _| false);
    out
}

/// [`split_items`] of `new`, given `old_items = split_items(old)`: only the
/// text around the edit is lexed again. The edit is found by comparing the
/// texts (their common prefix and suffix); the split restarts at an item
/// that starts before the edit, where lexing and splitting are known to be
/// in the same state as in the whole file, and stops at the first item after
/// the edit that the old split also has (the rest is the old split, moved).
/// Gives exactly `split_items(new)` (tested on random edits); with
/// `old_items` that are not the split of `old`, it splits `new` afresh.
pub fn split_items_edit(old: &str, old_items: &[ItemBounds], new: &str) -> Vec<ItemBounds> {
    let consistent = old_items.first().is_some_and(|b| b.start == 0)
        && old_items.last().is_some_and(|b| b.end == old.len())
        && old_items.windows(2).all(|w| w[0].end == w[1].start && w[0].start < w[1].start)
        && old_items.iter().all(|b| old.is_char_boundary(b.start));
    if !consistent {
        return split_items(new);
    }
    if old == new {
        return old_items.to_vec();
    }
    let (ob, nb) = (old.as_bytes(), new.as_bytes());
    let min = ob.len().min(nb.len());
    let prefix = common_prefix(ob, nb);
    let suffix = common_suffix(&ob[prefix..], &nb[prefix..]).min(min - prefix);
    // A restart at item `j` (start `r`) is sound when everything the lexer
    // reads to produce the tokens before `r`, the keyword at `r` and the
    // token after it (which decides whether a keyword inside open blocks
    // starts an item) lies before the edit. Those reads end at the end of
    // the line of that second token: strings and `#` stop at a newline,
    // closed block comments at their end, other tokens look one byte ahead.
    let last = old_items.partition_point(|b| b.start < prefix).saturating_sub(1);
    let mut restart = 0;
    for j in (1..=last).rev().take(4) {
        let r = old_items[j].start;
        let mut lx = crate::lexer::Lexer::new(&new[r..]);
        while lx.out.tokens.len() < 2 && lx.step() {}
        let Some(&(_, second)) = lx.out.tokens.get(1) else { continue };
        let at = r + second.start as usize;
        if new[at..].find('\n').is_some_and(|nl| at + nl < prefix) {
            restart = j;
            break;
        }
    }
    let mut out = if restart == 0 {
        vec![ItemBounds { start: 0, end: new.len(), next: None }]
    } else {
        old_items[..restart].to_vec()
    };
    let delta = new.len() as isize - old.len() as isize;
    let same_from = new.len() - suffix;
    split_from(new, old_items[restart].start * usize::from(restart > 0), &mut out, |q, out| {
        // From an item start in the common suffix that the old split also
        // has, both splits see the same text in the same state.
        if q < same_from {
            return false;
        }
        let Ok(m) = old_items.binary_search_by_key(&((q as isize - delta) as usize), |b| b.start) else {
            return false;
        };
        out.pop();
        out.extend(old_items[m..].iter().map(|b| ItemBounds {
            start: (b.start as isize + delta) as usize,
            end: (b.end as isize + delta) as usize,
            next: b.next,
        }));
        true
    });
    out
}

fn common_prefix(a: &[u8], b: &[u8]) -> usize {
    const W: usize = 64;
    let n = a.len().min(b.len());
    let mut i = 0;
    while i + W <= n && a[i..i + W] == b[i..i + W] {
        i += W;
    }
    i + a[i..n].iter().zip(&b[i..n]).take_while(|(x, y)| x == y).count()
}

fn common_suffix(a: &[u8], b: &[u8]) -> usize {
    const W: usize = 64;
    let n = a.len().min(b.len());
    let (a, b) = (&a[a.len() - n..], &b[b.len() - n..]);
    let mut k = 0;
    while k + W <= n && a[n - k - W..n - k] == b[n - k - W..n - k] {
        k += W;
    }
    k + a[..n - k].iter().rev().zip(b[..n - k].iter().rev()).take_while(|(x, y)| x == y).count()
}

/// The item split of `src` from `from` on: `from` is 0 (the prelude) or the
/// first byte of an item's keyword, where the lexer is between tokens and no
/// block is open. `out`'s last part is the one that holds `from`. Each new
/// part is pushed, then `stop(start, out)` may end the split (having
/// completed `out` itself) by returning `true`.
fn split_from(
    src: &str,
    from: usize,
    out: &mut Vec<ItemBounds>,
    mut stop: impl FnMut(usize, &mut Vec<ItemBounds>) -> bool,
) {
    let mut lx = crate::lexer::Lexer::new(&src[from..]);
    let mut stack: Vec<Token<'_>> = Vec::new();
    let mut i = 0;
    loop {
        // The token and the one after it.
        while lx.out.tokens.len() < i + 2 && lx.step() {}
        let tokens = &lx.out.tokens;
        let Some(&(tok, span)) = tokens.get(i) else { break };
        if closer_of(tok).is_some() {
            stack.push(tok);
        } else if is_closer(tok) {
            if let Some(pos) = stack.iter().rposition(|o| closer_of(*o) == Some(tok)) {
                stack.truncate(pos);
            }
        } else if let Token::Kw(k) = tok {
            let boundary =
                if stack.is_empty() { k.starts_item() } else { starts_item_here(tok, tokens.get(i + 1).map(|t| t.0)) };
            if boundary {
                stack.clear();
                let at = from + span.start as usize;
                let last = out.last_mut().expect("the part that holds `from`");
                last.end = at;
                last.next = Some((k, span.len() as u32));
                out.push(ItemBounds { start: at, end: src.len(), next: None });
                if stop(at, out) {
                    return;
                }
            }
        }
        i += 1;
    }
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
    let tokens = balance(lexed.tokens, src, &mut errors, why, &mut deep_regions);
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
    // The parser reads the limit from its state: one grammar, built once per
    // thread, serves every item and file.
    let mut limit = SimpleState(if next.is_some() { len } else { usize::MAX });
    let tokens: &[(Token<'_>, SimpleSpan)] = &input;
    let (file, parse_errors) = GRAMMAR.with(|g| {
        if quick {
            let quick = match next {
                Some(_) => g.quick_item.get().parse_with_state(token_stream(tokens, eoi), &mut limit),
                None => g.quick_file.get().parse_with_state(token_stream(tokens, eoi), &mut limit),
            };
            if !quick.has_errors() {
                return (quick.into_output(), Vec::new());
            }
        }
        let stream = token_stream(tokens, eoi);
        match next {
            Some(_) => g.item.get().parse_with_state(stream, &mut limit),
            None => g.file.get().parse_with_state(stream, &mut limit),
        }
        .into_output_errors()
    });
    errors.extend(parse_errors.into_iter().map(rich_to_diagnostic));
    // What a too-deep construct left (an opener and its closer, a keyword)
    // does not parse: those errors are follow-ups of the nesting error.
    if !deep_regions.is_empty() {
        errors.retain(|d| {
            d.code == codes::NESTING_TOO_DEEP
                || !deep_regions.iter().any(|r| r.start <= d.span.start && d.span.start <= r.end)
        });
    }
    let file = file.unwrap_or_default();
    lint_spellings(&file, &mut errors);
    errors.sort_by_key(|d| (d.span.start, d.span.end));
    errors.dedup();
    Parse { file, comments: lexed.comments, errors }
}

// ---------------------------------------------------------------------------
// Pass 1: delimiter balancing.

fn closer_of(t: Token<'_>) -> Option<Token<'static>> {
    match t {
        Token::LBrace => Some(Token::RBrace),
        Token::LParen => Some(Token::RParen),
        Token::LBracket => Some(Token::RBracket),
        _ => None,
    }
}

fn is_closer(t: Token<'_>) -> bool {
    matches!(t, Token::RBrace | Token::RParen | Token::RBracket)
}

/// Whether `tok`, followed by `next`, looks like the start of a top-level
/// item. A keyword alone is not enough: `events { mission; }` uses a keyword
/// as a name by mistake, which must be one error, not a closed block.
fn starts_item_here(tok: Token<'_>, next: Option<Token<'_>>) -> bool {
    let Token::Kw(k) = tok else { return false };
    match k {
        Kw::Import => matches!(next, Some(Token::Str(_))),
        Kw::Mission => matches!(next, Some(Token::LBrace | Token::Colon | Token::Ident(_))),
        Kw::PlanOp => matches!(next, Some(Token::Ident(_))),
        _ => k.starts_item() && matches!(next, Some(Token::LBrace)),
    }
}

/// The deepest nesting the parser accepts: open delimiters plus control
/// structures whose condition is written without delimiters (`if if A then
/// { B } then { C }`). Every later stage (checker, compiler, formatter,
/// language server) walks the tree recursively, so this bound is also the
/// bound of their recursion; it leaves room for a debug build on a 2 MB
/// thread stack. Real missions nest a handful of levels.
pub const MAX_NESTING: usize = 64;

/// A construct nested deeper than [`MAX_NESTING`] whose contents the
/// balancing pass dropped: the error at its first token, and the region
/// whose parse errors are follow-ups of that one.
struct TooDeep {
    /// Number of open delimiters that stay open once the region ends (for
    /// a group, they include its opener).
    keep: usize,
    /// Whether the region is one delimited group (it ends with that group's
    /// closer) or a control structure's keyword (it ends at the next `;` or
    /// closer at its level).
    group: bool,
    start: usize,
}

/// Whether the identifier at `i` starts a call `Name( ... )` followed by
/// what follows a statement (rather than a parametrised mission's header).
fn is_call(tokens: &[(Token<'_>, Span)], i: usize) -> bool {
    if tokens.get(i + 1).map(|t| t.0) != Some(Token::LParen) {
        return false;
    }
    let mut depth = 0usize;
    for (j, (t, _)) in tokens.iter().enumerate().skip(i + 1) {
        if closer_of(*t).is_some() {
            depth += 1;
        } else if let Token::Kw(k) = t {
            if k.starts_item() {
                return false;
            }
        } else if is_closer(*t) {
            depth -= 1;
            if depth == 0 {
                return !matches!(tokens.get(j + 1).map(|t| t.0), Some(Token::LBrace | Token::LBracket));
            }
        }
    }
    false
}

/// Balances the delimiters of `tokens` (lexed from `src`). An item that
/// ends with blocks still open is balanced again reading its indentation,
/// the way rustc places a missing `}`: a `}` indented like an outer block's
/// line closes that block, and each `{` left open is closed where its
/// indented block ends. That reading is kept when it leaves nothing of the
/// item outside its body; otherwise the item keeps the plain matching.
fn balance<'s>(
    tokens: Vec<(Token<'s>, Span)>,
    src: &str,
    errors: &mut Vec<Diagnostic>,
    at_end: &str,
    deep_regions: &mut Vec<Span>,
) -> Vec<(Token<'s>, Span)> {
    let (e0, d0) = (errors.len(), deep_regions.len());
    let plain = balance_pass(&tokens, src, errors, at_end, deep_regions, &[]);
    let mut items = plain.unclosed;
    if items.is_empty() {
        return plain.out;
    }
    // Each pass drops at least one item, or is the last.
    loop {
        errors.truncate(e0);
        deep_regions.truncate(d0);
        let pass = balance_pass(&tokens, src, errors, at_end, deep_regions, &items);
        if pass.rejected.is_empty() {
            return pass.out;
        }
        items.retain(|i| !pass.rejected.contains(i));
    }
}

/// What one balancing pass gives: the balanced tokens, the items (by the
/// index of their first token) that end with delimiters still open, and
/// the items read by indentation whose reading was rejected.
struct Balanced<'s> {
    out: Vec<(Token<'s>, Span)>,
    unclosed: Vec<usize>,
    rejected: Vec<usize>,
}

/// The start of the line that holds byte `at`, not before `item` (the
/// item's first byte: an item parsed alone starts there, so its first line
/// is read the same way in both cases).
fn line_start(src: &str, item: usize, at: usize) -> usize {
    src.as_bytes()[item..at].iter().rposition(|&b| b == b'\n').map_or(item, |p| item + p + 1)
}

/// The indentation (in bytes) of the line that holds byte `at`.
fn indent_of(src: &str, item: usize, at: usize) -> usize {
    let ls = line_start(src, item, at);
    src.as_bytes()[ls..].iter().take_while(|&&b| b == b' ' || b == b'\t').count()
}

/// The column of `at` when it is the first token of its line.
fn first_on_line(src: &str, item: usize, at: usize) -> Option<usize> {
    // Only the blanks before `at` are read: a long line costs nothing.
    let b = src.as_bytes();
    let mut i = at;
    while i > item && matches!(b[i - 1], b' ' | b'\t' | b'\r') {
        i -= 1;
    }
    (i == item || b[i - 1] == b'\n').then_some(at - i)
}

/// For a `}` at `at` that would close `stack[inner]`: the outer `{` it is
/// indented like, when it is the first token of its line, less indented than
/// the line of `stack[inner]`, and only `{` are open in between.
fn outer_by_indent(src: &str, item: usize, stack: &[(Token<'_>, Span)], inner: usize, at: usize) -> Option<usize> {
    let col = first_on_line(src, item, at)?;
    if col >= indent_of(src, item, stack[inner].1.start as usize) {
        return None;
    }
    let q = (0..inner).rev().find(|&q| indent_of(src, item, stack[q].1.start as usize) <= col)?;
    let braces = stack[q..=inner].iter().all(|(t, _)| *t == Token::LBrace);
    (braces && indent_of(src, item, stack[q].1.start as usize) == col).then_some(q)
}

/// Where the `}` of each `{` of `stack[from..]` (all open at the end of
/// `out`, which holds the item from `lo` on) is expected by indentation:
/// before the first token, after the `{` and the ends found for the blocks
/// inside it, that starts a line no more indented than the `{`'s line, at a
/// point where only `stack` is open (in a control structure, before the `;`
/// that ends the line before it). Innermost first; `None` when no line ends the block before
/// the end of `out`.
fn block_ends(
    src: &str,
    item: usize,
    out: &[(Token<'_>, Span)],
    lo: usize,
    stack: &[(Token<'_>, Span)],
    from: usize,
) -> Vec<Option<usize>> {
    // The depth before each token, back to the outermost `{` asked about
    // (from the end: `rev[0]` is the last token's).
    let n = stack.len();
    let mut rev = Vec::new();
    // The first opener seen at depth `d` going back is `stack[d]`: the
    // depth stays above `d` after it.
    let mut opened = vec![None; n];
    let mut d = n;
    let mut k = out.len();
    while k > lo && d > from {
        k -= 1;
        let t = out[k].0;
        if closer_of(t).is_some() {
            d -= 1;
            if d < n {
                opened[d] = opened[d].or(Some(k));
            }
        } else if is_closer(t) {
            d += 1;
        }
        rev.push(d);
    }
    let depth = |k: usize| rev[out.len() - 1 - k];
    let mut ends = Vec::new();
    let mut after = 0;
    for j in (from..n).rev() {
        let indent = indent_of(src, item, stack[j].1.start as usize);
        let Some(open) = opened[j] else {
            ends.push(None);
            continue;
        };
        let start = after.max(open + 1);
        let end = (start..out.len()).find(|&k| {
            let (_, span) = out[k];
            depth(k) == n
                && !span.is_empty()
                && first_on_line(src, item, span.start as usize).is_some_and(|col| col <= indent)
        });
        // `... } ;`: in a control structure's block (its `{` follows a
        // keyword or a condition), a `;` that ends the line separates the
        // statements of the outer block, so the `}` goes before it.
        let control = open.checked_sub(1).is_some_and(|b| {
            matches!(
                out[b].0,
                Token::RParen
                    | Token::Kw(
                        Kw::Parallel
                            | Kw::And
                            | Kw::Or
                            | Kw::Try
                            | Kw::Catch
                            | Kw::Then
                            | Kw::Else
                            | Kw::Do
                            | Kw::Monitor
                    )
            )
        });
        let end =
            end.map(
                |k| {
                    if control && k > start && out[k - 1].0 == Token::Semi && depth(k - 1) == n {
                        k - 1
                    } else {
                        k
                    }
                },
            );
        after = end.unwrap_or(out.len());
        ends.push(end);
    }
    ends
}

/// Whether the balanced tokens of one item keep everything after its body's
/// `{` inside that body, up to its last token.
fn holds_together(out: &[(Token<'_>, Span)]) -> bool {
    let mut depth = 0usize;
    let mut body = false;
    for (k, (t, _)) in out.iter().enumerate() {
        if closer_of(*t).is_some() {
            body |= depth == 0 && *t == Token::LBrace;
            depth += 1;
        } else if is_closer(*t) {
            depth = depth.saturating_sub(1);
            if body && depth == 0 && k + 1 < out.len() {
                return false;
            }
        }
    }
    true
}

/// One balancing pass; the items of `by_indent` are read by indentation.
fn balance_pass<'s>(
    tokens: &[(Token<'s>, Span)],
    src: &str,
    errors: &mut Vec<Diagnostic>,
    at_end: &str,
    deep_regions: &mut Vec<Span>,
    by_indent: &[usize],
) -> Balanced<'s> {
    let len = src.len();
    let mut out = Vec::with_capacity(tokens.len() + 4);
    let mut unclosed_items = Vec::new();
    let mut rejected = Vec::new();
    // The item being read: its first token, first byte, first balanced
    // token, and whether it is read by indentation.
    let mut item = ItemAt::new(0, 0, 0, by_indent);
    let mut stack: Vec<(Token<'s>, Span)> = Vec::new();
    // Per open delimiter (and the top level at index 0): the control
    // keywords whose bare condition is still open; `nested` is their sum.
    let mut pending: Vec<usize> = vec![0];
    let mut nested = 0usize;
    let mut skip: Option<TooDeep> = None;
    // After a nesting error, the other constructs too deep in the same item
    // (the `catch` of a `try` too deep, a call's parentheses at the limit)
    // are skipped too, without another error.
    let mut quiet = false;
    // The header of the mission being read (`mission : name [ ID at NUM ]`,
    // `mission Name( ... )`): how far it got, and where its body should
    // have started if a token that belongs to no header came before any
    // `{`. A `}` with no opener then closes that missing `{`.
    let mut header: Option<u8> = None;
    let mut missing_open: Option<(usize, Span)> = None;
    let unclosed = |open: (Token<'_>, Span), at: Span, why: &str| {
        let close = closer_of(open.0).expect("stack holds openers");
        Diagnostic::error(codes::UNCLOSED_DELIMITER, format!("unclosed {}", open.0), open.1)
            .with_label(open.1, format!("this {} is never closed", open.0))
            .with_label(at, format!("{close} expected {why}"))
            .with_help(format!("add the missing {close}"))
    };
    let too_deep = |span: Span, what: &str| {
        Diagnostic::error(
            codes::NESTING_TOO_DEEP,
            format!("{what} nested too deeply (more than {MAX_NESTING} levels)"),
            span,
        )
        .with_label(span, format!("this is nesting level {}", MAX_NESTING + 1))
        .with_help("split the mission: move the innermost part into a task or a separate mission; its contents are not checked")
    };
    // Ends the dropped region before `at`: the delimiters opened inside it
    // are forgotten, the others stay open.
    let end_skip = |skip: &mut Option<TooDeep>,
                    stack: &mut Vec<(Token<'s>, Span)>,
                    pending: &mut Vec<usize>,
                    nested: &mut usize,
                    deep_regions: &mut Vec<Span>,
                    at: usize| {
        if let Some(s) = skip.take() {
            stack.truncate(s.keep);
            pending.truncate(s.keep + 1);
            *nested = pending.iter().sum();
            deep_regions.push(Span::new(s.start, at));
        }
    };
    for (i, &(tok, span)) in tokens.iter().enumerate() {
        if let Some(s) = &skip {
            // Inside a dropped region: only the delimiters are followed, to
            // find where it ends.
            if closer_of(tok).is_some() {
                stack.push((tok, span));
                pending.push(0);
                continue;
            }
            if is_closer(tok) {
                match stack.iter().rposition(|(o, _)| closer_of(*o) == Some(tok)) {
                    Some(pos) if pos >= s.keep => {
                        stack.truncate(pos);
                        pending.truncate(pos + 1);
                        continue;
                    }
                    Some(_) => {
                        // It closes the group or an outer block: the region
                        // ends here and the closer is handled as usual.
                        end_skip(&mut skip, &mut stack, &mut pending, &mut nested, deep_regions, span.start as usize);
                    }
                    None => continue,
                }
            } else if tok == Token::Semi && !s.group && stack.len() == s.keep {
                end_skip(&mut skip, &mut stack, &mut pending, &mut nested, deep_regions, span.start as usize);
            } else if matches!(tok, Token::Kw(k) if k.starts_item() && stack.is_empty())
                || starts_item_here(tok, tokens.get(i + 1).map(|t| t.0))
            {
                // The next item (where `split_items` cuts the file too).
                end_skip(&mut skip, &mut stack, &mut pending, &mut nested, deep_regions, span.start as usize);
            } else {
                continue;
            }
        }
        if closer_of(tok).is_some() {
            if stack.is_empty() {
                match (header, tok) {
                    (Some(h), Token::LParen) if h <= 2 => header = Some(3),
                    (Some(h), Token::LBracket) if h <= 3 => header = Some(4),
                    (Some(_), _) => {
                        if tok != Token::LBrace {
                            missing_open = Some((out.len(), span));
                        }
                        header = None;
                    }
                    (None, Token::LBrace) => missing_open = None,
                    _ => {}
                }
            }
            // `if ( A )`, `while { A }`: the condition's delimiters are its
            // level, not the keyword.
            let top = pending.last_mut().expect("the top level is always there");
            if *top > 0
                && i > 0
                && matches!(tokens[i - 1].0, Token::Kw(Kw::If | Kw::While | Kw::Condition | Kw::WhileCondition))
            {
                *top -= 1;
                nested -= 1;
            }
            stack.push((tok, span));
            pending.push(0);
            out.push((tok, span));
            if stack.len() + nested > MAX_NESTING {
                if !quiet {
                    errors.push(too_deep(span, "blocks"));
                    quiet = true;
                }
                skip = Some(TooDeep { keep: stack.len(), group: true, start: span.start as usize });
            }
        } else if is_closer(tok) {
            match stack.iter().rposition(|(o, _)| closer_of(*o) == Some(tok)) {
                Some(pos) => {
                    while stack.len() > pos + 1 {
                        let open = stack.pop().expect("len > pos + 1");
                        errors.push(unclosed(open, span, "before this"));
                        out.push((closer_of(open.0).expect("opener"), Span::at(span.start as usize)));
                    }
                    // Read by indentation, a `}` may close an outer block:
                    // the blocks inside it are the ones left open.
                    let outer = item.by_indent && tok == Token::RBrace;
                    let pos = match outer.then(|| outer_by_indent(src, item.start, &stack, pos, span.start as usize)) {
                        Some(Some(q)) => {
                            let shut = Shut { fallback: span, why: "", closer: Some(span) };
                            close_by_indent(src, item, &mut stack, q + 1, shut, errors, &mut out, &unclosed);
                            q
                        }
                        _ => pos,
                    };
                    if item.by_indent && tok == Token::RBrace {
                        let col = first_on_line(src, item.start, span.start as usize);
                        item.askew |= col.is_some_and(|c| c != indent_of(src, item.start, stack[pos].1.start as usize));
                    }
                    stack.pop();
                    pending.truncate(pos + 1);
                    nested = pending.iter().sum();
                    out.push((tok, span));
                }
                None => match missing_open.take() {
                    Some((at, first)) if tok == Token::RBrace => {
                        // `mission m  Depth(1); }`: the body's `{` is missing.
                        errors.push(
                            Diagnostic::error(codes::UNEXPECTED_TOKEN, "expected `{` before the mission's body", first)
                                .with_label(first, "the body starts here")
                                .with_label(span, "and ends here")
                                .with_help("add the missing `{` after the mission's header"),
                        );
                        out.insert(at, (Token::LBrace, Span::at(first.start as usize)));
                        out.push((tok, span));
                    }
                    _ => errors.push(
                        Diagnostic::error(codes::UNMATCHED_CLOSE, format!("unmatched {tok}"), span)
                            .with_help("remove it, or add the opening delimiter it closes"),
                    ),
                },
            }
        } else if !stack.is_empty() && starts_item_here(tok, tokens.get(i + 1).map(|t| t.0)) {
            // Items only appear at the top level: close everything still open.
            close_item(src, item, &mut stack, span.start as usize, "before the next item", errors, &mut out, &unclosed);
            end_item(item, &out, true, &mut unclosed_items, &mut rejected);
            item = ItemAt::new(i, span.start as usize, out.len(), by_indent);
            pending.truncate(1);
            pending[0] = 0;
            nested = 0;
            quiet = false;
            header = matches!(tok, Token::Kw(Kw::Mission | Kw::PlanOp)).then_some(0);
            missing_open = None;
            out.push((tok, span));
        } else {
            if stack.is_empty() {
                match (header, tok) {
                    (_, Token::Kw(k)) if k.starts_item() => {
                        header = matches!(k, Kw::Mission | Kw::PlanOp).then_some(0);
                        missing_open = None;
                        end_item(item, &out, false, &mut unclosed_items, &mut rejected);
                        item = ItemAt::new(i, span.start as usize, out.len(), by_indent);
                    }
                    (Some(0), Token::Colon) => header = Some(1),
                    (Some(h), Token::Ident(_)) if h <= 1 && !is_call(tokens, i) => header = Some(2),
                    (Some(1), Token::Kw(_)) => header = Some(2),
                    (Some(_), _) => {
                        missing_open = Some((out.len(), span));
                        header = None;
                    }
                    _ => {}
                }
            }
            out.push((tok, span));
            let top = pending.last_mut().expect("the top level is always there");
            match tok {
                Token::Semi => {
                    nested -= *top;
                    *top = 0;
                }
                Token::Kw(Kw::Then | Kw::Do) if *top > 0 => {
                    *top -= 1;
                    nested -= 1;
                }
                Token::Kw(Kw::If | Kw::While | Kw::Condition | Kw::WhileCondition) => {
                    *top += 1;
                    nested += 1;
                    if stack.len() + nested > MAX_NESTING {
                        if !quiet {
                            errors.push(too_deep(span, "control structures"));
                            quiet = true;
                        }
                        skip = Some(TooDeep { keep: stack.len(), group: false, start: span.start as usize });
                    }
                }
                Token::Kw(k) if k.starts_item() => {
                    nested -= *top;
                    *top = 0;
                    if stack.is_empty() {
                        quiet = false;
                    }
                }
                _ => {}
            }
        }
    }
    end_skip(&mut skip, &mut stack, &mut pending, &mut nested, deep_regions, len);
    let open = !stack.is_empty();
    close_item(src, item, &mut stack, len, at_end, errors, &mut out, &unclosed);
    end_item(item, &out, open, &mut unclosed_items, &mut rejected);
    Balanced { out, unclosed: unclosed_items, rejected }
}

/// The item being balanced.
#[derive(Clone, Copy)]
struct ItemAt {
    /// The index of its first token, which names it.
    first: usize,
    /// Its first byte.
    start: usize,
    /// The index of its first balanced token.
    out: usize,
    /// Whether it is read by indentation.
    by_indent: bool,
    /// Whether, so read, a `}` that starts a line closes a `{` whose line
    /// is indented differently: then the indentation cannot be trusted.
    askew: bool,
}

impl ItemAt {
    fn new(first: usize, start: usize, out: usize, by_indent: &[usize]) -> Self {
        ItemAt { first, start, out, by_indent: by_indent.contains(&first), askew: false }
    }
}

/// Records how the item `item` ended: with delimiters still `open`, and
/// whether its reading by indentation holds.
fn end_item(item: ItemAt, out: &[(Token<'_>, Span)], open: bool, unclosed: &mut Vec<usize>, rejected: &mut Vec<usize>) {
    if open {
        unclosed.push(item.first);
    }
    if item.by_indent && (item.askew || !holds_together(&out[item.out..])) {
        rejected.push(item.first);
    }
}

/// How [`close_by_indent`] ends its blocks: `closer` is the `}` that closes
/// an outer block, if one does (it ends them all); otherwise a block that no
/// line ends is closed before `fallback`, said `why`.
struct Shut<'a> {
    fallback: Span,
    why: &'a str,
    closer: Option<Span>,
}

/// Closes the delimiters still open at the end of an item: by indentation
/// when the item is read so and only a few `{` are open, else at `at`.
#[allow(clippy::too_many_arguments)]
fn close_item<'s>(
    src: &str,
    item: ItemAt,
    stack: &mut Vec<(Token<'s>, Span)>,
    at: usize,
    why: &str,
    errors: &mut Vec<Diagnostic>,
    out: &mut Vec<(Token<'s>, Span)>,
    unclosed: &Unclosed,
) {
    if item.by_indent && !stack.is_empty() && stack.len() <= 3 && stack.iter().all(|(t, _)| *t == Token::LBrace) {
        let shut = Shut { fallback: Span::at(at), why, closer: None };
        close_by_indent(src, item, stack, 0, shut, errors, out, unclosed);
    } else {
        close_all(stack, at, why, errors, out, unclosed);
    }
}

/// Closes the `{` of `stack[from..]`, each where its indented block ends
/// ([`block_ends`]), one error each.
#[allow(clippy::too_many_arguments)]
fn close_by_indent<'s>(
    src: &str,
    item: ItemAt,
    stack: &mut Vec<(Token<'s>, Span)>,
    from: usize,
    shut: Shut<'_>,
    errors: &mut Vec<Diagnostic>,
    out: &mut Vec<(Token<'s>, Span)>,
    unclosed: &Unclosed,
) {
    let ends = block_ends(src, item.start, out, item.out, stack, from);
    let mut inserts = Vec::new();
    for (end, &open) in ends.iter().zip(stack[from..].iter().rev()) {
        // A `}` that closes an outer block ends the inner ones too.
        let end = end.or(shut.closer.map(|_| out.len()));
        let (k, at, why) = match end {
            // After the last token of the block (`k` follows its `{`).
            Some(k) => (k, Span::at(out[k - 1].1.end as usize), "here, where its indented block ends"),
            None => (out.len(), shut.fallback, shut.why),
        };
        let mut d = unclosed(open, at, why);
        if let Some(c) = shut.closer {
            d = d.with_label(c, "this `}` is indented like an outer block, so it closes that block");
        }
        errors.push(d);
        inserts.push((k, (closer_of(open.0).expect("opener"), Span::at(at.start as usize))));
    }
    // Outermost first: the places of the inner ones, before, stay right.
    for (k, t) in inserts.into_iter().rev() {
        out.insert(k, t);
    }
    stack.truncate(from);
}

/// Builds the error of a delimiter left open: the opener, where its closer
/// was expected, and why there.
type Unclosed = dyn Fn((Token<'_>, Span), Span, &str) -> Diagnostic;

/// Closes every delimiter still open at `at`, one error each; beyond a few
/// (generated or pasted text), one error at the outermost says how many more
/// are open inside it.
fn close_all<'s>(
    stack: &mut Vec<(Token<'s>, Span)>,
    at: usize,
    why: &str,
    errors: &mut Vec<Diagnostic>,
    out: &mut Vec<(Token<'s>, Span)>,
    unclosed: &Unclosed,
) {
    const SHOWN: usize = 3;
    let n = stack.len();
    for (k, open) in stack.drain(..).rev().enumerate() {
        if n <= SHOWN || k == n - 1 {
            let mut d = unclosed(open, Span::at(at), why);
            if n > SHOWN {
                d = d.with_note(format!("{} more delimiters opened inside this one are not closed either", n - 1));
            }
            errors.push(d);
        }
        out.push((closer_of(open.0).expect("opener"), Span::at(at)));
    }
}

// ---------------------------------------------------------------------------
// Pass 2: the grammar.

type In<'t, 's> = MappedInput<
    't,
    Token<'s>,
    SimpleSpan,
    &'t [(Token<'s>, SimpleSpan)],
    fn(&'t (Token<'s>, SimpleSpan)) -> (&'t Token<'s>, &'t SimpleSpan),
>;
/// The parser's extra types: its errors `R` (rich, or [`EmptyErr`] for the
/// quick pass), and its state, where the current item ends (`usize::MAX` for
/// a whole file): the keyword of the next item that follows is not parsed.
type Ex<R> = extra::Full<R, SimpleState<usize>, ()>;

/// The errors the grammar can produce: [`Rich`] ones, or none at all
/// ([`EmptyErr`]: only whether an error happened).
trait Fail<'t, I: Input<'t>>: chumsky::error::Error<'t, I> + LabelError<'t, I, &'static str> + 't {
    /// An error with a message (see [`custom`]).
    fn custom(span: SimpleSpan, msg: String) -> Self;
}

impl<'t, 's: 't, I: Input<'t, Token = Token<'s>, Span = SimpleSpan>> Fail<'t, I> for Rich<'t, Token<'s>, SimpleSpan> {
    fn custom(span: SimpleSpan, msg: String) -> Self {
        Rich::custom(span, msg)
    }
}

impl<'t, I: Input<'t>> Fail<'t, I> for EmptyErr {
    fn custom(_: SimpleSpan, _: String) -> Self {
        EmptyErr::default()
    }
}

/// The parser's input. One lifetime: [`In`] is invariant in the tokens'
/// lifetime, and the cached grammar is used with `In<'t, 't>`.
fn token_stream<'t>(tokens: &'t [(Token<'t>, SimpleSpan)], eoi: SimpleSpan) -> In<'t, 't> {
    tokens.map(eoi, |(t, s)| (t, s))
}

/// The grammar of a whole file (`ITEM = false`) or of one item followed by
/// the next one's keyword (`ITEM = true`), for any input lifetime: building
/// it allocates hundreds of boxed combinators, so each thread builds it once
/// ([`GRAMMAR`]) instead of once per item.
#[derive(Default)]
struct Grammar<const ITEM: bool>;

impl<const ITEM: bool> Cached for Grammar<ITEM> {
    type Parser<'t> = Boxed<'t, 't, In<'t, 't>, SourceFile, Ex<Rich<'t, Token<'t>, SimpleSpan>>>;

    fn make_parser<'t>(self) -> Self::Parser<'t> {
        item_parser(ITEM)
    }
}

/// The same grammar without error reporting. Most texts have no syntax
/// error: the quick pass gives their tree without building an error for
/// every alternative tried; a text with an error is parsed again with
/// [`Grammar`] (the tree is the same whenever no error was emitted: error
/// recovery only runs after an error).
#[derive(Default)]
struct QuickGrammar<const ITEM: bool>;

impl<const ITEM: bool> Cached for QuickGrammar<ITEM> {
    type Parser<'t> = Boxed<'t, 't, In<'t, 't>, SourceFile, Ex<EmptyErr>>;

    fn make_parser<'t>(self) -> Self::Parser<'t> {
        item_parser(ITEM)
    }
}

struct Grammars {
    file: Cache<Grammar<false>>,
    item: Cache<Grammar<true>>,
    quick_file: Cache<QuickGrammar<false>>,
    quick_item: Cache<QuickGrammar<true>>,
}

thread_local! {
    static GRAMMAR: Grammars = Grammars {
        file: Cache::default(),
        item: Cache::default(),
        quick_file: Cache::default(),
        quick_item: Cache::default(),
    };
}

/// Custom errors carry their code and help in the message, separated by `\u{1}`.
fn custom(code: &str, msg: impl std::fmt::Display, help: &str) -> String {
    format!("{code}\u{1}{msg}\u{1}{help}")
}

fn name<'t, 's: 't, I, R>() -> impl Parser<'t, I, Name, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    select! { Token::Ident(s) = e => Name { text: s.to_string(), span: Span::from(e.span()) } }.labelled("identifier")
}

fn number<'t, 's: 't, I, R>() -> impl Parser<'t, I, Number, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    select! { Token::Num(s) = e => Number { text: s.to_string(), span: Span::from(e.span()) } }.labelled("number")
}

/// A contextual word lexed as an identifier, e.g. `c`, `v`, `a`, `e`, `mutex`.
fn word<'t, 's: 't, I, R>(
    w: &'static str,
    label: &'static str,
) -> impl Parser<'t, I, Span, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    select! { Token::Ident(s) = e if s == w => Span::from(e.span()) }.labelled(label)
}

fn kw<'t, 's: 't, I, R>(k: Kw) -> impl Parser<'t, I, Span, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    just(Token::Kw(k)).map_with(|_, e| Span::from(e.span()))
}

/// Any balanced token tree: a delimited group or a single non-delimiter token.
fn token_tree<'t, 's: 't, I, R>() -> impl Parser<'t, I, (), Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    recursive(|tt| {
        let group = |o: Token<'static>, c: Token<'static>| tt.clone().repeated().delimited_by(just(o), just(c));
        choice((
            group(Token::LBrace, Token::RBrace),
            group(Token::LParen, Token::RParen),
            group(Token::LBracket, Token::RBracket),
            none_of([Token::LBrace, Token::RBrace, Token::LParen, Token::RParen, Token::LBracket, Token::RBracket])
                .ignored(),
        ))
        .ignored()
    })
    .boxed()
}

/// `p` repeated inside a braced list of `;`-terminated definitions. A broken
/// definition is skipped up to and including its `;` (or up to the `}`).
fn semi_list<'t, 's: 't, I, R, T>(p: impl Parser<'t, I, T, Ex<R>> + Clone + 't) -> Boxed<'t, 't, I, Vec<T>, Ex<R>>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
    T: 't,
{
    let skip = token_tree()
        .and_is(none_of([Token::Semi, Token::RBrace]).ignored())
        .repeated()
        .then(just(Token::Semi).or_not())
        .ignored();
    let item = p
        .then_ignore(just(Token::Semi))
        .map(Some)
        .recover_with(via_parser(none_of([Token::RBrace]).rewind().ignore_then(skip).map(|_| None)));
    none_of([Token::RBrace])
        .rewind()
        .ignore_then(item)
        .repeated()
        .collect::<Vec<Option<T>>>()
        .map(|v| v.into_iter().flatten().collect())
        .boxed()
}

/// `{ ... }` whose contents, if they fail to parse, become `fallback`.
fn braced<'t, 's: 't, I, R, T: 't>(
    p: impl Parser<'t, I, T, Ex<R>> + Clone + 't,
    fallback: impl Fn() -> T + Clone + 't,
) -> Boxed<'t, 't, I, T, Ex<R>>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    p.delimited_by(just(Token::LBrace), just(Token::RBrace))
        .recover_with(via_parser(
            just(Token::LBrace)
                .ignore_then(token_tree().repeated())
                .then_ignore(just(Token::RBrace))
                .map(move |_| fallback()),
        ))
        .boxed()
}

fn value<'t, 's: 't, I, R>() -> impl Parser<'t, I, Value, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    recursive(|value| {
        let list = value
            .separated_by(just(Token::Comma))
            .allow_trailing()
            .collect::<Vec<_>>()
            .delimited_by(just(Token::LBracket), just(Token::RBracket))
            .recover_with(via_parser(
                just(Token::LBracket)
                    .ignore_then(token_tree().repeated())
                    .then_ignore(just(Token::RBracket))
                    .to(Vec::new()),
            ));
        let string = select! { Token::Str(s) => ValueKind::Str(unescape(s)) }.labelled("string");
        choice((
            name().then(list.clone().or_not()).map(|(n, l)| match l {
                Some(items) => ValueKind::List { tag: Some(n), items },
                None => ValueKind::Ident(n),
            }),
            number().map(ValueKind::Number),
            string,
            list.map(|items| ValueKind::List { tag: None, items }),
        ))
        .map_with(|kind, e| Value { kind, span: Span::from(e.span()) })
        .labelled("value")
    })
    .boxed()
}

fn stmt_error(span: Span) -> Stmt {
    Stmt { kind: StmtKind::Error, span }
}

fn empty_block(span: Span) -> Block {
    Block { stmts: vec![stmt_error(span)], span }
}

/// Tokens that end a statement list used as a bare condition
/// (`if A then { B }`, `while A do { B }`); never consumed by statement recovery.
const STMT_STOP: [Token<'static>; 7] = [
    Token::LBrace,
    Token::RBrace,
    Token::RParen,
    Token::RBracket,
    Token::Kw(Kw::Then),
    Token::Kw(Kw::Do),
    Token::Kw(Kw::Else),
];

/// Tokens that end a statement list between delimiters (`{ ... }`, `( ... )`).
/// The token stream is balanced, so the first of them is the list's own
/// closing delimiter: a delimited list always extends to it, and a broken
/// statement is skipped up to the next `;` or that delimiter (skipping whole
/// `{ ... }` groups), never further and never less.
const CLOSERS: [Token<'static>; 3] = [Token::RBrace, Token::RParen, Token::RBracket];

fn block<'t, 's: 't, I, R>(
    stmt: impl Parser<'t, I, Stmt, Ex<R>> + Clone + 't,
    stops: &'static [Token<'static>],
) -> Boxed<'t, 't, I, Block, Ex<R>>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    // A statement that fails is skipped up to the next `;` or stop token.
    let skip = token_tree().and_is(none_of([Token::Semi]).ignored()).and_is(none_of(stops).ignored()).repeated();
    let recovering = stmt.recover_with(via_parser(
        token_tree().and_is(none_of(stops).ignored()).then(skip).map_with(|_, e| stmt_error(Span::from(e.span()))),
    ));
    let item = none_of(stops)
        .rewind()
        .ignore_then(recovering)
        .then(just(Token::Semi).map_with(|_, e| Span::from(e.span())).or_not());
    item.repeated().collect::<Vec<(Stmt, Option<Span>)>>().validate(|items, e, emitter| {
        let span = Span::from(e.span());
        if items.is_empty() {
            emitter.emit(R::custom(
                e.span(),
                custom(codes::EMPTY_BLOCK, "expected a statement", "a block holds at least one task call or control structure; use `Void()` for a task that does nothing"),
            ));
            return empty_block(span);
        }
        let n = items.len();
        let mut stmts = Vec::with_capacity(n);
        let next_ok: Vec<bool> = items.iter().skip(1).map(|(s, _)| s.kind != StmtKind::Error).collect();
        for (i, (s, semi)) in items.into_iter().enumerate() {
            // Only between two statements that parsed: after or before a
            // broken one, the error already reported is enough.
            if i + 1 < n && semi.is_none() && s.kind != StmtKind::Error && next_ok[i] {
                emitter.emit(R::custom(
                    SimpleSpan::from(s.span.end as usize..s.span.end as usize),
                    custom(codes::UNEXPECTED_TOKEN, "expected `;` between two statements", "`;` runs the statement before it, then the statement after it"),
                ));
            }
            stmts.push(s);
        }
        Block { stmts, span }
    })
    .boxed()
}

fn stmt<'t, 's: 't, I, R>() -> impl Parser<'t, I, Stmt, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    recursive(|stmt| {
        let bare_block = block(stmt.clone().boxed(), &STMT_STOP).boxed();
        let block = block(stmt.boxed(), &CLOSERS).boxed();
        let braced_block = braced(block.clone(), || empty_block(Span::default()))
            .map_with(|mut b: Block, e| {
                b.span = Span::from(e.span());
                b
            })
            .labelled("`{ ... }`")
            .boxed();
        let paren_block = block
            .clone()
            .delimited_by(just(Token::LParen), just(Token::RParen))
            .recover_with(via_parser(
                just(Token::LParen)
                    .ignore_then(token_tree().repeated())
                    .then_ignore(just(Token::RParen))
                    .map_with(|_, e| empty_block(Span::from(e.span()))),
            ))
            .boxed();
        // A condition: `( A )`, `{ A }` or a bare statement list ending at `then`/`do`.
        let cond = choice((paren_block.clone(), braced_block.clone(), bare_block)).boxed();

        let args = value()
            .separated_by(just(Token::Comma))
            .allow_trailing()
            .collect::<Vec<_>>()
            .delimited_by(just(Token::LParen), just(Token::RParen))
            .map_with(|args, e| (args, Span::from(e.span())))
            .recover_with(via_parser(
                just(Token::LParen)
                    .ignore_then(token_tree().repeated())
                    .then_ignore(just(Token::RParen))
                    .map_with(|_, e| (Vec::new(), Span::from(e.span()))),
            ));
        let call = name()
            .then(args)
            .then(just(Token::Colon).ignore_then(name()).or_not())
            .map_with(|((name, (args, args_span)), label), e| {
                StmtKind::Call(Call { name, args, args_span, label, span: Span::from(e.span()) })
            })
            .labelled("task call")
            .boxed();

        let while_ = kw(Kw::While)
            .then(cond.clone())
            .then_ignore(kw(Kw::Do).or_not())
            .then(braced_block.clone())
            .map(|((keyword, cond), body)| StmtKind::While { keyword, cond, body })
            .boxed();

        let else_ = kw(Kw::Else).then(braced_block.clone()).map(|(_, b)| (b, None));
        // Table B.4 writes the else branch as `then { C }`: accepted, linted.
        let then_as_else = kw(Kw::Then).then(braced_block.clone()).map(|(s, b)| (b, Some(s)));
        let if_ = kw(Kw::If)
            .then(cond.clone())
            .then_ignore(kw(Kw::Then).or_not())
            .then(braced_block.clone())
            .then(else_.or(then_as_else).or_not())
            .map(|(((keyword, cond), then), otherwise)| {
                let (otherwise, then_spelling) = match otherwise {
                    Some((b, s)) => (Some(b), s),
                    None => (None, None),
                };
                StmtKind::If { keyword, cond, then, otherwise, else_written_then: then_spelling }
            })
            .boxed();

        let par_op = kw(Kw::And).map(|s| (ParallelOp::And, s)).or(kw(Kw::Or).map(|s| (ParallelOp::Or, s)));
        let parallel = kw(Kw::Parallel)
            .then(braced_block.clone())
            .then(par_op.then(braced_block.clone()).repeated().at_least(1).collect::<Vec<_>>())
            .map(|((keyword, first), rest)| {
                let mut branches = vec![first];
                let mut ops = Vec::new();
                for (op, b) in rest {
                    ops.push(op);
                    branches.push(b);
                }
                StmtKind::Parallel { keyword, branches, ops }
            })
            .boxed();

        let try_ = kw(Kw::Try)
            .then(braced_block.clone())
            .then_ignore(kw(Kw::Catch))
            .then(braced_block.clone())
            .map(|((keyword, body), catch)| StmtKind::Try { keyword, body, catch })
            .boxed();

        let not = kw(Kw::Not)
            .then(paren_block.clone().or(braced_block.clone()))
            .map(|(keyword, body)| StmtKind::Not { keyword, body })
            .boxed();

        let handler_kind = kw(Kw::Condition)
            .map(|s| (MonitorKind::Condition, s))
            .or(kw(Kw::WhileCondition).map(|s| (MonitorKind::WhileCondition, s)));
        let handler = handler_kind.then(cond.clone()).then_ignore(kw(Kw::Do)).then(braced_block.clone()).map_with(
            |(((kind, keyword_span), condition), action), e| MonitorHandler {
                kind,
                keyword_span,
                condition,
                action,
                span: Span::from(e.span()),
            },
        );
        let monitor = kw(Kw::Monitor)
            .then(braced_block.clone())
            .then(handler.repeated().at_least(1).collect::<Vec<_>>())
            .map(|((keyword, body), handlers)| StmtKind::Monitor { keyword, body, handlers })
            .boxed();

        choice((call, while_, if_, parallel, try_, not, monitor))
            .map_with(|kind, e| Stmt { kind, span: Span::from(e.span()) })
            .labelled("statement")
    })
    .boxed()
}

/// The grammar of a file; with `Some(limit)`, of one item followed by the
/// keyword of the next one (at `limit`), which is not parsed.
fn item_parser<'t, 's: 't, R: Fail<'t, In<'t, 's>>>(one_item: bool) -> Boxed<'t, 't, In<'t, 's>, SourceFile, Ex<R>> {
    // import "path";
    let string = select! { Token::Str(s) = e => (unescape(s), Span::from(e.span())) }.labelled("string");
    // A missing `;` is one error after the path, and the import is kept (so
    // that the names it brings are still defined).
    let import = kw(Kw::Import).then(string).then(just(Token::Semi).or_not()).validate(
        |((_, (path, path_span)), semi), e, emitter| {
            if semi.is_none() {
                emitter.emit(R::custom(
                    SimpleSpan::from(path_span.end as usize..path_span.end as usize),
                    custom(
                        codes::UNEXPECTED_TOKEN,
                        "expected `;` after the imported file",
                        "write `import \"file.mcl\";`",
                    ),
                ));
            }
            Item::Import(Import { path, path_span, span: Span::from(e.span()) })
        },
    );

    // actions { name = Primitive( c: cmd, v: x, ... ); }
    enum ActionArg {
        Command(Name),
        Param(Value),
    }
    let action_arg = choice((
        word("c", "`c:`").ignore_then(just(Token::Colon)).ignore_then(name()).map(ActionArg::Command),
        word("v", "`v:`").ignore_then(just(Token::Colon)).ignore_then(value()).map(ActionArg::Param),
    ));
    let action_args = action_arg
        .separated_by(just(Token::Comma))
        .allow_trailing()
        .collect::<Vec<_>>()
        .validate(|args, e, emitter| {
            let mut command = None;
            let mut params = Vec::new();
            for a in args {
                match a {
                    ActionArg::Command(c) if command.is_none() => command = Some(c),
                    ActionArg::Command(c) => emitter.emit(R::custom(
                        SimpleSpan::from(c.span.range()),
                        custom(
                            codes::MISSING_COMMAND,
                            "an action has exactly one command `c: ...`",
                            "keep one `c:` and pass values with `v:`",
                        ),
                    )),
                    ActionArg::Param(v) => params.push(v),
                }
            }
            if command.is_none() {
                emitter.emit(R::custom(
                    e.span(),
                    custom(
                        codes::MISSING_COMMAND,
                        "an action needs a command `c: ...`",
                        "write the command first, e.g. `GotoPrimitive( c: enable, v: way-point )`",
                    ),
                ));
            }
            (command, params)
        })
        .delimited_by(just(Token::LParen), just(Token::RParen));
    let action = name()
        .then_ignore(just(Token::Eq))
        .then(name())
        .then(action_args)
        .map_with(|((name, primitive), (command, params)), e| ActionDef {
            name,
            primitive,
            command,
            params,
            span: Span::from(e.span()),
        })
        .boxed();
    let actions = kw(Kw::Actions)
        .ignore_then(braced(semi_list(action), Vec::new))
        .map_with(|actions, e| Item::Actions(ActionsBlock { actions, span: Span::from(e.span()) }));

    let events = kw(Kw::Events)
        .ignore_then(braced(semi_list(name()), Vec::new))
        .map_with(|events, e| Item::Events(EventsBlock { events, span: Span::from(e.span()) }));

    // Patterns.
    let iface = just(Token::Dot).ignore_then(number());
    let paren_num = number().delimited_by(just(Token::LParen), just(Token::RParen));
    let place =
        name().then(iface.clone().or_not()).then(paren_num.clone().or_not()).then(iface.clone().or_not()).map_with(
            |(((name, i1), tokens), i2), e| PlaceDef { name, interface: i1.or(i2), tokens, span: Span::from(e.span()) },
        );
    let delay = choice((number().map(Delay::Fixed), name().map(Delay::Param)))
        .delimited_by(just(Token::LParen), just(Token::RParen));
    let transition = name().then(iface.clone().or_not()).then(delay.or_not()).then(iface.clone().or_not()).map_with(
        |(((name, i1), delay), i2), e| TransitionDef { name, interface: i1.or(i2), delay, span: Span::from(e.span()) },
    );
    let node_ref = name().then(iface.clone().or_not()).map(|(name, interface)| NodeRef { name, interface });
    let arc = node_ref
        .clone()
        .then_ignore(just(Token::Arrow))
        .then(node_ref)
        .then(paren_num.or_not())
        .map_with(|((source, target), weight), e| ArcDef { source, target, weight, span: Span::from(e.span()) });
    let section = |k: Kw| kw(k).ignored();
    let net = section(Kw::Places)
        .ignore_then(braced(semi_list(place), Vec::new))
        .then(section(Kw::Transitions).ignore_then(braced(semi_list(transition), Vec::new)))
        .then(section(Kw::Arcs).ignore_then(braced(semi_list(arc), Vec::new)))
        .map(|((places, transitions), arcs)| PatternNet { places, transitions, arcs })
        .boxed();
    let file_name = choice((
        select! { Token::Str(s) => unescape(s) },
        name().then(just(Token::Dot).ignore_then(name()).repeated().collect::<Vec<_>>()).map(|(first, rest)| {
            let mut s = first.text;
            for n in rest {
                s.push('.');
                s.push_str(&n.text);
            }
            s
        }),
    ))
    .map_with(|path, e| (path, Span::from(e.span())))
    .labelled("file name");
    let pattern_body = choice((
        just(Token::Colon)
            .ignore_then(file_name)
            .then_ignore(just(Token::Semi))
            .map(|(path, path_span)| PatternBody::File { path, path_span }),
        braced(net.map(PatternBody::Net), || PatternBody::Net(PatternNet::default())),
    ));
    let pattern = name()
        .then(pattern_body)
        .map_with(|(name, body), e| Pattern { name, body, span: Span::from(e.span()) })
        .boxed();
    let pattern_item = none_of([Token::RBrace])
        .rewind()
        .ignore_then(
            pattern.map(Some).recover_with(via_parser(
                // A broken pattern keeps its name, so that its uses are not
                // reported as undefined (the checker skips its checks).
                name()
                    .or_not()
                    .rewind()
                    .then(
                        token_tree()
                            .and_is(none_of([Token::RBrace]).ignored())
                            .then(
                                token_tree()
                                    .and_is(none_of([Token::RBrace]).ignored())
                                    .and_is(none_of([Token::LBrace]).ignored())
                                    .repeated(),
                            )
                            .then(just(Token::Semi).or_not()),
                    )
                    .map_with(|(name, _), e| {
                        name.map(|name| Pattern {
                            name,
                            body: PatternBody::Net(PatternNet::default()),
                            span: Span::from(e.span()),
                        })
                    }),
            )),
        )
        .repeated()
        .collect::<Vec<Option<Pattern>>>()
        .map(|v| v.into_iter().flatten().collect::<Vec<_>>());
    let patterns = kw(Kw::Pattern)
        .or(kw(Kw::Patterns))
        .ignore_then(braced(pattern_item, Vec::new))
        .map_with(|patterns, e| Item::Patterns(PatternsBlock { patterns, span: Span::from(e.span()) }));

    // Tasks.
    let name_list = name().separated_by(just(Token::Comma)).allow_trailing().collect::<Vec<_>>();
    let binding_kind = word("a", "`a:`").to(BindingKind::Action).or(word("e", "`e:`").to(BindingKind::Event));
    let binding = binding_kind
        .then_ignore(just(Token::Colon))
        .then(name())
        .then_ignore(just(Token::Arrow))
        .then(name().separated_by(just(Token::Comma)).at_least(1).collect::<Vec<_>>())
        .map_with(|((kind, target), transitions), e| Binding { kind, target, transitions, span: Span::from(e.span()) });
    let task = name()
        .then(name_list.clone().delimited_by(just(Token::LParen), just(Token::RParen)))
        .then(just(Token::Colon).ignore_then(name()).or_not())
        .then(braced(semi_list(binding), Vec::new))
        .map_with(|(((name, params), pattern), bindings), e| TaskDef {
            name,
            params,
            pattern,
            bindings,
            span: Span::from(e.span()),
        })
        .boxed();
    let task_item = none_of([Token::RBrace])
        .rewind()
        .ignore_then(
            task.map(Some).recover_with(via_parser(
                // A broken task keeps its name, so that its calls are not
                // reported as undefined (the checker skips its checks).
                name()
                    .or_not()
                    .rewind()
                    .then(
                        token_tree()
                            .and_is(none_of([Token::RBrace]).ignored())
                            .then(token_tree().and_is(none_of([Token::RBrace, Token::LBrace]).ignored()).repeated())
                            .then(token_tree().and_is(just(Token::LBrace).ignored()).or_not()),
                    )
                    .map_with(|(name, _), e| {
                        name.map(|name| TaskDef {
                            name,
                            params: Vec::new(),
                            pattern: None,
                            bindings: Vec::new(),
                            span: Span::from(e.span()),
                        })
                    }),
            )),
        )
        .repeated()
        .collect::<Vec<Option<TaskDef>>>()
        .map(|v| v.into_iter().flatten().collect::<Vec<_>>());
    let tasks = kw(Kw::Tasks)
        .ignore_then(braced(task_item, Vec::new))
        .map_with(|tasks, e| Item::Tasks(TasksBlock { tasks, span: Span::from(e.span()) }));

    // Missions.
    let body = braced(block(stmt().boxed(), &CLOSERS), || empty_block(Span::default())).map_with(|mut b: Block, e| {
        if b.span == Span::default() {
            b.span = Span::from(e.span());
        }
        b
    });
    let params = name_list
        .delimited_by(just(Token::LParen), just(Token::RParen))
        .recover_with(via_parser(
            just(Token::LParen).ignore_then(token_tree().repeated()).then_ignore(just(Token::RParen)).to(Vec::new()),
        ))
        .map_with(|p, e| (p, Span::from(e.span())));
    let placement = name()
        .then_ignore(word("at", "`at`"))
        .then(number())
        .delimited_by(just(Token::LBracket), just(Token::RBracket))
        .map_with(|p, e| (p, Span::from(e.span())));
    let starts_item = any().filter(|t: &Token<'_>| matches!(t, Token::Kw(k) if k.starts_item()));
    // Anything else before the body's `{` is reported once and skipped, so
    // that the body is still parsed.
    let junk = any()
        .filter(|t: &Token<'_>| *t != Token::LBrace && !matches!(t, Token::Kw(k) if k.starts_item()))
        .map_with(|t, e| (t, e.span()))
        .rewind()
        .then_ignore(
            token_tree().and_is(none_of([Token::LBrace]).ignored()).and_is(starts_item.not()).repeated().at_least(1),
        )
        .validate(|(t, span), _, emitter| {
            emitter.emit(R::custom(span, custom(codes::UNEXPECTED_TOKEN, format!("expected `{{`, found {t}"), "")));
        });
    // Every part of the header is parsed as optional, and the combination
    // is checked afterwards: a malformed header is one error, and the
    // mission is kept.
    // `mission : while { ... }`: a keyword where the name goes is one error,
    // and the mission keeps it as its name.
    let kw_name =
        any().filter(|t: &Token<'_>| matches!(t, Token::Kw(k) if !k.starts_item())).validate(|t, e, emitter| {
            let text = match t {
                Token::Kw(k) => k.as_str(),
                _ => "",
            };
            emitter.emit(R::custom(
                e.span(),
                custom(
                    codes::UNEXPECTED_TOKEN,
                    format!("`{text}` is a keyword and cannot be a mission's name"),
                    "choose another name",
                ),
            ));
            Name { text: text.to_string(), span: Span::from(e.span()) }
        });
    let header = just(Token::Colon)
        .map_with(|_, e| Span::from(e.span()))
        .or_not()
        .then(name().or(kw_name).or_not())
        .then(params.or_not())
        .then(placement.or_not())
        .then_ignore(junk.or_not())
        .boxed();
    let mission = kw(Kw::Mission)
        .to(MissionKind::Mission)
        .or(kw(Kw::PlanOp).to(MissionKind::PlanOp))
        .map_with(|k, e| (k, Span::from(e.span())))
        .then(header)
        .then(body.clone())
        .validate(|(((kind, keyword_span), (((colon, name), params), placement)), body), e, emitter| {
            let mut error = |span: Span, msg: &str, help: &str| {
                emitter.emit(R::custom(SimpleSpan::from(span.range()), custom(codes::UNEXPECTED_TOKEN, msg, help)));
            };
            let name_span = name.as_ref().map(|n: &Name| n.span);
            match kind {
                MissionKind::Mission => {
                    if let (Some(c), None) = (colon, &name) {
                        error(c, "expected the mission's name after `:`", "write `mission : name { ... }`");
                    }
                    if let (Some(_), Some((_, ps))) = (colon, &params) {
                        error(*ps, "a named mission has no parameters", "a parametrised mission is written without `:`: `mission Name( x, y ) { ... }`");
                    }
                    if let (None, Some(ns), None) = (colon, name_span, &params) {
                        error(ns, "expected `:` before the mission's name", "write `mission : name { ... }`, or `mission Name( ... ) { ... }` for a parametrised mission");
                    }
                    if let (None, None, Some((_, ps))) = (colon, name_span, &params) {
                        error(*ps, "a parametrised mission needs a name", "write `mission Name( x, y ) { ... }`");
                    }
                    if let (Some((_, ps)), true) = (&placement, colon.is_none() || params.is_some()) {
                        error(*ps, "`[ ID at NUM ]` follows the name of a named mission", "write `mission : name [ ID at NUM ] { ... }`");
                    }
                }
                MissionKind::PlanOp => {
                    if let Some(c) = colon {
                        error(c, "`mcl_plan_op` is followed by the operator's name, without `:`", "write `mcl_plan_op Name( x, y ) { ... }`");
                    }
                    match (name_span, &params) {
                        (None, _) => error(Span::at(keyword_span.end as usize), "expected the operator's name after `mcl_plan_op`", "write `mcl_plan_op Name( x, y ) { ... }`"),
                        (Some(ns), None) => error(Span::at(ns.end as usize), "expected the operator's parameters `( ... )`", "an operator without parameters is written `mcl_plan_op Name() { ... }`"),
                        _ => {}
                    }
                    if let Some((_, ps)) = &placement {
                        error(*ps, "an operator has no `[ ID at NUM ]` part", "remove it");
                    }
                }
            }
            let (params, _) = params.unwrap_or_default();
            let placement = placement.map(|(p, _)| p);
            Item::Mission(Mission { kind, keyword_span, name, params, placement, body, span: Span::from(e.span()) })
        });

    // Constraints.
    let label_ref = name().then(just(Token::Colon).ignore_then(name()).or_not()).map_with(|(a, b), e| match b {
        Some(label) => LabelRef { mission: Some(a), label, span: Span::from(e.span()) },
        None => LabelRef { mission: None, label: a, span: Span::from(e.span()) },
    });
    let refs = label_ref.separated_by(just(Token::Comma)).allow_trailing().collect::<Vec<_>>();
    let constraint_kw = choice((
        word("mutex", "`mutex`").map(|s| (ConstraintKind::Mutex, s, false)),
        word("_mutex_", "`_mutex_`").map(|s| (ConstraintKind::Mutex, s, true)),
        word("order", "`order`").map(|s| (ConstraintKind::Order, s, false)),
        word("_order_", "`_order_`").map(|s| (ConstraintKind::Order, s, true)),
        word("sync", "`sync`").map(|s| (ConstraintKind::Sync, s, false)),
        word("_sync_", "`_sync_`").map(|s| (ConstraintKind::Sync, s, true)),
    ))
    .labelled("`mutex`, `order` or `sync`");
    let constraint = constraint_kw
        .clone()
        .then(braced(refs, Vec::new))
        .then(just(Token::Eq).ignore_then(number()).or_not())
        .then_ignore(just(Token::Semi).or_not())
        .map_with(|(((kind, keyword_span, bnf_spelling), refs), bound), e| Constraint {
            kind,
            keyword_span,
            bnf_spelling,
            refs,
            bound,
            span: Span::from(e.span()),
        });
    let constraint_item = none_of([Token::RBrace])
        .rewind()
        .ignore_then(
            constraint.map(Some).recover_with(via_parser(
                // Skip to the next constraint keyword, `;` (included) or `}`.
                token_tree()
                    .and_is(none_of([Token::RBrace]).ignored())
                    .then(
                        token_tree()
                            .and_is(none_of([Token::RBrace, Token::Semi]).ignored())
                            .and_is(constraint_kw.clone().not())
                            .repeated(),
                    )
                    .then(just(Token::Semi).or_not())
                    .to(None),
            )),
        )
        .repeated()
        .collect::<Vec<Option<Constraint>>>()
        .map(|v| v.into_iter().flatten().collect::<Vec<_>>());
    let constraints = kw(Kw::Constraints)
        .ignore_then(braced(constraint_item, Vec::new))
        .map_with(|constraints, e| Item::Constraints(ConstraintsBlock { constraints, span: Span::from(e.span()) }));

    let item = choice((
        import.boxed(),
        actions.boxed(),
        events.boxed(),
        patterns.boxed(),
        tasks.boxed(),
        mission.boxed(),
        constraints.boxed(),
        planning_item().boxed(),
        pddl_map_item().boxed(),
    ))
    .labelled("item");
    let skip_item = token_tree()
        .then(token_tree().and_is(starts_item.not()).repeated())
        .map_with(|_, e| {
            let _ = e.span();
        })
        .to(None);
    let before_limit = any()
        .try_map_with(|_, e| {
            let span: SimpleSpan = e.span();
            let limit: &mut SimpleState<usize> = e.state();
            if span.start >= **limit {
                Err(R::custom(span, String::new()))
            } else {
                Ok(())
            }
        })
        .rewind();
    let items = before_limit
        .ignore_then(item.map(Some).recover_with(via_parser(skip_item)))
        .repeated()
        .collect::<Vec<Option<Item>>>()
        .map(|v| SourceFile { items: v.into_iter().flatten().collect() });
    if one_item {
        items.then_ignore(any()).then_ignore(end()).boxed()
    } else {
        items.then_ignore(end()).boxed()
    }
}

// ---------------------------------------------------------------------------
// Errors.

fn describe_expected(expected: &[RichPattern<'_, Token<'_>>]) -> String {
    let mut names: Vec<String> = expected
        .iter()
        .filter_map(|p| match p {
            RichPattern::Token(t) => Some(format!("{}", &**t)),
            RichPattern::Label(l) => Some(l.to_string()),
            RichPattern::Identifier(i) => Some(format!("`{i}`")),
            RichPattern::EndOfInput => Some("end of file".to_string()),
            _ => None,
        })
        .collect();
    names.sort();
    names.dedup();
    match names.len() {
        0 => "something else".to_string(),
        1 => names.remove(0),
        _ => {
            let last = names.pop().expect("len >= 2");
            format!("{} or {}", names.join(", "), last)
        }
    }
}

fn rich_to_diagnostic(e: Rich<'_, Token<'_>, SimpleSpan>) -> Diagnostic {
    let span = Span::from(*e.span());
    match e.reason() {
        RichReason::Custom(msg) => {
            let mut parts = msg.splitn(3, '\u{1}');
            let code = parts.next().unwrap_or(codes::UNEXPECTED_TOKEN);
            let code = [codes::EMPTY_BLOCK, codes::MISSING_COMMAND, codes::UNEXPECTED_TOKEN]
                .into_iter()
                .find(|c| *c == code)
                .unwrap_or(codes::UNEXPECTED_TOKEN);
            let message = parts.next().unwrap_or("syntax error").to_string();
            let mut d = Diagnostic::error(code, message, span);
            if let Some(help) = parts.next().filter(|h| !h.is_empty()) {
                d = d.with_help(help);
            }
            d
        }
        RichReason::ExpectedFound { expected, found } => {
            let expected_s = describe_expected(expected);
            let found_s = match found {
                Some(t) => format!("{}", &**t),
                None => "end of file".to_string(),
            };
            let mut d =
                Diagnostic::error(codes::UNEXPECTED_TOKEN, format!("expected {expected_s}, found {found_s}"), span)
                    .with_label(span, format!("unexpected {found_s}"));
            if let Some(Token::Kw(k)) = found.as_deref() {
                if expected.iter().any(|p| matches!(p, RichPattern::Label(l) if l == "identifier")) {
                    d = d.with_help(format!("`{}` is a keyword and cannot be used as a name", k.as_str()));
                }
            }
            if let Some(Token::Num(_)) = found.as_deref() {
                if expected.iter().any(|p| matches!(p, RichPattern::Token(t) if **t == Token::RParen)) {
                    d = d.with_help("separate arguments with `,`");
                }
            }
            d
        }
    }
}

/// Warnings for accepted but non-canonical spellings.
fn lint_spellings(file: &SourceFile, out: &mut Vec<Diagnostic>) {
    fn block(b: &Block, out: &mut Vec<Diagnostic>) {
        for s in &b.stmts {
            stmt(s, out);
        }
    }
    fn stmt(s: &Stmt, out: &mut Vec<Diagnostic>) {
        match &s.kind {
            StmtKind::If { cond, then, otherwise, else_written_then, .. } => {
                if let Some(span) = else_written_then {
                    out.push(
                        Diagnostic::warning(
                            codes::NON_CANONICAL,
                            "the else branch of `if` is written `then`; the canonical keyword is `else`",
                            *span,
                        )
                        .with_label(*span, "accepted for compatibility with the seed's Table B.4")
                        .with_help("write `else { ... }`"),
                    );
                }
                block(cond, out);
                block(then, out);
                if let Some(o) = otherwise {
                    block(o, out);
                }
            }
            StmtKind::While { cond, body, .. } => {
                block(cond, out);
                block(body, out);
            }
            StmtKind::Parallel { branches, .. } => branches.iter().for_each(|b| block(b, out)),
            StmtKind::Try { body, catch, .. } => {
                block(body, out);
                block(catch, out);
            }
            StmtKind::Not { body, .. } => block(body, out),
            StmtKind::Monitor { body, handlers, .. } => {
                block(body, out);
                for h in handlers {
                    block(&h.condition, out);
                    block(&h.action, out);
                }
            }
            StmtKind::Call(_) | StmtKind::Error => {}
        }
    }
    for item in &file.items {
        if let Item::Mission(m) = item {
            block(&m.body, out);
        }
    }
}

// ---------------------------------------------------------------------------
// Planning: `planning { ... }` and `pddl_map { ... }` (docs/planning.md).
// Every word inside these blocks is contextual (lexed as an identifier), so
// that `type`, `goal` or `cost` stay usable as names elsewhere.

/// Skips a broken definition of a planning block: up to and including its
/// `;`, or its `{ ... }` group, never past the block's `}`.
fn plan_skip<'t, 's: 't, I, R>() -> impl Parser<'t, I, (), Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    token_tree()
        .and_is(none_of([Token::RBrace]).ignored())
        .then(token_tree().and_is(none_of([Token::RBrace, Token::LBrace, Token::Semi]).ignored()).repeated())
        .then(just(Token::Semi).ignored().or(token_tree().and_is(just(Token::LBrace).ignored())).or_not())
        .ignored()
        .boxed()
}

/// `p` repeated until the enclosing `}`, each failure skipped with [`plan_skip`].
fn plan_list<'t, 's: 't, I, R, T: 't>(p: impl Parser<'t, I, T, Ex<R>> + Clone + 't) -> Boxed<'t, 't, I, Vec<T>, Ex<R>>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    none_of([Token::RBrace])
        .rewind()
        .ignore_then(p.map(Some).recover_with(via_parser(plan_skip().map(|_| None))))
        .repeated()
        .collect::<Vec<Option<T>>>()
        .map(|v| v.into_iter().flatten().collect())
        .boxed()
}

/// `( a, b, ... )`, possibly empty.
fn plan_names<'t, 's: 't, I, R>() -> impl Parser<'t, I, Vec<Name>, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    name()
        .separated_by(just(Token::Comma))
        .allow_trailing()
        .collect::<Vec<_>>()
        .delimited_by(just(Token::LParen), just(Token::RParen))
        .boxed()
}

/// An operand: `l2.x`, `distance( a, b )`, `l1`, a number or a string.
fn plan_operand<'t, 's: 't, I, R>() -> impl Parser<'t, I, PlanOperand, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    let string = select! { Token::Str(s) => ValueKind::Str(unescape(s)) }.labelled("string");
    let literal =
        number().map(ValueKind::Number).or(string).map_with(|kind, e| Value { kind, span: Span::from(e.span()) });
    choice((
        name().then_ignore(just(Token::Dot)).then(name()).map(|(n, a)| OperandKind::Attr(n, a)),
        name().then(plan_names()).map(|(n, args)| OperandKind::Function(n, args)),
        name().map(OperandKind::Name),
        literal.map(OperandKind::Literal),
    ))
    .map_with(|kind, e| PlanOperand { kind, span: Span::from(e.span()) })
    .labelled("operand")
    .boxed()
}

/// `Mission( arg, ... )`.
fn plan_call<'t, 's: 't, I, R>() -> impl Parser<'t, I, PlanCall, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    name()
        .then(
            plan_operand()
                .separated_by(just(Token::Comma))
                .allow_trailing()
                .collect::<Vec<_>>()
                .delimited_by(just(Token::LParen), just(Token::RParen)),
        )
        .map_with(|(name, args), e| PlanCall { name, args, span: Span::from(e.span()) })
        .labelled("mission call")
        .boxed()
}

/// A fact `[not] subject relation [object]`.
fn plan_fact<'t, 's: 't, I, R>() -> impl Parser<'t, I, PlanFact, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    kw(Kw::Not)
        .or_not()
        .then(name())
        .then(name())
        .then(name().or_not())
        .map_with(|(((negated, subject), relation), object), e| PlanFact {
            negated,
            subject,
            relation,
            object,
            span: Span::from(e.span()),
        })
        .labelled("fact `entity relation [entity]`")
        .boxed()
}

/// `{ fact; ... }`
fn plan_facts<'t, 's: 't, I, R>() -> impl Parser<'t, I, Vec<PlanFact>, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    braced(semi_list(plan_fact()), Vec::new).boxed()
}

/// `planning { ... }`
fn planning_item<'t, 's: 't, I, R>() -> impl Parser<'t, I, Item, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    let end = just(Token::Semi).or_not().ignored();
    // type location { x; y; z; }  |  type robot;  |  type auv : robot;
    let attrs = braced(semi_list(name()), Vec::new).then_ignore(end).or(just(Token::Semi).to(Vec::new()));
    let ty =
        word("type", "`type`").then(name()).then(just(Token::Colon).ignore_then(name()).or_not()).then(attrs).map_with(
            |(((keyword_span, name), parent), attrs), e| {
                PlanDef::Type(PlanType { keyword_span, name, parent, attrs, span: Span::from(e.span()) })
            },
        );
    // entity location dock { x = 0; }  |  entity robot auv;
    let attr_value = name().then_ignore(just(Token::Eq)).then(value()).map_with(|(name, value), e| AttrValue {
        name,
        value,
        span: Span::from(e.span()),
    });
    let values = braced(semi_list(attr_value), Vec::new).then_ignore(end).or(just(Token::Semi).to(Vec::new()));
    let entity = word("entity", "`entity`").then(name()).then(name()).then(values).map_with(
        |(((keyword_span, ty), name), values), e| {
            PlanDef::Entity(PlanEntity { keyword_span, ty, name, values, span: Span::from(e.span()) })
        },
    );
    // function distance( zone, zone );
    let function =
        word("function", "`function`").then(name()).then(plan_names()).then_ignore(just(Token::Semi)).map_with(
            |((keyword_span, name), params), e| {
                PlanDef::Function(PlanFunction { keyword_span, name, params, span: Span::from(e.span()) })
            },
        );
    // operator move( vehicle v, location l1 ) { precond { ... } ... }
    let typed = name().then(name()).map(|(ty, name)| TypedParam { ty, name });
    let typed_params = typed
        .separated_by(just(Token::Comma))
        .allow_trailing()
        .collect::<Vec<_>>()
        .delimited_by(just(Token::LParen), just(Token::RParen));
    let expr = plan_operand()
        .then(
            select! { Token::Cmp(s) => s.to_string(), Token::Eq => "=".to_string() }
                .map_with(|op, e| (op, Span::from(e.span())))
                .labelled("comparison"),
        )
        .then(plan_operand())
        .map_with(|((left, (op, op_span)), right), e| PlanExpr { left, op, op_span, right, span: Span::from(e.span()) })
        .labelled("expression");
    let part_kind = choice((
        word("precond", "`precond`").then(plan_facts()).map(|(k, f)| (k, OpPartKind::Precond(f))),
        word("add", "`add`").then(plan_facts()).map(|(k, f)| (k, OpPartKind::Add(f))),
        word("del", "`del`").then(plan_facts()).map(|(k, f)| (k, OpPartKind::Del(f))),
        word("expression", "`expression`")
            .then(braced(semi_list(expr), Vec::new))
            .map(|(k, x)| (k, OpPartKind::Expression(x))),
        word("cost", "`cost`")
            .then(plan_operand())
            .then_ignore(just(Token::Semi))
            .map(|(k, c)| (k, OpPartKind::Cost(c))),
        word("mcl", "`mcl`").then(plan_call()).then_ignore(just(Token::Semi)).map(|(k, c)| (k, OpPartKind::Mcl(c))),
    ))
    .then_ignore(end)
    .map_with(|(keyword_span, kind), e| OpPart { keyword_span, kind, span: Span::from(e.span()) });
    let operator = word("operator", "`operator`")
        .then(name())
        .then(typed_params)
        .then(braced(plan_list(part_kind), Vec::new))
        .then_ignore(end)
        .map_with(|(((keyword_span, name), params), parts), e| {
            PlanDef::Operator(PlanOperator { keyword_span, name, params, parts, span: Span::from(e.span()) })
        });
    // initial { auv in deploy; distance( deploy, recovery ) = 5; }  |  goal { ... }
    enum Entry {
        Fact(PlanFact),
        Value(FunctionValue),
    }
    let fvalue =
        name().then(plan_names()).then_ignore(just(Token::Eq)).then(value()).map_with(|((name, args), value), e| {
            Entry::Value(FunctionValue { name, args, value, span: Span::from(e.span()) })
        });
    let entry = fvalue.or(plan_fact().map(Entry::Fact));
    let initial = word("initial", "`initial`").then(braced(semi_list(entry), Vec::new)).then_ignore(end).map_with(
        |(keyword_span, entries), e| {
            let mut facts = Vec::new();
            let mut values = Vec::new();
            for x in entries {
                match x {
                    Entry::Fact(f) => facts.push(f),
                    Entry::Value(v) => values.push(v),
                }
            }
            PlanDef::Facts(PlanFacts { keyword_span, goal: false, facts, values, span: Span::from(e.span()) })
        },
    );
    let goal = word("goal", "`goal`").then(plan_facts()).then_ignore(end).map_with(|(keyword_span, facts), e| {
        PlanDef::Facts(PlanFacts { keyword_span, goal: true, facts, values: Vec::new(), span: Span::from(e.span()) })
    });
    let def = choice((ty.boxed(), entity.boxed(), function.boxed(), operator.boxed(), initial.boxed(), goal.boxed()))
        .labelled("`type`, `entity`, `function`, `operator`, `initial` or `goal`");
    kw(Kw::Planning)
        .then(braced(plan_list(def), Vec::new))
        .map_with(|(keyword_span, defs), e| {
            Item::Planning(PlanningBlock { keyword_span, defs, span: Span::from(e.span()) })
        })
        .boxed()
}

/// `pddl_map { action( a, b ) -> Mission( b.x, 3 ); }`
fn pddl_map_item<'t, 's: 't, I, R>() -> impl Parser<'t, I, Item, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    let mapping = name()
        .then(plan_names())
        .then_ignore(just(Token::Arrow))
        .then(plan_call())
        .then_ignore(just(Token::Semi))
        .map_with(|((action, params), call), e| PddlMapping { action, params, call, span: Span::from(e.span()) })
        .labelled("mapping `action( params ) -> Mission( args );`");
    kw(Kw::PddlMap)
        .then(braced(plan_list(mapping), Vec::new))
        .map_with(|(keyword_span, maps), e| {
            Item::PddlMap(PddlMapBlock { keyword_span, maps, span: Span::from(e.span()) })
        })
        .boxed()
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
