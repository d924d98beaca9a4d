//! The tree-sitter grammar of `editors/tree-sitter-mcl` (its generated parser,
//! committed, compiled by the `tree-sitter-mcl` crate) against the reference
//! parser `mcl-syntax`: every example parses without an ERROR or MISSING
//! node; both parsers agree on which files are valid (the examples, the
//! malformed corpus, generated programs, and single-token mutations of them);
//! the corpus tests of `test/corpus/*.txt` hold (as `tree-sitter test` checks
//! them, without needing the CLI); the queries compile and capture what they
//! should.

use proptest::prelude::*;
use proptest::test_runner::Config;
use std::path::{Path, PathBuf};
use tree_sitter::{Language, Node, Parser, Query, QueryCursor, StreamingIterator, Tree};

fn language() -> Language {
    tree_sitter_mcl::LANGUAGE.into()
}

fn ts_parse(text: &str) -> Tree {
    let mut parser = Parser::new();
    parser.set_language(&language()).expect("load the MCL grammar");
    parser.parse(text, None).expect("a tree")
}

/// The first ERROR or MISSING node, as `kind at line:col`.
fn first_error(node: Node<'_>) -> Option<String> {
    if node.is_error() || node.is_missing() {
        let p = node.start_position();
        return Some(format!(
            "{} at {}:{}",
            if node.is_missing() { "MISSING" } else { "ERROR" },
            p.row + 1,
            p.column + 1
        ));
    }
    if !node.has_error() {
        return None;
    }
    let mut cursor = node.walk();
    let children: Vec<Node<'_>> = node.children(&mut cursor).collect();
    children.into_iter().find_map(first_error)
}

/// Whether mcl-syntax reports a syntax error (warnings do not count).
fn mcl_invalid(text: &str) -> bool {
    mcl_syntax::parse(text).errors.iter().any(|d| d.is_error())
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn mcl_files(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "mcl"))
        .collect();
    v.sort();
    v
}

#[test]
fn every_example_parses_without_error() {
    let files = mcl_files(&root().join("examples"));
    assert!(files.len() >= 8);
    for p in files {
        let text = std::fs::read_to_string(&p).expect("read");
        assert!(!mcl_invalid(&text), "{}: mcl-syntax rejects an example", p.display());
        let tree = ts_parse(&text);
        if let Some(e) = first_error(tree.root_node()) {
            panic!("{}: {e}\n{}", p.display(), tree.root_node().to_sexp());
        }
    }
}

#[test]
fn the_malformed_corpus_is_rejected_by_both() {
    let files = mcl_files(&root().join("mcl-syntax/tests/bad"));
    assert!(files.len() >= 20);
    for p in files {
        let text = std::fs::read_to_string(&p).expect("read");
        let tree = ts_parse(&text);
        assert_eq!(
            mcl_invalid(&text),
            tree.root_node().has_error(),
            "{}: mcl-syntax and tree-sitter disagree\n{}",
            p.display(),
            tree.root_node().to_sexp()
        );
    }
}

#[test]
fn generated_and_formatted_programs_parse_without_error() {
    for seed in 0..4 {
        let text = mcl_syntax::gen::program(600, seed);
        assert!(first_error(ts_parse(&text).root_node()).is_none(), "gen seed {seed}");
        let formatted = mcl_syntax::format::format(&text).expect("format");
        assert!(first_error(ts_parse(&formatted).root_node()).is_none(), "formatted gen seed {seed}");
    }
}

// ---------------------------------------------------------------------------
// The corpus tests of the grammar, checked as `tree-sitter test` does.

/// Removes field names (`name:`) and normalizes white space, as
/// `tree-sitter test` does when the expected tree has no fields.
fn normalize_sexp(s: &str) -> String {
    let mut out = String::new();
    for word in s.split_whitespace() {
        if word.ends_with(':') {
            continue;
        }
        out.push_str(word);
        out.push(' ');
    }
    out.replace(" )", ")").trim().to_string()
}

#[test]
fn corpus_tests() {
    let dir = root().join("editors/tree-sitter-mcl/test/corpus");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("test/corpus")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "txt"))
        .collect();
    files.sort();
    let mut n = 0;
    for f in files {
        let text = std::fs::read_to_string(&f).expect("read");
        let lines: Vec<&str> = text.lines().collect();
        let mut i = 0;
        while i < lines.len() {
            if !lines[i].starts_with("===") {
                i += 1;
                continue;
            }
            let name = lines[i + 1].trim();
            i += 3;
            let sep = (i..lines.len()).find(|&j| lines[j].trim() == "---").expect("--- after the input");
            let input = lines[i..sep].join("\n");
            let end = (sep + 1..lines.len()).find(|&j| lines[j].starts_with("===")).unwrap_or(lines.len());
            let expected = lines[sep + 1..end].join("\n");
            let tree = ts_parse(input.trim_end());
            assert_eq!(
                normalize_sexp(&tree.root_node().to_sexp()),
                normalize_sexp(&expected),
                "{}: {name}",
                f.display()
            );
            assert!(!mcl_invalid(&input), "{}: {name}: mcl-syntax rejects a corpus example", f.display());
            n += 1;
            i = end;
        }
    }
    assert!(n >= 20, "only {n} corpus tests");
}

// ---------------------------------------------------------------------------
// Queries.

const QUERIES: &[&str] = &["highlights", "folds", "indents", "locals"];

fn query(name: &str) -> Query {
    let path = root().join(format!("editors/tree-sitter-mcl/queries/{name}.scm"));
    let src = std::fs::read_to_string(&path).expect("read query");
    // Portable queries: no editor-specific predicates.
    for pred in ["#lua-match?", "#any-of?", "#contains?", "#set!", "#offset!", "#vim-match?", "#not-"] {
        assert!(!src.contains(pred), "{name}.scm uses the editor-specific predicate {pred}");
    }
    Query::new(&language(), &src).unwrap_or_else(|e| panic!("{name}.scm: {e}"))
}

/// `(capture name, text)` of every capture of `q` in `text`.
fn captures(q: &Query, text: &str) -> Vec<(String, String)> {
    let tree = ts_parse(text);
    let mut cursor = QueryCursor::new();
    let mut out = Vec::new();
    let mut it = cursor.captures(q, tree.root_node(), text.as_bytes());
    while let Some((m, i)) = it.next() {
        let c = m.captures()[*i];
        out.push((q.capture_names()[c.index as usize].to_string(), text[c.node.byte_range()].to_string()));
    }
    out
}

#[test]
fn queries_compile_and_capture() {
    for q in QUERIES {
        query(q);
    }
    let text = "import \"v.mcl\";\n\
        actions { go = P( c: enable, v: wp ); }\n\
        events { ok; }\n\
        tasks { Goto( wp ): T { a: go -> T0; e: ok -> T1; } }\n\
        mission : auv { if ( Goto( [1, 2] ) : first ) { Void() } else { Void() } } // done\n\
        constraints { mutex { auv:first } = 1 }\n";
    let caps = captures(&query("highlights"), text);
    let has = |cap: &str, t: &str| caps.iter().any(|(c, x)| c == cap && x == t);
    for (cap, t) in [
        ("keyword.import", "import"),
        ("string.special.path", "\"v.mcl\""),
        ("function", "go"),
        ("constructor", "P"),
        ("keyword", "c"),
        ("constant", "ok"),
        ("function", "Goto"),
        ("variable.parameter", "wp"),
        ("type", "T"),
        ("variable.member", "T0"),
        ("keyword", "mission"),
        ("module", "auv"),
        ("keyword.conditional", "if"),
        ("keyword.conditional", "else"),
        ("function.call", "Goto"),
        ("label", "first"),
        ("constant.numeric", "1"),
        ("comment", "// done"),
        ("keyword", "mutex"),
        ("operator", "->"),
    ] {
        assert!(has(cap, t), "no @{cap} on `{t}`: {caps:?}");
    }
    let folds = captures(&query("folds"), text);
    assert!(folds.iter().any(|(c, x)| c == "fold" && x.starts_with("mission")));
    let locals = captures(&query("locals"), text);
    assert!(locals.iter().any(|(c, x)| c == "local.definition" && x == "wp"));
}

// ---------------------------------------------------------------------------
// Agreement on mutated programs.

/// Valid programs to mutate: every construct and spelling.
const PROGRAMS: &[&str] = &[r#"import "v.mcl";
actions { go = P( c: enable, v: wp, v: -2, v: 1.5, v: "x" ); stop = P( v: [1, 2], c: disable, ); }
events { ok; fail; }
pattern {
    T { places { begin.1; off(1); p(2).0; } transitions { T0; T1(30); TO(timeout); } arcs { begin.1 -> T0; T0 → ok.1 (2); } }
    P_F : a/b.xml; P_S : "c d.xml";
}
tasks { Goto( wp, timeout ): T { a: go -> T0; a: stop -> T1, TO; e: ok -> T1; } Void(): T { } }
mission : auv [ x at 3 ] {
    monitor {
        try { Goto( [24, 12], 5 ) : first ; while ( not ( Void() ) ) { Goto( path[[0, 0], [1.5, -1]], t ) } ;
            if ( Void() ) { Void() } else { Void() } ; parallel { Void() } and { Void() } ;
            parallel { Void() } or { Void() } ; }
        catch { Void() }
    } condition ( Void() ) do { Void() } while_condition { Void() } do { Void() }
}
mission Move( x ) { Goto( [x], 1 ) }
mcl_plan_op Op( t ) { if Void() then { Void() } ; while Void() do { Void() } ; if ( Void() ) then { Void() } then { Void() } ;
  monitor { Void() } condition Void() ; Void() do { Void() } ; not { Void() } }
constraints { mutex { auv:first, first } = 1 _order_ { auv : first , auv : first } ; sync { first } }
"#];

fn mutation_sources() -> Vec<String> {
    let mut v: Vec<String> = PROGRAMS.iter().map(|s| s.to_string()).collect();
    for p in mcl_files(&root().join("examples")) {
        v.push(std::fs::read_to_string(p).expect("read"));
    }
    v
}

/// Tokens that a mutation may insert.
const INSERTS: &[&str] = &[
    "{",
    "}",
    "(",
    ")",
    "[",
    "]",
    ";",
    ":",
    ",",
    ".",
    "=",
    "->",
    "x",
    "3",
    "-2",
    "\"s\"",
    "import",
    "actions",
    "events",
    "pattern",
    "tasks",
    "mission",
    "mcl_plan_op",
    "constraints",
    "places",
    "transitions",
    "arcs",
    "while",
    "if",
    "then",
    "else",
    "do",
    "parallel",
    "and",
    "or",
    "try",
    "catch",
    "not",
    "monitor",
    "condition",
    "while_condition",
    "c",
    "v",
    "a",
    "e",
    "at",
    "mutex",
    "_sync_",
    "A()",
    "007",
    "1.",
    "0.5",
    "→",
    "\"a\\\"b\"",
    "/* c */",
    "// c\n",
    "$x",
    "a/b-c",
    "@",
    "#",
];

#[derive(Clone, Debug)]
enum Mutation {
    Delete(usize),
    Duplicate(usize),
    Swap(usize),
    Insert(usize, usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        any::<usize>().prop_map(Mutation::Delete),
        any::<usize>().prop_map(Mutation::Duplicate),
        any::<usize>().prop_map(Mutation::Swap),
        (any::<usize>(), 0..INSERTS.len()).prop_map(|(i, k)| Mutation::Insert(i, k)),
    ]
}

/// The program's tokens (as written), mutated once, joined by spaces.
fn mutate(src: &str, m: &Mutation) -> String {
    let lexed = mcl_syntax::lexer::lex(src);
    let mut toks: Vec<String> = lexed.tokens.iter().map(|(_, s)| src[s.range()].to_string()).collect();
    let n = toks.len().max(1);
    match *m {
        Mutation::Delete(i) if !toks.is_empty() => {
            toks.remove(i % n);
        }
        Mutation::Duplicate(i) if !toks.is_empty() => {
            let t = toks[i % n].clone();
            toks.insert(i % n, t);
        }
        Mutation::Swap(i) if toks.len() >= 2 => toks.swap(i % (n - 1), i % (n - 1) + 1),
        Mutation::Insert(i, k) => toks.insert(i % (toks.len() + 1), INSERTS[k].to_string()),
        _ => {}
    }
    toks.join(" ")
}

fn cases() -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(300)
}

proptest! {
    #![proptest_config(Config { cases: cases(), failure_persistence: None, ..Config::default() })]

    /// A single-token change makes both parsers reject the program, or neither.
    #[test]
    fn both_parsers_agree_on_mutated_programs(which in 0usize..32, m in mutation()) {
        let srcs = mutation_sources();
        let text = mutate(&srcs[which % srcs.len()], &m);
        let tree = ts_parse(&text);
        let ts_bad = tree.root_node().has_error();
        let mcl_bad = mcl_invalid(&text);
        prop_assert_eq!(
            mcl_bad,
            ts_bad,
            "mcl-syntax {} but tree-sitter {} after {:?}:\n{}\n{:?}",
            if mcl_bad { "rejects" } else { "accepts" },
            if ts_bad { "rejects" } else { "accepts" },
            m,
            text,
            mcl_syntax::parse(&text).errors.first().map(|d| &d.message)
        );
    }
}
