//! Property tests: the parser never panics, always returns a tree, keeps every
//! span inside the text and on character boundaries, and accepts well-formed
//! programs without a diagnostic, whatever the layout of their trivia.

mod common;

use common::{check_invariants, sexp};
use mcl_syntax::parse;
use proptest::prelude::*;
use proptest::test_runner::Config;
use std::path::Path;
use std::sync::OnceLock;

/// Well-formed programs written for these tests, independent of examples/.
const OWN_PROGRAMS: &[&str] = &[
    r#"// A complete single-file program.
actions {
    enableGoto = GotoPrimitive( c: enable, v: way-point );
    disableGoto = GotoPrimitive( c: disable );
    enableAlarm = AlarmPrimitive( c: enable, v: 4, v: -2.5, v: "x" );
    disableAlarm = AlarmPrimitive( c: disable );
}
events { eventGotoOk; eventGotoFail; eventAlarmOk; eventAlarmFail; }
pattern {
    AchieveOneGoal {
        places { begin.1; abort.1; ok.1; fail.1; is_exe; off(1); exe; }
        transitions { TT0; TT1; T0; T1; TO(timeout); T9(30).0; }
        arcs { begin.1 -> TT0; off -> TT0; TT0 -> is_exe; is_exe → T0 (2); T0 -> ok.1; abort.1 -> TT1; }
    }
    P_FILE : nets/task.xml;
    P_STR : "nets/other task.xml";
}
tasks {
    Goto( way-point ): AchieveOneGoal {
        a: enableGoto -> T0;
        a: disableGoto -> T1, TT1;
        e: eventGotoOk -> T0;
        e: eventGotoFail -> T1;
    }
    Alarm(): AchieveOneGoal { a: enableAlarm -> T0; e: eventAlarmOk -> T1; }
}
mission : auv [ x at 3 ] {
    monitor {
        try {
            Goto( [24, 12] ) : first ;
            while ( not ( Alarm() ) ) { Goto( path[[0, 0], [1.5, -1]] ) } ;
            if ( Alarm() ) { Goto( [0, 0] ) } else { Goto( [1, 1] ) } ;
            parallel { Goto( [1, 2] ) } and { Alarm() } and { Goto( here ) } ;
            parallel { Goto( [3, 4] ) } or { Alarm() }
        } catch { Goto( home ) }
    } condition ( Alarm() ) do { Goto( home ) }
      while_condition { Alarm() } do { Goto( $x ) }
}
mission MclMove( x, y, z ) { Goto( [x, y, z] ) }
mcl_plan_op SearchOp( timeout ) { if Alarm() then { Goto( [timeout, 0] ) } ; while Alarm() do { Goto( a-b/c ) } }
constraints {
    mutex { auv:first, auv:first } = 1
    _order_ { auv : first , auv : first } ;
    sync { first }
}
"#,
    "import \"vehicle.mcl\";\nmission { Depth( 15, \"achieve\" ) ; Goto( [24, 12] ) ; Surface() ; StartRecoveryBeacon() ; }\n",
    "/* only trivia */ // and a line comment",
    "",
];

/// Every well-formed program: ours, the examples, and generated ones.
fn corpus() -> &'static [String] {
    static CORPUS: OnceLock<Vec<String>> = OnceLock::new();
    CORPUS.get_or_init(|| {
        let mut v: Vec<String> = OWN_PROGRAMS.iter().map(|s| s.to_string()).collect();
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples");
        if let Ok(rd) = std::fs::read_dir(dir) {
            let mut paths: Vec<_> =
                rd.map(|e| e.unwrap().path()).filter(|p| p.extension().is_some_and(|e| e == "mcl")).collect();
            paths.sort();
            for p in paths {
                v.push(std::fs::read_to_string(p).unwrap());
            }
        }
        for seed in 0..3 {
            v.push(mcl_syntax::gen::program(120, seed));
        }
        v
    })
}

fn fragment() -> impl Strategy<Value = &'static str> {
    proptest::sample::select(mcl_syntax::gen::MUTATION_PIECES)
}

fn floor(s: &str, i: usize) -> usize {
    let mut i = i.min(s.len());
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// One edit of a program, with positions as fractions of its length so that
/// the same edit applies to any program.
#[derive(Clone, Debug)]
enum Mutation {
    Delete { at: f64, len: usize },
    Insert { at: f64, text: &'static str },
    Duplicate { at: f64, len: usize, to: f64 },
    Truncate { at: f64 },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let at = 0.0..=1.0f64;
    prop_oneof![
        (at.clone(), 1usize..40).prop_map(|(at, len)| Mutation::Delete { at, len }),
        (at.clone(), fragment()).prop_map(|(at, text)| Mutation::Insert { at, text }),
        (at.clone(), 1usize..80, at.clone()).prop_map(|(at, len, to)| Mutation::Duplicate { at, len, to }),
        at.prop_map(|at| Mutation::Truncate { at }),
    ]
}

fn apply(src: &str, m: &Mutation) -> String {
    let pos = |f: f64| floor(src, (f * src.len() as f64) as usize);
    match *m {
        Mutation::Delete { at, len } => {
            let a = pos(at);
            let b = floor(src, a + len);
            format!("{}{}", &src[..a], &src[b..])
        }
        Mutation::Insert { at, text } => {
            let a = pos(at);
            format!("{}{}{}", &src[..a], text, &src[a..])
        }
        Mutation::Duplicate { at, len, to } => {
            let a = pos(at);
            let b = floor(src, a + len);
            let t = pos(to);
            format!("{}{}{}", &src[..t], &src[a..b], &src[t..])
        }
        Mutation::Truncate { at } => src[..pos(at)].to_string(),
    }
}

/// `cases` by default; `PROPTEST_CASES=N` runs N cases instead (for a longer
/// search, e.g. in release mode).
fn config(cases: u32) -> Config {
    let cases = std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(cases);
    Config { cases, failure_persistence: None, ..Config::default() }
}

proptest! {
    #![proptest_config(config(512))]

    #[test]
    fn random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let src = String::from_utf8_lossy(&bytes);
        let p = parse(&src);
        check_invariants(&src, &p);
    }

    #[test]
    fn random_text(src in "\\PC{0,300}") {
        let p = parse(&src);
        check_invariants(&src, &p);
    }

    #[test]
    fn token_soup(parts in proptest::collection::vec((fragment(), proptest::sample::select(&[" ", "", "\n", " /*x*/ "][..])), 0..120)) {
        let src: String = parts.iter().flat_map(|(t, sep)| [*t, *sep]).collect();
        let p = parse(&src);
        check_invariants(&src, &p);
    }
}

proptest! {
    #![proptest_config(config(384))]

    #[test]
    fn mutated_programs(which in any::<prop::sample::Index>(), edits in proptest::collection::vec(mutation(), 1..5)) {
        let corpus = corpus();
        let mut src = corpus[which.index(corpus.len())].clone();
        for m in &edits {
            src = apply(&src, m);
        }
        let p = parse(&src);
        check_invariants(&src, &p);
    }

    /// A missing brace anywhere in a well-formed program gives one or two
    /// errors, never a cascade.
    #[test]
    fn one_deleted_brace_is_one_or_two_errors(which in any::<prop::sample::Index>(), nth in any::<prop::sample::Index>()) {
        let corpus = corpus();
        let src = &corpus[which.index(corpus.len())];
        let lexed = mcl_syntax::lexer::lex(src);
        let braces: Vec<_> = lexed.tokens.iter().filter(|(t, _)| matches!(t, mcl_syntax::lexer::Token::RBrace)).map(|(_, s)| *s).collect();
        if braces.is_empty() {
            return Ok(());
        }
        let span = braces[nth.index(braces.len())];
        let mutated = format!("{}{}", &src[..span.start as usize], &src[span.end as usize..]);
        let p = parse(&mutated);
        check_invariants(&mutated, &p);
        let errors = p.errors.iter().filter(|d| d.is_error()).count();
        prop_assert!((1..=2).contains(&errors), "{} errors:\n{}", errors, common::render_errors(&mutated, &p));
    }

    /// Well-formed programs give no diagnostic, and adding trivia between
    /// their tokens changes nothing in the tree.
    #[test]
    fn well_formed_programs_with_any_trivia(which in any::<prop::sample::Index>(), trivia in proptest::collection::vec((any::<prop::sample::Index>(), proptest::sample::select(&[" ", "\n", "\t", "\r\n", "/**/", "/* é → */", "// c\n", "//\n"][..])), 0..40)) {
        let corpus = corpus();
        let src = &corpus[which.index(corpus.len())];
        let p = parse(src);
        check_invariants(src, &p);
        prop_assert!(p.errors.is_empty(), "{}", common::render_errors(src, &p));
        let lexed = mcl_syntax::lexer::lex(src);
        if lexed.tokens.is_empty() {
            return Ok(());
        }
        // Insert trivia after randomly chosen tokens, from the end so that
        // earlier positions stay valid.
        let mut at: Vec<(usize, &str)> = trivia.iter().map(|(i, t)| (lexed.tokens[i.index(lexed.tokens.len())].1.end as usize, *t)).collect();
        at.sort_by_key(|a| std::cmp::Reverse(a.0));
        let mut text = src.clone();
        for (pos, t) in at {
            text.insert_str(pos, t);
        }
        let q = parse(&text);
        check_invariants(&text, &q);
        prop_assert!(q.errors.is_empty(), "{}", common::render_errors(&text, &q));
        prop_assert_eq!(sexp(&q.file), sexp(&p.file));
    }

    #[test]
    fn generated_programs_are_well_formed(lines in 10usize..400, seed in any::<u64>()) {
        let src = mcl_syntax::gen::program(lines, seed);
        let p = parse(&src);
        check_invariants(&src, &p);
        prop_assert!(p.errors.is_empty(), "{}", common::render_errors(&src, &p));
    }
}
