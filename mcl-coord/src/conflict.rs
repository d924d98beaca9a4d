//! Constraints that conflict by construction (E0408): a `sync` whose calls
//! a `mutex` forbids to run together, or `order`s that make calls wait for
//! each other in a cycle. Found on the syntax tree, before the deadlock
//! analysis (which reports the orders' cycle too, as E0406, with a
//! counterexample).

use mcl_compiler::codes;
use mcl_syntax::{ast, Diagnostic};

/// A call named by a constraint: `mission:label` (or `:label`).
fn key(r: &ast::LabelRef) -> String {
    format!("{}:{}", r.mission.as_ref().map_or("", |m| m.text.as_str()), r.label.text)
}

/// E0408: constraints that contradict each other whatever the missions do.
///
/// * A `sync` makes its calls start together, a `mutex` with bound β lets at
///   most β of its calls run at once: a sync with more than β calls of the
///   mutex cannot be kept.
/// * An `order { a, b }` makes `b` start after `a` ended; a sync makes its
///   calls start together (so they are one node here). A cycle of orders
///   through these nodes (`order` both ways, an order inside a sync) makes
///   each call wait for another to end first: none can start.
pub fn conflicts(cs: &[ast::Constraint]) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    let arity_ok = |c: &ast::Constraint| match c.kind {
        ast::ConstraintKind::Order => c.refs.len() == 2,
        _ => c.refs.len() >= 2,
    };
    // Sync and mutex.
    for (i, s) in cs.iter().enumerate().filter(|(_, c)| c.kind == ast::ConstraintKind::Sync && arity_ok(c)) {
        for (j, m) in cs.iter().enumerate().filter(|(_, c)| c.kind == ast::ConstraintKind::Mutex && arity_ok(c)) {
            let Some(bound) = m.bound.as_ref().and_then(|b| b.as_u32()).filter(|&b| b > 0) else { continue };
            let mut common: Vec<String> =
                s.refs.iter().map(key).filter(|k| m.refs.iter().any(|r| key(r) == *k)).collect();
            common.sort();
            common.dedup();
            if common.len() as u32 <= bound {
                continue;
            }
            let list = common.iter().map(|k| format!("`{k}`")).collect::<Vec<_>>().join(", ");
            out.push(
                Diagnostic::error(
                    codes::CONFLICTING_CONSTRAINTS,
                    format!(
                        "constraints {} and {} conflict: the `sync` starts {list} together, the `mutex` lets {bound} of them run at once",
                        i + 1,
                        j + 1
                    ),
                    s.span,
                )
                .with_label(s.span, format!("constraint {}: {list} start together", i + 1))
                .with_label(m.span, format!("constraint {}: at most {bound} of {list} at once", j + 1))
                .with_note(
                    "the sync would hold the first call until the others arrive, then the mutex would hold the \
                     others until it ends: they never start together",
                )
                .with_help("remove one of the two constraints, or raise the mutex's bound"),
            );
        }
    }
    // Orders through sync classes.
    let mut keys: Vec<String> = cs.iter().flat_map(|c| c.refs.iter().map(key)).collect();
    keys.sort();
    keys.dedup();
    let idx = |k: &str| keys.binary_search_by(|x| x.as_str().cmp(k)).unwrap_or(0);
    let mut class: Vec<usize> = (0..keys.len()).collect();
    fn find(class: &mut [usize], x: usize) -> usize {
        let mut r = x;
        while class[r] != r {
            r = class[r];
        }
        class[x] = r;
        r
    }
    for s in cs.iter().filter(|c| c.kind == ast::ConstraintKind::Sync && arity_ok(c)) {
        let first = idx(&key(&s.refs[0]));
        for r in &s.refs[1..] {
            let (a, b) = (find(&mut class, first), find(&mut class, idx(&key(r))));
            class[a] = b;
        }
    }
    // Edges: (from class, to class, constraint index).
    let edges: Vec<(usize, usize, usize)> = cs
        .iter()
        .enumerate()
        .filter(|(_, c)| c.kind == ast::ConstraintKind::Order && arity_ok(c))
        .map(|(k, c)| (find(&mut class, idx(&key(&c.refs[0]))), find(&mut class, idx(&key(&c.refs[1]))), k))
        .collect();
    let mut reported: Vec<Vec<usize>> = Vec::new();
    for &(u, v, k) in &edges {
        // A path of orders from v back to u closes a cycle with k.
        let mut prev: Vec<Option<(usize, usize)>> = vec![None; keys.len()];
        let mut seen = vec![false; keys.len()];
        let mut queue = std::collections::VecDeque::from([v]);
        seen[v] = true;
        while let Some(x) = queue.pop_front() {
            if x == u {
                break;
            }
            for &(a, b, e) in &edges {
                if a == x && !seen[b] {
                    seen[b] = true;
                    prev[b] = Some((a, e));
                    queue.push_back(b);
                }
            }
        }
        if !seen[u] {
            continue;
        }
        // k, then the path from v back to u.
        let mut path = Vec::new();
        let mut x = u;
        while x != v {
            let Some((a, e)) = prev[x] else { break };
            path.push(e);
            x = a;
        }
        let cycle: Vec<usize> = std::iter::once(k).chain(path.into_iter().rev()).collect();
        let mut orders = cycle.clone();
        orders.sort_unstable();
        orders.dedup();
        // The syncs that join two calls of the cycle.
        let used: Vec<String> = orders.iter().flat_map(|&e| cs[e].refs.iter().map(key)).collect();
        let mut involved = orders.clone();
        for (j, s) in cs.iter().enumerate().filter(|(_, c)| c.kind == ast::ConstraintKind::Sync && arity_ok(c)) {
            let n = s.refs.iter().map(key).filter(|k| used.contains(k)).collect::<std::collections::BTreeSet<_>>();
            if n.len() >= 2 {
                involved.push(j);
            }
        }
        involved.sort_unstable();
        if reported.contains(&involved) {
            continue;
        }
        reported.push(involved.clone());
        let chain: Vec<String> = cycle
            .iter()
            .map(|&e| format!("`{}` ends before `{}` starts", key(&cs[e].refs[0]), key(&cs[e].refs[1])))
            .collect();
        let numbers = involved.iter().map(|j| (j + 1).to_string()).collect::<Vec<_>>();
        let first = involved[0];
        let mut d = Diagnostic::error(
            codes::CONFLICTING_CONSTRAINTS,
            format!(
                "constraints {} conflict: each of their calls waits for another one to end first",
                match numbers.split_last() {
                    Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
                    _ => numbers.join(""),
                }
            ),
            cs[first].span,
        );
        for &j in &involved {
            let what = match cs[j].kind {
                ast::ConstraintKind::Sync => "its calls start together".to_string(),
                _ => format!("`{}` ends before `{}` starts", key(&cs[j].refs[0]), key(&cs[j].refs[1])),
            };
            d = d.with_label(cs[j].span, format!("constraint {}: {what}", j + 1));
        }
        d = d
            .with_note(format!(
                "{}{}: none of these calls can ever start",
                chain.join(", "),
                if involved.len() > orders.len() { " (calls of a sync start together)" } else { "" }
            ))
            .with_help("remove one of these orders, or turn it around");
        out.push(d);
    }
    out
}
