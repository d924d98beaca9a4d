//! Coordination verdicts (E0406, W0407) that outlive edits which cannot
//! change them.
//!
//! The deadlock analysis of a file's constraints can take seconds, and the
//! salsa query that runs it (`mcl_coord::coordination_diagnostics`) is
//! recomputed after any edit of the file, even one that only moves the
//! constraints or changes a task nobody calls. The server keeps the last
//! [`Verdict`] of each file with a fingerprint of the analysis' input (the
//! missions' nets and the constraints, without source positions): while the
//! fingerprint is the same the verdict is still valid, and it is shown again
//! at once, its positions carried to where the constraints now are, without
//! running the analysis again.

use super::Analysis;
use mcl_compiler::queries::parse;
use mcl_compiler::SourceFile;
use mcl_syntax::ast::Item;
use mcl_syntax::{Diagnostic, Span};
use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};

/// A file's coordination diagnostics and what they were computed on.
#[derive(Clone, Debug)]
pub struct Verdict {
    /// The missions and constraints, without positions (see [`fingerprint`]).
    pub fingerprint: u64,
    /// Where the constraints were (see [`anchors`]).
    pub anchors: Vec<Span>,
    /// The file's text then (to carry other positions across edits).
    pub text: String,
    pub diags: Vec<Diagnostic>,
}

/// The keyword that opens a constraints block (as `mcl_coord::check` places it).
fn keyword(text: &str, block: Span) -> Span {
    let rest = text.get(block.start as usize..block.end as usize).unwrap_or("");
    match rest.find(|c: char| c.is_whitespace() || c == '{') {
        Some(n) if n > 0 => Span::new(block.start as usize, block.start as usize + n),
        _ => block,
    }
}

/// Where the constraints are written: each non-empty block, its keyword,
/// then each of its constraints, in source order (from the parse alone).
pub fn anchors(a: &Analysis<'_>, file: SourceFile) -> Vec<Span> {
    let text = a.text(file);
    let mut anchors = Vec::new();
    for item in &parse(a.db, file).file.items {
        if let Item::Constraints(b) = item {
            if !b.constraints.is_empty() {
                anchors.push(b.span);
                anchors.push(keyword(text, b.span));
                anchors.extend(b.constraints.iter().map(|c| c.span));
            }
        }
    }
    anchors
}

/// A hash of the input of the coordination analysis of `file` (its
/// missions' nets and its constraints, without source positions): `None`
/// when there is no analysis (no constraints, or errors in the program).
/// Compiles the file's missions.
pub fn fingerprint(a: &Analysis<'_>, file: SourceFile) -> Option<u64> {
    let anchors = anchors(a, file);
    if anchors.is_empty() {
        return None;
    }
    let (missions, constraints) = mcl_coord::source::load(a.db, file).ok()?;
    let mut h = DefaultHasher::new();
    anchors.len().hash(&mut h);
    for m in &missions {
        m.name.hash(&mut h);
        format!("{:?} {:?} {:?} {:?}", m.initial_places, m.final_places, m.controllable, m.activities).hash(&mut h);
        let net = &m.net;
        for p in net.places() {
            (&*p.id, &*p.name, p.initial, p.interface).hash(&mut h);
        }
        for t in net.transitions() {
            (&*t.id, &*t.name, t.priority).hash(&mut h);
            format!("{:?} {:?} {:?}", t.kind, t.actions, t.binding).hash(&mut h);
        }
        format!("{:?}", net.arcs()).hash(&mut h);
    }
    for c in &constraints {
        format!("{:?} {:?}", c.kind, c.calls).hash(&mut h);
    }
    Some(h.finish())
}

/// Runs the analysis (slow; salsa may cancel it) on the current text, whose
/// fingerprint is `fingerprint`.
pub fn compute(a: &Analysis<'_>, file: SourceFile, fingerprint: u64) -> Verdict {
    let diags = mcl_coord::coordination_diagnostics(a.db, file).iter().map(|fd| fd.diag.clone()).collect();
    Verdict { fingerprint, anchors: anchors(a, file), text: a.text(file).to_string(), diags }
}

/// The verdict's diagnostics placed in the current text: positions on the
/// constraints go to where the same constraints now are, others are
/// carried across the edit. `None` when the constraints are not the same
/// in number. Says nothing of validity (compare [`fingerprint`]s).
pub fn place(a: &Analysis<'_>, file: SourceFile, v: &Verdict, now: &[Span]) -> Option<Vec<Diagnostic>> {
    if v.anchors.len() != now.len() {
        return None;
    }
    let text = a.text(file);
    let moved = |s: Span| -> Span {
        if let Some(i) = v.anchors.iter().position(|&x| x == s) {
            return now[i];
        }
        Span::new(carry(&v.text, text, s.start as usize), carry(&v.text, text, s.end as usize))
    };
    Some(
        v.diags
            .iter()
            .map(|d| {
                let mut d = d.clone();
                d.span = moved(d.span);
                for l in d.labels.iter_mut().filter(|l| l.file.is_none()) {
                    l.span = moved(l.span);
                }
                d
            })
            .collect(),
    )
}

/// The verdict placed in the current text if it is still valid (the same
/// fingerprint), with the current text's verdict to keep in its place.
pub fn reuse(a: &Analysis<'_>, file: SourceFile, v: &Verdict, fingerprint: u64) -> Option<Verdict> {
    if v.fingerprint != fingerprint {
        return None;
    }
    let now = anchors(a, file);
    let diags = place(a, file, v, &now)?;
    Some(Verdict { fingerprint, anchors: now, text: a.text(file).to_string(), diags })
}

/// Where `offset` of `old` is in `new`: the same offset before the changed
/// part, the same distance from the end after it, the change's start inside it.
fn carry(old: &str, new: &str, offset: usize) -> usize {
    let prefix = old.bytes().zip(new.bytes()).take_while(|(a, b)| a == b).count();
    let max_suffix = old.len().min(new.len()) - prefix;
    let suffix = old.bytes().rev().zip(new.bytes().rev()).take(max_suffix).take_while(|(a, b)| a == b).count();
    let r = if offset <= prefix {
        offset
    } else if offset >= old.len() - suffix {
        new.len() - (old.len() - offset.min(old.len()))
    } else {
        prefix
    };
    let mut r = r.min(new.len());
    while !new.is_char_boundary(r) {
        r -= 1;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::fixture::Fixture;

    const CYCLE: &str = r#"actions { go = P( c: enable ); stop = P( c: disable ); }
events { eOk; eFail; }
tasks {
    T(): AchieveOneGoal { a: go -> T0; a: stop -> T1, T6, T7; e: eOk -> T2; e: eFail -> T3; }
    Unused(): Instant { }
}
mission : v1 { T() : p2 ; T() }
mission : v2 { T() : p5 ; T() }
constraints {
    order { v1:p2, v2:p5 }
    order { v2:p5, v1:p2 }
}
"#;

    #[test]
    fn a_verdict_survives_edits_that_cannot_change_it() {
        let f = Fixture::new(&[("a.mcl", CYCLE)]);
        let a = f.analysis();
        let file = f.file("a.mcl");
        let before = fingerprint(&a, file).expect("constraints");
        let v = compute(&a, file, before);
        assert_eq!(v.diags.iter().map(|d| d.code).collect::<Vec<_>>(), ["E0408", "E0406"], "{:?}", v.diags);

        // A comment above and an unused task changed: the same input, the
        // verdict moves with its constraint.
        let moved = format!("// a comment\n{}", CYCLE.replace("Unused(): Instant { }", "Unused2(): Instant { }"));
        let f2 = Fixture::new(&[("a.mcl", &moved)]);
        let a2 = f2.analysis();
        let file2 = f2.file("a.mcl");
        let now = fingerprint(&a2, file2).unwrap();
        assert_eq!(now, before);
        let kept = reuse(&a2, file2, &v, now).expect("still valid");
        let at = moved.find("order { v1:p2").unwrap();
        assert_eq!(kept.diags[0].span.start as usize, at);
        assert_eq!(kept.diags, compute(&a2, file2, now).diags);

        // A constraint removed, a mission changed: another input.
        let fixed = CYCLE.replace("    order { v2:p5, v1:p2 }\n", "");
        let f3 = Fixture::new(&[("a.mcl", &fixed)]);
        assert_ne!(fingerprint(&f3.analysis(), f3.file("a.mcl")), Some(before));
        let other = CYCLE.replace("mission : v2 { T() : p5 ; T() }", "mission : v2 { T() : p5 }");
        let f4 = Fixture::new(&[("a.mcl", &other)]);
        assert_ne!(fingerprint(&f4.analysis(), f4.file("a.mcl")), Some(before));
        // No constraints, or errors: no analysis.
        let none = CYCLE.replace("constraints {", "constraints_ {");
        let f5 = Fixture::new(&[("a.mcl", &none)]);
        assert_eq!(fingerprint(&f5.analysis(), f5.file("a.mcl")), None);
    }

    #[test]
    fn carry_keeps_offsets_outside_the_change() {
        assert_eq!(carry("abcdef", "abXXcdef", 1), 1);
        assert_eq!(carry("abcdef", "abXXcdef", 4), 6);
        assert_eq!(carry("abcdef", "aef", 3), 1);
        assert_eq!(carry("é", "", 2), 0);
    }
}
