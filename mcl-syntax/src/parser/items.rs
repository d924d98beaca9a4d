//! Cutting a file into its top-level items ([`split_items`]), and cutting
//! it again after an edit, lexing only around the edit
//! ([`split_items_edit`]). The boundaries are the ones delimiter balancing
//! finds ([`super::balance`]), so that parsing the items one by one gives
//! what parsing the whole file gives.

use super::balance::{closer_of, is_closer, starts_item_here};
use crate::lexer::{Kw, Token};

/// The bounds of one top-level item of a file, as found by [`split_items`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ItemBounds {
    /// Byte offset of the item's first token (0 for the prelude).
    pub start: usize,
    /// Byte offset of the next item's first token, or the file's length.
    pub end: usize,
    /// The keyword that starts the next item and its length as written
    /// (`None` for the last item): [`super::parse_item`] needs it to report what
    /// follows the item exactly as [`super::parse`] does.
    pub next: Option<(Kw, u32)>,
}

/// Splits a file into its top-level items: the prelude (whatever comes
/// before the first item: trivia, or text that is no item), then one part per
/// item, from its keyword to the next item's keyword. Item boundaries are the
/// ones of [`super::parse`]: a top-level keyword at depth 0, or one that closes the
/// open blocks (delimiter balancing). Parsing every part with [`super::parse_item`]
/// and shifting the results by `start` gives what [`super::parse`] gives (tested on
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
