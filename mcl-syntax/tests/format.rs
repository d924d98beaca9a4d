//! Tests of the formatter (`mcl_syntax::format`): on every example, on
//! generated programs and on property-generated layouts with comments
//! anywhere, formatting keeps the tree (compared with every span erased),
//! keeps every comment, gives a text without errors, and is idempotent. Plus
//! the style itself, case by case, and a snapshot of a formatted example.

use mcl_syntax::format::{comment_text, format, FormatError};
use mcl_syntax::lexer::{lex, Kw, Token};
use mcl_syntax::{parse, Parse};
use proptest::prelude::*;
use proptest::test_runner::Config;
use std::path::{Path, PathBuf};

// ---------------------------------------------------------------------------
// The promise, checked independently of the formatter's own self-check.

/// `Debug` of the tree with every span erased and the accepted spellings made
/// canonical: an independent oracle (it does not use `format::normalize`).
fn shape(p: &Parse) -> String {
    let dbg = format!("{:#?}", p.file);
    let mut out = String::with_capacity(dbg.len());
    let mut rest = dbg.as_str();
    // `Span { start: 1, end: 2 }` is written over several lines by `{:#?}`.
    while let Some(i) = rest.find("Span {") {
        out.push_str(&rest[..i]);
        let close = rest[i..].find('}').expect("a span closes") + i;
        out.push_str("Span");
        rest = &rest[close + 1..];
    }
    out.push_str(rest);
    let out = out.replace("bnf_spelling: true", "bnf_spelling: false");
    // `else_written_then: Some(\n Span,\n ),` becomes `None,`.
    let mut norm = String::with_capacity(out.len());
    let mut lines = out.lines().peekable();
    while let Some(l) = lines.next() {
        if l.trim_start().starts_with("else_written_then: Some(") {
            let indent = &l[..l.len() - l.trim_start().len()];
            norm.push_str(indent);
            norm.push_str("else_written_then: None,\n");
            for l2 in lines.by_ref() {
                if l2.trim() == ")," {
                    break;
                }
            }
        } else {
            norm.push_str(l);
            norm.push('\n');
        }
    }
    norm
}

fn comments(src: &str, p: &Parse) -> Vec<String> {
    let mut v: Vec<String> = p.comments.iter().map(|c| comment_text(src, c.kind, c.span)).collect();
    v.sort();
    v
}

/// Formats `src` (which must parse without errors) and checks every property;
/// returns the formatted text.
fn check(name: &str, src: &str) -> String {
    let before = parse(src);
    assert!(!before.errors.iter().any(|d| d.is_error()), "{name}: the input has errors: {:?}", before.errors);
    let out = match format(src) {
        Ok(o) => o,
        Err(e) => panic!("{name}: {e}\n--- input ---\n{src}"),
    };
    let after = parse(&out);
    assert!(
        after.errors.iter().all(|d| !d.is_error()),
        "{name}: the output has errors: {:?}\n--- output ---\n{out}",
        after.errors
    );
    assert!(
        after.errors.is_empty(),
        "{name}: the output has warnings (non-canonical spellings): {:?}\n--- output ---\n{out}",
        after.errors
    );
    assert_eq!(shape(&before), shape(&after), "{name}: the tree changed\n--- input ---\n{src}\n--- output ---\n{out}");
    assert_eq!(comments(src, &before), comments(&out, &after), "{name}: comments changed\n--- output ---\n{out}");
    let again = format(&out).unwrap_or_else(|e| panic!("{name}: formatting the output failed: {e}\n{out}"));
    if again != out {
        panic!("{name}: not idempotent\n--- input ---\n{src}\n--- first ---\n{out}\n--- second ---\n{again}");
    }
    for (i, l) in out.lines().enumerate() {
        assert!(!l.ends_with(' ') && !l.ends_with('\t'), "{name}: trailing white space on line {}: {l:?}", i + 1);
        assert!(!l.contains('\t') || l.contains("//") || l.contains("/*"), "{name}: a tab on line {}", i + 1);
    }
    assert!(out.is_empty() || (out.ends_with('\n') && !out.ends_with("\n\n")), "{name}: ends with one newline");
    assert!(!out.contains("\n\n\n"), "{name}: two blank lines in a row\n{out}");
    assert!(!out.contains('→'), "{name}: non-canonical arrow kept");
    out
}

fn examples() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples");
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("examples/")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "mcl"))
        .collect();
    v.sort();
    assert!(v.len() >= 8, "the example corpus is missing");
    v
}

#[test]
fn every_example() {
    for p in examples() {
        let src = std::fs::read_to_string(&p).expect("read");
        check(&p.display().to_string(), &src);
    }
}

#[test]
fn generated_programs() {
    for (lines, seed) in [(400, 0), (800, 1), (1500, 2), (3000, 3)] {
        let src = mcl_syntax::gen::program(lines, seed);
        let out = check(&format!("gen({lines}, {seed})"), &src);
        // The generator writes the canonical style but for its BNF spellings
        // and its packed definitions.
        assert!(out.lines().count() >= src.lines().count());
    }
}

#[test]
fn snapshot_of_a_formatted_example() {
    let src = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/appendix-c.mcl"))
        .expect("read");
    insta::assert_snapshot!("appendix_c_formatted", check("appendix-c", &src));
}

#[test]
fn syntax_errors_are_refused() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad");
    let mut n = 0;
    for e in std::fs::read_dir(dir).expect("tests/bad") {
        let p = e.expect("entry").path();
        let src = std::fs::read_to_string(&p).expect("read");
        let parsed = parse(&src);
        let errors: Vec<_> = parsed.errors.iter().filter(|d| d.is_error()).cloned().collect();
        match format(&src) {
            Err(FormatError::Syntax(got)) => {
                assert_eq!(got, errors, "{}", p.display());
                n += 1;
            }
            Ok(_) => assert!(errors.is_empty(), "{} has errors but was formatted", p.display()),
            Err(e) => panic!("{}: {e}", p.display()),
        }
    }
    assert!(n >= 20, "only {n} malformed files were refused");
}

// ---------------------------------------------------------------------------
// The style, case by case.

fn fmt(src: &str) -> String {
    check("case", src)
}

#[test]
fn definitions_one_per_line() {
    let src = r#"import "a.mcl"; import "b.mcl";
actions { go = GotoPrimitive( v: wp, c: enable, v: 4, v: -2.5, v: "s\"q" ); stop = P(c:disable,); }
events { ok; fail; }
patterns { P_X : dir/file.xml; P_Y : "nets/y.xml"; T { places { begin.1; off(1).0; p.0(2); } transitions { T0; T1(30); TO(timeout).1; } arcs { begin.1 → T0; T0 -> p (2); } } }
tasks { Goto( wp, ): T { a: go -> T0, T1; e: ok -> T1; } Void(): T { } NoPattern() { } }
constraints { _mutex_ { a, m:b, } = 2; order{m:a,n:b} _sync_ { x } ; sync { } }
"#;
    let want = r#"import "a.mcl";
import "b.mcl";

actions {
    go = GotoPrimitive( c: enable, v: wp, v: 4, v: -2.5, v: "s\"q" );
    stop = P( c: disable );
}

events {
    ok;
    fail;
}

pattern {
    P_X : dir/file.xml;
    P_Y : "nets/y.xml";
    T {
        places {
            begin.1;
            off.0(1);
            p.0(2);
        }
        transitions {
            T0;
            T1(30);
            TO.1(timeout);
        }
        arcs {
            begin.1 -> T0;
            T0 -> p (2);
        }
    }
}

tasks {
    Goto( wp ): T {
        a: go -> T0, T1;
        e: ok -> T1;
    }
    Void(): T { }
    NoPattern() { }
}

constraints {
    mutex { a, m:b } = 2
    order { m:a, n:b }
    sync { x }
    sync { }
}
"#;
    assert_eq!(fmt(src), want);
}

#[test]
fn missions_and_statements() {
    let src = r#"mission : auv [ x at 3 ] { monitor { try { A( [1, [2]], t[], "s" ) : l1 ; B() ; } catch { C() } }
 condition ( Alarm() ) do { D() } while_condition { E() ; F() } do { G() } }
mission MclMove( x, y ) { parallel { A() } and { B() ; C() } and { D() } }
mission Empty() { A() }
mcl_plan_op Op( t ) { parallel { A() } or { B() } ; not { X() } ; not ( not ( Y() ) ) }
mission { while ( parallel { A() } or { B() } ) { C() } ; if not ( A() ) then { B() } ; if (A() ; B()) { C() } }
"#;
    let want = r#"mission : auv [ x at 3 ] {
    monitor {
        try {
            A( [1, [2]], t[], "s" ) : l1 ;
            B()
        } catch {
            C()
        }
    } condition ( Alarm() ) do {
        D()
    } while_condition ( E() ; F() ) do {
        G()
    }
}

mission MclMove( x, y ) {
    parallel {
        A()
    } and {
        B() ;
        C()
    } and {
        D()
    }
}

mission Empty() {
    A()
}

mcl_plan_op Op( t ) {
    parallel {
        A()
    } or {
        B()
    } ;
    not ( X() ) ;
    not ( not ( Y() ) )
}

mission {
    while (
        parallel {
            A()
        } or {
            B()
        }
    ) {
        C()
    } ;
    if ( not ( A() ) ) {
        B()
    } ;
    if ( A() ; B() ) {
        C()
    }
}
"#;
    assert_eq!(fmt(src), want);
}

#[test]
fn comments_stay_in_place() {
    let src = r#"// header

// second paragraph
actions { // after brace
    // before a
    a = P( c: x ); // after a
    /* block before b */ b = P( c: y /* inline */ );


    // two blank lines above became one
} // after actions
/* between items */
mission {
    A() // after A, before ;
    ; B( 1, // after 1
    2 ) ;
    if ( C() ) { D() } // after if block
    else { E() } ;
    F() ; // dropped semicolon before
}
// at the end
"#;
    let want = r#"// header

// second paragraph
actions { // after brace
    // before a
    a = P( c: x ); // after a
    /* block before b */ b = P( c: y /* inline */ );

    // two blank lines above became one
} // after actions

/* between items */
mission {
    A() ; // after A, before ;
    B( 1, // after 1
        2 ) ;
    if ( C() ) {
        D()
    } // after if block
    else {
        E()
    } ;
    F() // dropped semicolon before
}
// at the end
"#;
    assert_eq!(fmt(src), want);
}

#[test]
fn warnings_do_not_prevent_formatting() {
    let src = "mission { if ( A() ) { B() } then { C() } }";
    assert!(!parse(src).errors.is_empty());
    assert_eq!(fmt(src), "mission {\n    if ( A() ) {\n        B()\n    } else {\n        C()\n    }\n}\n");
}

#[test]
fn crlf_and_odd_whitespace() {
    let src = "mission {\r\n\tA() ;   // c  \r\n\r\n\r\n\tB() /* x\r\n y */\r\n}\r\n";
    assert_eq!(fmt(src), "mission {\n    A() ; // c\n\n    B() /* x\n y */\n}\n");
}

// ---------------------------------------------------------------------------
// Property tests: random layouts, comments in every gap, accepted spellings.

/// Well-formed programs with every construct and spelling.
const OWN: &[&str] = &[
    r#"import "v.mcl";
actions { go = P( c: enable, v: wp, v: -2, v: 1.5, v: "x" ); stop = P( c: disable ); }
events { ok; fail; }
pattern {
    T { places { begin.1; abort.1; ok.1; fail.1; off(1); p(2).0; } transitions { T0; T1(30); TO(timeout); } arcs { begin.1 -> T0; T0 -> ok.1 (2); } }
    P_F : a/b.xml; P_S : "c d.xml";
}
tasks { Goto( wp, timeout ): T { a: go -> T0; a: stop -> T1, TO; e: ok -> T1; } Void(): T { } }
mission : auv [ x at 3 ] {
    monitor {
        try { Goto( [24, 12], 5 ) : first ; while ( not ( Void() ) ) { Goto( path[[0, 0], [1.5, -1]], t ) } ;
            if ( Void() ) { Void() } else { Void() } ; parallel { Void() } and { Void() } and { Void() } ;
            parallel { Void() } or { Void() } ; }
        catch { Void() }
    } condition ( Void() ) do { Void() } while_condition { Void() } do { Void() }
}
mission Move( x ) { Goto( [x], 1 ) }
mcl_plan_op Op( t ) { if Void() then { Void() } ; while Void() do { Void() } ; if ( Void() ) then { Void() } then { Void() } ;
  monitor { Void() } condition Void() ; Void() do { Void() } ; not { Void() } }
constraints { mutex { auv:first, auv:first } = 1 _order_ { auv : first , auv : first } ; sync { first } _mutex_ { a } = 2; _sync_ { a, b, } }
"#,
    "mission { A() }",
    "/* only trivia */ // and a line comment",
    "",
];

fn programs() -> Vec<String> {
    let mut v: Vec<String> = OWN.iter().map(|s| s.to_string()).collect();
    for p in examples() {
        v.push(std::fs::read_to_string(p).expect("read"));
    }
    v.push(mcl_syntax::gen::program(100, 11));
    v
}

/// What to put in one gap between two tokens.
#[derive(Clone, Debug)]
enum Gap {
    Space,
    Newline,
    Blank,
    Line(u8),
    Block(u8),
    BlockNl(u8),
}

fn gap() -> impl Strategy<Value = Gap> {
    prop_oneof![
        6 => Just(Gap::Space),
        3 => Just(Gap::Newline),
        1 => Just(Gap::Blank),
        1 => any::<u8>().prop_map(Gap::Line),
        1 => any::<u8>().prop_map(Gap::Block),
        1 => any::<u8>().prop_map(Gap::BlockNl),
    ]
}

/// Re-lays out `src` token by token: the gaps come from `gaps` (cycled), the
/// existing comments are kept, arrows and `pattern` take their other spelling
/// when `alt` says so.
fn relayout(src: &str, gaps: &[Gap], alt: &[bool]) -> String {
    let lexed = lex(src);
    let mut pieces: Vec<(usize, String)> = Vec::new();
    for (i, (t, s)) in lexed.tokens.iter().enumerate() {
        let text = &src[s.range()];
        let flip = alt.get(i % alt.len().max(1)).copied().unwrap_or(false);
        let text = match t {
            Token::Arrow if flip => "→".to_string(),
            Token::Kw(Kw::Pattern) if flip => "patterns".to_string(),
            _ => text.to_string(),
        };
        pieces.push((s.start as usize, text));
    }
    for c in &lexed.comments {
        let text = &src[c.span.range()];
        let text = if text.starts_with("//") { format!("{text}\n") } else { text.to_string() };
        pieces.push((c.span.start as usize, text));
    }
    pieces.sort_by_key(|(p, _)| *p);
    let mut out = String::new();
    for (i, (_, text)) in pieces.iter().enumerate() {
        if i > 0 {
            match &gaps[i % gaps.len()] {
                Gap::Space => out.push(' '),
                Gap::Newline => out.push('\n'),
                Gap::Blank => out.push_str("\n\n"),
                Gap::Line(n) => out.push_str(&format!(" // c{n}\n")),
                Gap::Block(n) => out.push_str(&format!(" /* b{n} */ ")),
                Gap::BlockNl(n) => out.push_str(&format!("\n/* m{n}\n   more */\n")),
            }
        }
        out.push_str(text);
    }
    out
}

fn cases() -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(200)
}

proptest! {
    // PROPTEST_CASES=5000 for a longer run.
    #![proptest_config(Config { cases: cases(), failure_persistence: None, ..Config::default() })]

    #[test]
    fn random_layouts_keep_everything(
        which in 0usize..64,
        gaps in proptest::collection::vec(gap(), 1..40),
        alt in proptest::collection::vec(any::<bool>(), 1..8),
    ) {
        let ps = programs();
        let src = relayout(&ps[which % ps.len()], &gaps, &alt);
        check("relayout", &src);
    }

    #[test]
    fn generated_programs_with_comments(
        seed in any::<u64>(),
        gaps in proptest::collection::vec(gap(), 1..20),
    ) {
        let src = relayout(&mcl_syntax::gen::program(60, seed), &gaps, &[false]);
        check("gen", &src);
    }
}
