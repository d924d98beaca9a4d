//! Pass 1 of parsing: delimiter balancing. Every `{`, `(` and `[` gets its
//! closing delimiter (one error at an unclosed opener, one per stray
//! closer); an item left open is balanced again reading its indentation;
//! constructs nested deeper than [`MAX_NESTING`] are dropped with one error.

use crate::diag::{codes, Diagnostic};
use crate::lexer::{Kw, Token};
use crate::span::Span;

/// The closing delimiter of an opening one (`None` for any other token).
pub(super) fn closer_of(t: Token<'_>) -> Option<Token<'static>> {
    match t {
        Token::LBrace => Some(Token::RBrace),
        Token::LParen => Some(Token::RParen),
        Token::LBracket => Some(Token::RBracket),
        _ => None,
    }
}

/// Whether `t` is a closing delimiter.
pub(super) fn is_closer(t: Token<'_>) -> bool {
    matches!(t, Token::RBrace | Token::RParen | Token::RBracket)
}

/// Whether `tok`, followed by `next`, looks like the start of a top-level
/// item. A keyword alone is not enough: `events { mission; }` uses a keyword
/// as a name by mistake, which must be one error, not a closed block.
pub(super) fn starts_item_here(tok: Token<'_>, next: Option<Token<'_>>) -> bool {
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
pub(super) fn balance<'s>(
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
