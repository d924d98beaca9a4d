//! Tests of every construct of the grammar (docs/language.md section 12, seed
//! Appendix C), asserting on the tree, and snapshots of the diagnostics of a
//! corpus of malformed inputs (tests/bad/*.mcl).

mod common;

use common::{block, check_invariants, render_errors, sexp};
use mcl_syntax::ast::*;
use mcl_syntax::lexer::{CommentKind, Kw};
use mcl_syntax::{parse, LineIndex, Parse, Severity, Span};
use std::path::{Path, PathBuf};

/// Parses `src`, which must give no diagnostic at all.
fn ok(src: &str) -> Parse {
    let p = parse(src);
    check_invariants(src, &p);
    assert!(p.errors.is_empty(), "unexpected diagnostics:\n{}\nin:\n{src}", render_errors(src, &p));
    p
}

/// The tree of a well-formed file.
fn tree(src: &str) -> String {
    sexp(&ok(src).file)
}

/// The body of `mission { body }` (well formed).
fn body(stmts: &str) -> String {
    let src = format!("mission {{ {stmts} }}");
    let p = ok(&src);
    match &p.file.items[..] {
        [Item::Mission(m)] => block(&m.body),
        other => panic!("expected one mission, got {other:?}"),
    }
}

/// Parses a malformed input: returns the diagnostics' codes and the tree.
fn bad(src: &str) -> (Vec<&'static str>, String, Parse) {
    let p = parse(src);
    check_invariants(src, &p);
    (p.errors.iter().map(|d| d.code).collect(), sexp(&p.file), p)
}

fn text(src: &str, span: Span) -> &str {
    &src[span.range()]
}

// ---------------------------------------------------------------------------
// Items.

#[test]
fn actions_with_every_kind_of_parameter() {
    assert_eq!(
        tree(
            "actions {
                enableGoto = GotoPrimitive( c: enable, v: way-point );
                disableGoto = GotoPrimitive( c: disable );
                enableGps = GpsPrimitive( c: enable, v: 4, v: -2.5, v: \"fast \\\"mode\\\"\", v: $x );
                send = ModemPrimitive( c: send, v: [1, 2], );
            }"
        ),
        "(actions (enableGoto = GotoPrimitive c:enable v:way-point) (disableGoto = GotoPrimitive c:disable) \
         (enableGps = GpsPrimitive c:enable v:4 v:-2.5 v:\"fast \\\"mode\\\"\" v:$x) (send = ModemPrimitive c:send v:[1 2]))"
    );
}

#[test]
fn empty_blocks_of_definitions() {
    assert_eq!(
        tree("actions { } events { } pattern { } tasks { } constraints { }"),
        "(actions)\n(events)\n(pattern)\n(tasks)\n(constraints)"
    );
}

#[test]
fn events() {
    assert_eq!(tree("events { eventGotoOk; eventGotoFail; e-1/x$; }"), "(events eventGotoOk eventGotoFail e-1/x$)");
}

#[test]
fn import() {
    let src = "import \"vehicle.mcl\";\nimport \"dir/other file.mcl\";";
    let p = ok(src);
    assert_eq!(sexp(&p.file), "(import \"vehicle.mcl\")\n(import \"dir/other file.mcl\")");
    let Item::Import(i) = &p.file.items[0] else { panic!() };
    assert_eq!(text(src, i.path_span), "\"vehicle.mcl\"");
    assert_eq!(text(src, i.span), "import \"vehicle.mcl\";");
}

#[test]
fn pattern_net_with_every_suffix() {
    assert_eq!(
        tree(
            "pattern {
                AchieveOneGoal {
                    places { begin.1; abort.1; off(1); exe; p.0(2); q(3).1; }
                    transitions { T0; T1.1; TO(timeout); T30(30); T2.1(5); T3(2.5).0; }
                    arcs { begin.1 -> T0; T0 -> exe; exe -> T1 (2); abort.1 → T1.1; T1.1->off; }
                }
            }"
        ),
        "(pattern (AchieveOneGoal (places begin.1 abort.1 off(1) exe p.0(2) q.1(3)) \
         (transitions T0 T1.1 TO($timeout) T30(30) T2.1(5) T3.0(2.5)) \
         (arcs begin.1->T0 T0->exe exe->T1(2) abort.1->T1.1 T1.1->off)))"
    );
}

#[test]
fn pattern_from_files_and_bnf_names() {
    assert_eq!(
        tree("pattern { P_X : file.xml; P_TASK-2 : \"a/b.xml\"; P_Y : nets.v2.task.pnml; }\npatterns { P_Z : z.xml; }"),
        "(pattern (P_X file \"file.xml\") (P_TASK-2 file \"a/b.xml\") (P_Y file \"nets.v2.task.pnml\"))\n(pattern (P_Z file \"z.xml\"))"
    );
    let src = "pattern { P_X : file.xml; }";
    let p = ok(src);
    let Item::Patterns(b) = &p.file.items[0] else { panic!() };
    let PatternBody::File { path_span, .. } = &b.patterns[0].body else { panic!() };
    assert_eq!(text(src, *path_span), "file.xml");
    assert_eq!(text(src, b.patterns[0].span), "P_X : file.xml;");
}

#[test]
fn tasks() {
    assert_eq!(
        tree(
            "tasks {
                Goto( way-point ): AchieveOneGoal {
                    a: enableGoto -> T0;
                    a: disableGoto -> T1, T6, T7;
                    e: eventGotoOk -> T2;
                    e: eventGotoFail → T3;
                }
                Altitude( altitude, timeout, mode ): P_TIMED { }
                Void(): Instant { }
            }"
        ),
        "(tasks (Goto(way-point): AchieveOneGoal (a enableGoto -> T0) (a disableGoto -> T1 T6 T7) (e eventGotoOk -> T2) (e eventGotoFail -> T3)) \
         (Altitude(altitude timeout mode): P_TIMED) (Void(): Instant))"
    );
}

#[test]
fn binding_markers_are_contextual() {
    // `a`, `e`, `c`, `v`, `at`, `mutex`... are names everywhere else.
    assert_eq!(
        tree("events { a; e; c; v; at; mutex; _sync_; order; } tasks { a( e, c ): v { a: a -> e; e: e -> a; } }"),
        "(events a e c v at mutex _sync_ order)\n(tasks (a(e c): v (a a -> e) (e e -> a)))"
    );
}

#[test]
fn mission_headers() {
    let src = "mission { A() }
mission : auv { A() }
mission : auv [ x at 3 ] { A() }
mission : asc [ y-2 at -1.5 ] { A() }
mission MclMove( x, y, z ) { Goto( [x, y, z] ) }
mcl_plan_op SearchCableOp( timeout, cable_description, altitude ) { A() }
mcl_plan_op TakeFix() { A() }";
    assert_eq!(
        tree(src),
        "(mission {A()})
(mission auv {A()})
(mission auv [x at 3] {A()})
(mission asc [y-2 at -1.5] {A()})
(mission MclMove(x y z) {Goto([x y z])})
(mcl_plan_op SearchCableOp(timeout cable_description altitude) {A()})
(mcl_plan_op TakeFix() {A()})"
    );
    let p = ok(src);
    let Item::Mission(m) = &p.file.items[2] else { panic!() };
    assert_eq!(m.kind, MissionKind::Mission);
    assert_eq!(text(src, m.keyword_span), "mission");
    assert_eq!(m.placement.as_ref().map(|(n, num)| (n.text.as_str(), num.value())), Some(("x", 3.0)));
    let Item::Mission(m) = &p.file.items[5] else { panic!() };
    assert_eq!(m.kind, MissionKind::PlanOp);
    assert_eq!(text(src, m.keyword_span), "mcl_plan_op");
    assert_eq!(text(src, m.name.as_ref().unwrap().span), "SearchCableOp");
    assert_eq!(text(src, m.params[1].span), "cable_description");
    // A mission body's span covers its statements; the span of a
    // statement's block includes the braces.
    assert_eq!(text(src, m.body.span), "A()");
}

#[test]
fn malformed_mission_headers_keep_the_mission() {
    for (src, msg) in [
        ("mission auv { A() }", "expected `:` before the mission's name"),
        ("mission : { A() }", "expected the mission's name after `:`"),
        ("mission : auv ( x ) { A() }", "a named mission has no parameters"),
        ("mission ( x ) { A() }", "a parametrised mission needs a name"),
        ("mission M( x ) [ a at 1 ] { A() }", "`[ ID at NUM ]` follows the name of a named mission"),
        ("mcl_plan_op { A() }", "expected the operator's name after `mcl_plan_op`"),
        ("mcl_plan_op Op { A() }", "expected the operator's parameters `( ... )`"),
        ("mcl_plan_op : Op() { A() }", "`mcl_plan_op` is followed by the operator's name, without `:`"),
        ("mission : auv x y { A() }", "expected `{`, found identifier `x`"),
    ] {
        let (codes, t, p) = bad(src);
        assert_eq!(codes, ["E0010"], "{src}: {}", render_errors(src, &p));
        assert_eq!(p.errors[0].message, msg, "{src}");
        assert!(t.ends_with("{A()})"), "{src}: the body is kept: {t}");
    }
    // A broken parameter list is reported where it breaks.
    let (codes, t, p) = bad("mission M( x y ) { A() }");
    assert_eq!(codes, ["E0010"]);
    assert_eq!(p.errors[0].message, "expected `)` or `,`, found identifier `y`");
    assert_eq!(t, "(mission M {A()})");
}

#[test]
fn constraints_in_both_spellings() {
    let src = "constraints {
        mutex { auv:l1, asc:l2 } = 1
        order { asc:deploy_auv, auv:deploy_auv };
        sync { auv:send_data, asc:send_data }
        _mutex_ { l1, l2, l3 } = 2;
        _order_ { m2 : a , m1 : b }
        _sync_ { m1:send, m2:receive };
    }";
    assert_eq!(
        tree(src),
        "(constraints (mutex auv:l1 asc:l2 = 1) (order asc:deploy_auv auv:deploy_auv) (sync auv:send_data asc:send_data) \
         (_mutex_ l1 l2 l3 = 2) (_order_ m2:a m1:b) (_sync_ m1:send m2:receive))"
    );
    let p = ok(src);
    let Item::Constraints(c) = &p.file.items[0] else { panic!() };
    assert_eq!(c.constraints[0].kind, ConstraintKind::Mutex);
    assert!(!c.constraints[0].bnf_spelling);
    assert!(c.constraints[3].bnf_spelling);
    assert_eq!(text(src, c.constraints[0].keyword_span), "mutex");
    assert_eq!(text(src, c.constraints[4].refs[0].span), "m2 : a");
    assert_eq!(c.constraints[3].refs[0].mission, None);
}

#[test]
fn items_in_any_order_and_repeated() {
    assert_eq!(
        tree("mission { A() } tasks { } events { x; } actions { } events { y; } import \"v.mcl\"; mission : b { B() }"),
        "(mission {A()})\n(tasks)\n(events x)\n(actions)\n(events y)\n(import \"v.mcl\")\n(mission b {B()})"
    );
}

#[test]
fn appendix_c_program_in_bnf_order() {
    let src = "
actions { enableGoto = GotoPrimitive( c: enable, v: way-point ); }
events { eventGotoOk; }
pattern { P_TASK { places { begin.1; } transitions { T0; } arcs { begin.1 -> T0; } } P_F : f.xml; }
tasks { Goto( way-point ): P_TASK { a: enableGoto -> T0; e: eventGotoOk -> T0; } }
mission : m1 [ auv at 0 ] { Goto( p ) : l1 ; while ( Goto( q ) ) { Goto( r ) } }
mission : m2 [ asc at 1 ] { Goto( s ) : l2 }
constraints { _mutex_ { m1 : l1 , m2 : l2 } = 1 _order_ { m1 : l1 , m2 : l2 } _sync_ { l1 , l2 } }
";
    let p = ok(src);
    assert_eq!(p.file.items.len(), 7);
}

// ---------------------------------------------------------------------------
// Statements.

#[test]
fn calls_with_every_kind_of_argument() {
    assert_eq!(
        body("A() ; B( x, way-point, $v, a/b, 0, 15, -2, 15.5, -0.25, \"s\", \"\", [24, 12], [], [[0, 0], [1, -1]], path[[0,0],[1,1]], p[] ) : l-1"),
        "{A(); B(x way-point $v a/b 0 15 -2 15.5 -0.25 \"s\" \"\" [24 12] [] [[0 0] [1 -1]] path[[0 0] [1 1]] p[]):l-1}"
    );
    // Trailing commas in argument lists and lists.
    assert_eq!(body("A( 1, [2, 3,], )"), "{A(1 [2 3])}");
}

#[test]
fn call_spans() {
    let src = "mission { Goto( [24, 12], path[[0, 0]] ) : here }";
    let p = ok(src);
    let Item::Mission(m) = &p.file.items[0] else { panic!() };
    let StmtKind::Call(c) = &m.body.stmts[0].kind else { panic!() };
    assert_eq!(text(src, c.span), "Goto( [24, 12], path[[0, 0]] ) : here");
    assert_eq!(text(src, m.body.stmts[0].span), text(src, c.span));
    assert_eq!(text(src, c.name.span), "Goto");
    assert_eq!(text(src, c.args_span), "( [24, 12], path[[0, 0]] )");
    assert_eq!(text(src, c.args[0].span), "[24, 12]");
    assert_eq!(text(src, c.args[1].span), "path[[0, 0]]");
    let ValueKind::List { tag: Some(tag), items } = &c.args[1].kind else { panic!() };
    assert_eq!(text(src, tag.span), "path");
    assert_eq!(text(src, items[0].span), "[0, 0]");
    assert_eq!(text(src, c.label.as_ref().unwrap().span), "here");
}

#[test]
fn number_values() {
    let src = "mission { A( -2, 15.5, 0, -0.5 ) }";
    let p = ok(src);
    let Item::Mission(m) = &p.file.items[0] else { panic!() };
    let StmtKind::Call(c) = &m.body.stmts[0].kind else { panic!() };
    let nums: Vec<f64> = c
        .args
        .iter()
        .map(|v| match &v.kind {
            ValueKind::Number(n) => n.value(),
            _ => panic!(),
        })
        .collect();
    assert_eq!(nums, [-2.0, 15.5, 0.0, -0.5]);
}

#[test]
fn sequences() {
    assert_eq!(body("A()"), "{A()}");
    assert_eq!(body("A() ; B() ; C()"), "{A(); B(); C()}");
    // A `;` before `}` is tolerated.
    assert_eq!(body("A() ; B() ;"), "{A(); B()}");
    assert_eq!(body("A():x;B():y"), "{A():x; B():y}");
}

#[test]
fn while_in_every_spelling() {
    assert_eq!(body("while ( A() ) { B() }"), "{(while {A()} {B()})}");
    assert_eq!(body("while A() do { B() }"), "{(while {A()} {B()})}");
    assert_eq!(body("while True() do { B() ; C() }"), "{(while {True()} {B(); C()})}");
    assert_eq!(body("while ( A() ) do { B() }"), "{(while {A()} {B()})}");
    assert_eq!(body("while ( A() ; not ( B() ) ) { C() }"), "{(while {A(); (not {B()})} {C()})}");
}

#[test]
fn if_in_every_spelling() {
    assert_eq!(body("if ( A() ) { B() }"), "{(if {A()} {B()})}");
    assert_eq!(body("if ( A() ) { B() } else { C() }"), "{(if {A()} {B()} else {C()})}");
    assert_eq!(body("if ( A() ) then { B() }"), "{(if {A()} {B()})}");
    assert_eq!(body("if A() then { B() }"), "{(if {A()} {B()})}");
    assert_eq!(body("if GotoTarget() then { B() } else { C() }"), "{(if {GotoTarget()} {B()} else {C()})}");
    assert_eq!(body("if ( A() ) then { B() } else { C() }"), "{(if {A()} {B()} else {C()})}");
    assert_eq!(body("if ( not ( A() ) ) { B() }"), "{(if {(not {A()})} {B()})}");
}

#[test]
fn if_with_then_as_else_is_a_warning() {
    let src = "mission { if ( A() ) { B() } then { C() } }";
    let p = parse(src);
    check_invariants(src, &p);
    assert_eq!(sexp(&p.file), "(mission {(if {A()} {B()} then {C()})})");
    assert_eq!(p.errors.len(), 1);
    let w = &p.errors[0];
    assert_eq!((w.severity, w.code), (Severity::Warning, "W0015"));
    assert_eq!(text(src, w.span), "then");
    assert_eq!(w.span.start as usize, src.rfind("then").unwrap());
    let Item::Mission(m) = &p.file.items[0] else { panic!() };
    let StmtKind::If { else_written_then, .. } = &m.body.stmts[0].kind else { panic!() };
    assert_eq!(*else_written_then, Some(w.span));
}

#[test]
fn parallel() {
    assert_eq!(body("parallel { A() } and { B() }"), "{(parallel {A()} and {B()})}");
    assert_eq!(body("parallel { A() ; B() } or { C() } or { D() }"), "{(parallel {A(); B()} or {C()} or {D()})}");
    // Mixing is syntactically accepted and kept for the checker (E0301).
    assert_eq!(body("parallel { A() } and { B() } or { C() }"), "{(parallel {A()} and {B()} or {C()})}");
    let src = "mission { parallel { A() } and { B() } or { C() } }";
    let p = ok(src);
    let Item::Mission(m) = &p.file.items[0] else { panic!() };
    let StmtKind::Parallel { keyword, branches, ops } = &m.body.stmts[0].kind else { panic!() };
    assert_eq!(text(src, *keyword), "parallel");
    assert_eq!(branches.len(), 3);
    assert_eq!(ops.iter().map(|(_, s)| text(src, *s)).collect::<Vec<_>>(), ["and", "or"]);
    assert_eq!(text(src, branches[1].span), "{ B() }");
}

#[test]
fn try_catch_and_not() {
    assert_eq!(body("try { A() ; B() } catch { C() }"), "{(try {A(); B()} catch {C()})}");
    assert_eq!(body("not ( A() )"), "{(not {A()})}");
    assert_eq!(body("not ( not ( A() ) ; B() )"), "{(not {(not {A()}); B()})}");
}

#[test]
fn monitor_in_every_spelling() {
    assert_eq!(body("monitor { A() } condition ( B() ) do { C() }"), "{(monitor {A()} condition {B()} do {C()})}");
    assert_eq!(
        body("monitor { A() } while_condition ( B() ) do { C() }"),
        "{(monitor {A()} while_condition {B()} do {C()})}"
    );
    assert_eq!(body("monitor { A() } condition { B() } do { C() }"), "{(monitor {A()} condition {B()} do {C()})}");
    assert_eq!(body("monitor { A() } condition B() do { C() }"), "{(monitor {A()} condition {B()} do {C()})}");
    assert_eq!(
        body("monitor { A() } condition ( B() ) do { C() } while_condition ( D() ) do { E() }"),
        "{(monitor {A()} condition {B()} do {C()} while_condition {D()} do {E()})}"
    );
    let src = "mission { monitor { A() } while_condition ( B() : l ) do { C() } }";
    let p = ok(src);
    let Item::Mission(m) = &p.file.items[0] else { panic!() };
    let StmtKind::Monitor { handlers, .. } = &m.body.stmts[0].kind else { panic!() };
    assert_eq!(handlers[0].kind, MonitorKind::WhileCondition);
    assert_eq!(text(src, handlers[0].keyword_span), "while_condition");
    assert_eq!(text(src, handlers[0].span), "while_condition ( B() : l ) do { C() }");
}

#[test]
fn deep_nesting_with_labels() {
    let src = "
        monitor {
            try {
                Init() : ready ;
                while ( not ( SurveyDone() ) ) {
                    monitor {
                        parallel { NextLeg() } or { TakeImages() : img }
                    } while_condition ( SonarDetect( object ) : sonar ) do {
                        Inspect( object )
                    }
                } ;
                if ( Goto( recovery_point ) ) { Surface() } else { EmergencySurface() } ;
                parallel { SendData() : send } and { GpsFix() }
            } catch { Surface() ; Beacon() }
        } condition ( Alarm() ) do { EmergencySurface() }";
    assert_eq!(
        body(src),
        "{(monitor {(try {Init():ready; (while {(not {SurveyDone()})} {(monitor {(parallel {NextLeg()} or {TakeImages():img})} \
         while_condition {SonarDetect(object):sonar} do {Inspect(object)})}); (if {Goto(recovery_point)} {Surface()} else {EmergencySurface()}); \
         (parallel {SendData():send} and {GpsFix()})} catch {Surface(); Beacon()})} condition {Alarm()} do {EmergencySurface()})}"
    );
    // The labels, in source order, through the visitor.
    let p = ok(&format!("mission {{ {src} }}"));
    let Item::Mission(m) = &p.file.items[0] else { panic!() };
    let labels: Vec<&str> =
        mcl_syntax::visit::calls(&m.body).iter().filter_map(|c| c.label.as_ref()).map(|l| l.text.as_str()).collect();
    assert_eq!(labels, ["ready", "img", "sonar", "send"]);
}

#[test]
fn statement_spans() {
    let src = "mission { while ( A() ) { B() } ; try { C() } catch { D() } }";
    let p = ok(src);
    let Item::Mission(m) = &p.file.items[0] else { panic!() };
    assert_eq!(text(src, m.body.span), "while ( A() ) { B() } ; try { C() } catch { D() }");
    assert_eq!(text(src, m.body.stmts[0].span), "while ( A() ) { B() }");
    assert_eq!(text(src, m.body.stmts[1].span), "try { C() } catch { D() }");
    let StmtKind::While { keyword, cond, body } = &m.body.stmts[0].kind else { panic!() };
    assert_eq!(text(src, *keyword), "while");
    assert_eq!(text(src, body.span), "{ B() }");
    assert_eq!(text(src, cond.stmts[0].span), "A()");
    assert_eq!(text(src, cond.span), "A()");
    assert_eq!(text(src, m.span), src);
}

// ---------------------------------------------------------------------------
// Lexical structure.

#[test]
fn identifiers_with_dash_slash_dollar() {
    assert_eq!(
        body("Goto( way-point, sonar/front, $speed, x-1, _a, T0, a-b-c/d$e )"),
        "{Goto(way-point sonar/front $speed x-1 _a T0 a-b-c/d$e)}"
    );
}

#[test]
fn negative_numbers_and_dashes() {
    // `-` followed by a digit starts a number; inside an identifier it is part of it.
    assert_eq!(body("A( -2, a-2, -0.5, b, -3, [-1,-2] )"), "{A(-2 a-2 -0.5 b -3 [-1 -2])}");
    // `b -3` is two values, `b-3` one identifier.
    let (codes, _, p) = bad("mission { A( b -3 ) }");
    assert_eq!(codes, ["E0010"], "two values without a comma");
    assert_eq!(p.errors[0].message, "expected `)`, `,` or `[`, found number `-3`");
    assert_eq!(body("A( b-3 )"), "{A(b-3)}");
}

#[test]
fn arrows_and_comments_end_identifiers() {
    assert_eq!(
        tree("pattern { P { places { a; b-c; } transitions { t; } arcs { a->t; t→b-c; b-c->t; } } }"),
        "(pattern (P (places a b-c) (transitions t) (arcs a->t t->b-c b-c->t)))"
    );
    let src = "mission { A( x//comment\n ) ; B( y/*c*/ ) }";
    let p = ok(src);
    assert_eq!(sexp(&p.file), "(mission {A(x); B(y)})");
    assert_eq!(p.comments.len(), 2);
}

#[test]
fn comments_are_trivia_with_exact_spans() {
    let src = "// head\r\nmission /* a\nb */ { // tail é\n  A() /**/ ; B()\n} // end";
    let p = ok(src);
    assert_eq!(sexp(&p.file), "(mission {A(); B()})");
    let got: Vec<(CommentKind, &str)> = p.comments.iter().map(|c| (c.kind, text(src, c.span))).collect();
    assert_eq!(
        got,
        [
            (CommentKind::Line, "// head"),
            (CommentKind::Block, "/* a\nb */"),
            (CommentKind::Line, "// tail é"),
            (CommentKind::Block, "/**/"),
            (CommentKind::Line, "// end"),
        ]
    );
    // Comments inside strings are not comments.
    let p = ok("mission { A( \"// no\", \"/* no */\" ) }");
    assert!(p.comments.is_empty());
    assert_eq!(sexp(&p.file), "(mission {A(\"// no\" \"/* no */\")})");
}

#[test]
fn unicode_arrow_and_text() {
    let src = "pattern { P { places { é_not_ascii_is_not_an_identifier; } transitions { t; } arcs { a → t; } } }";
    let p = parse(src);
    check_invariants(src, &p);
    // One error for the whole identifier, which names the letter.
    assert_eq!(p.errors.iter().map(|d| d.code).collect::<Vec<_>>(), ["E0001"]);
    assert_eq!(text(src, p.errors[0].span), "é_not_ascii_is_not_an_identifier");
    assert_eq!(p.errors[0].labels[0].message, "`é` is not an ASCII letter");
    assert_eq!(p.errors[0].help.as_deref(), Some("identifiers are ASCII: letters a-z A-Z, digits, `_`, `$`, `-`, `/`; write `e_not_ascii_is_not_an_identifier`"));
    let p = ok("mission { Search( \"câble → ü\" ) }");
    assert_eq!(sexp(&p.file), "(mission {Search(\"câble → ü\")})");
}

#[test]
fn every_keyword_is_reserved() {
    for k in Kw::ALL {
        let src = format!("events {{ ok; {}; fine; }}", k.as_str());
        let (codes, t, p) = bad(&src);
        assert_eq!(codes, ["E0010"], "{src}: {}", render_errors(&src, &p));
        assert_eq!(t, "(events ok fine)", "{src}");
        assert_eq!(
            p.errors[0].help.as_deref(),
            Some(format!("`{}` is a keyword and cannot be used as a name", k.as_str()).as_str())
        );
    }
}

#[test]
fn line_columns_of_diagnostics_count_characters() {
    let src = "mission {\n  Search( \"é\" ) # x\n}";
    let p = parse(src);
    let idx = LineIndex::new(src);
    let lc = idx.line_col(src, p.errors[0].span.start as usize);
    assert_eq!((lc.line, lc.column), (2, 17));
}

// ---------------------------------------------------------------------------
// Recovery, asserted on the tree.

#[test]
fn broken_statement_keeps_the_rest_of_the_block() {
    let (codes, t, _) = bad("mission { A() ; B( 1 2 ) ; try { C() } D() ; E() }");
    assert_eq!(codes, ["E0010", "E0010"]);
    // A broken argument list gives a call without arguments; a broken
    // structure becomes an error statement.
    assert_eq!(t, "(mission {A(); B(); <error>; E()})");
}

#[test]
fn missing_semicolon_is_one_error_and_both_statements_are_kept() {
    let src = "mission { A() B() ; C() }";
    let (codes, t, p) = bad(src);
    assert_eq!(codes, ["E0010"]);
    assert_eq!(p.errors[0].message, "expected `;` between two statements");
    assert_eq!(p.errors[0].span, Span::at(src.find(" B").unwrap()));
    assert_eq!(t, "(mission {A(); B(); C()})");
}

#[test]
fn missing_closing_brace_before_next_item_is_one_error() {
    let src = "mission : a {\n  if ( A() ) {\n    B()\n  ;\n  C()\n  }\nmission : b { D() }\ntasks { }";
    let (codes, t, p) = bad(src);
    assert_eq!(codes, ["E0011"], "{}", render_errors(src, &p));
    assert_eq!(t, "(mission a {(if {A()} {B(); C()})})\n(mission b {D()})\n(tasks)");
    // The error points at the opener that is left open and says where the
    // closer was expected.
    assert_eq!(p.errors[0].span.start as usize, src.find('{').unwrap());
    let expected_at = p.errors[0].labels.iter().find(|l| l.message.contains("expected")).expect("a label says where");
    assert_eq!(expected_at.span.start as usize, src.find("mission : b").unwrap());
}

#[test]
fn missing_closing_brace_is_placed_by_indentation() {
    // The `}` indented like `mission` closes the mission: the `if` block is
    // the one left open, and it ends where its indented block ends (before
    // the `;` at the indentation of the `if`).
    let src = "mission : a {\n  if ( A() ) {\n    B()\n  ;\n  C()\n}\nmission : b { D() }\ntasks { }";
    let (codes, t, p) = bad(src);
    assert_eq!(codes, ["E0011"], "{}", render_errors(src, &p));
    assert_eq!(t, "(mission a {(if {A()} {B()}); C()})\n(mission b {D()})\n(tasks)");
    assert_eq!(p.errors[0].span.start as usize, src.find("{\n    B").unwrap());
    let expected_at = p.errors[0].labels.iter().find(|l| l.message.contains("expected")).expect("a label says where");
    assert_eq!(expected_at.span.start as usize, src.find("B()").unwrap() + 3);
    assert!(expected_at.message.contains("where its indented block ends"), "{}", expected_at.message);
    // The same text on one line has no indentation to read: the mission's
    // `{` is the one reported, at the next item.
    let flat = src.replace('\n', " ");
    let (codes, t, p) = bad(&flat);
    assert_eq!(codes, ["E0011"], "{}", render_errors(&flat, &p));
    assert_eq!(t, "(mission a {(if {A()} {B(); C()})})\n(mission b {D()})\n(tasks)");
    // Misindented but balanced text is no error.
    ok("mission {\n    try {\n        A()\n} catch {\n    B()\n  }\n    }");
}

#[test]
fn missing_closing_brace_at_end_of_file() {
    let (codes, t, _) = bad("mission { while ( A() ) { B() ; C()");
    assert_eq!(codes, ["E0011", "E0011"]);
    assert_eq!(t, "(mission {(while {A()} {B(); C()})})");
}

#[test]
fn garbage_between_items_is_skipped() {
    let (codes, t, _) = bad("junk ( 1 ) ; mission { A() } ] more junk events { e; } 42");
    assert_eq!(codes, ["E0010", "E0012", "E0010", "E0010"]);
    assert_eq!(t, "(mission {A()})\n(events e)");
}

#[test]
fn broken_definitions_are_skipped_one_by_one() {
    let (codes, t, _) = bad("actions { a = P( c: x ); b P( c: y ); c = P( c: z ); } events { e1; e 2; e3; }");
    assert_eq!(codes, ["E0010", "E0010"]);
    assert_eq!(t, "(actions (a = P c:x) (c = P c:z))\n(events e1 e3)");
    let (codes, t, _) = bad("tasks { A(): P { a: x; e: y -> T; } B( p q ): P { } C(): P { } }");
    assert_eq!(codes, ["E0010", "E0010"]);
    // The broken task keeps its name (so that its calls are not undefined),
    // with nothing else.
    assert_eq!(t, "(tasks (A(): P (e y -> T)) (B()) (C(): P))");
    let (codes, t, _) = bad("constraints { mutex { a:b } = x; order { a:b, c:d } foo { x } sync { a:b } }");
    assert_eq!(codes, ["E0010", "E0010"]);
    // The mutex is kept without its bound (the checker reports E0404).
    assert_eq!(t, "(constraints (mutex a:b) (order a:b c:d) (sync a:b))");
}

#[test]
fn actions_without_exactly_one_command() {
    let (codes, t, _) = bad("actions { a = P( v: x ); b = P( c: x, c: y ); }");
    assert_eq!(codes, ["E0014", "E0014"]);
    assert_eq!(t, "(actions (a = P c:? v:x) (b = P c:x))");
}

#[test]
fn empty_blocks_become_error_statements() {
    let (codes, t, _) = bad("mission { if ( ) { A() } else { } }");
    assert_eq!(codes, ["E0013", "E0013"]);
    assert_eq!(t, "(mission {(if {<error>} {A()} else {<error>})})");
}

#[test]
fn lexical_errors() {
    let (codes, t, p) = bad("mission { A( 007, 1., \"open ) ; B() } /* open");
    assert_eq!(codes, ["E0004", "E0004", "E0002", "E0003"]);
    assert_eq!(t, "(mission {A(007 1. \"open \"); B()})");
    assert_eq!(p.errors[1].message, "number with a `.` but no digits after it");
}

// ---------------------------------------------------------------------------
// Real programs.

fn examples_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples")
}

#[test]
fn every_example_parses_without_diagnostics() {
    let Ok(dir) = std::fs::read_dir(examples_dir()) else {
        return;
    };
    let mut n = 0;
    for entry in dir {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "mcl") {
            let src = std::fs::read_to_string(&path).unwrap();
            let p = parse(&src);
            check_invariants(&src, &p);
            assert!(p.errors.is_empty(), "{}:\n{}", path.display(), render_errors(&src, &p));
            assert!(!p.file.items.is_empty(), "{}", path.display());
            n += 1;
        }
    }
    eprintln!("{n} examples parsed");
}

#[test]
fn generated_programs_parse_without_diagnostics() {
    for (lines, seed) in [(50, 0), (600, 1), (3000, 2), (3000, 3)] {
        let src = mcl_syntax::gen::program(lines, seed);
        let p = parse(&src);
        check_invariants(&src, &p);
        assert!(p.errors.is_empty(), "gen({lines}, {seed}):\n{}", render_errors(&src, &p));
        let missions = p.file.items.iter().filter(|i| matches!(i, Item::Mission(_))).count();
        assert!(missions >= 1);
        if lines >= 3000 {
            assert!(missions > 20, "{missions} missions");
            // Every control structure occurs.
            let mut seen = std::collections::BTreeSet::new();
            for i in &p.file.items {
                if let Item::Mission(m) = i {
                    mcl_syntax::visit::walk_block(&m.body, &mut |s| {
                        seen.insert(match &s.kind {
                            StmtKind::Call(c) if c.label.is_some() => "labelled call",
                            StmtKind::Call(_) => "call",
                            StmtKind::While { .. } => "while",
                            StmtKind::If { otherwise: Some(_), .. } => "if-else",
                            StmtKind::If { .. } => "if",
                            StmtKind::Parallel { ops, .. } if ops[0].0 == ParallelOp::And => "and",
                            StmtKind::Parallel { .. } => "or",
                            StmtKind::Try { .. } => "try",
                            StmtKind::Not { .. } => "not",
                            StmtKind::Monitor { handlers, .. } if handlers[0].kind == MonitorKind::Condition => {
                                "condition"
                            }
                            StmtKind::Monitor { .. } => "while_condition",
                            StmtKind::Error => "error",
                        });
                    });
                }
            }
            assert_eq!(
                seen.into_iter().collect::<Vec<_>>(),
                [
                    "and",
                    "call",
                    "condition",
                    "if",
                    "if-else",
                    "labelled call",
                    "not",
                    "or",
                    "try",
                    "while",
                    "while_condition"
                ]
            );
        }
    }
}

// ---------------------------------------------------------------------------
// The corpus of malformed inputs: every file's diagnostics, as a snapshot.

fn bad_corpus() -> Vec<(String, String)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "mcl"))
        .collect();
    files.sort();
    files
        .into_iter()
        .map(|p| (p.file_stem().unwrap().to_string_lossy().into_owned(), std::fs::read_to_string(&p).unwrap()))
        .collect()
}

#[test]
fn bad_corpus_snapshots() {
    let corpus = bad_corpus();
    assert!(corpus.len() >= 20);
    let mut codes_seen = std::collections::BTreeSet::new();
    for (name, src) in &corpus {
        let p = parse(src);
        check_invariants(src, &p);
        codes_seen.extend(p.errors.iter().map(|d| d.code));
        // Every malformed input gives at least one diagnostic, and every
        // error is reported once.
        assert!(!p.errors.is_empty(), "{name}: no diagnostic");
        if name.starts_with("missing_brace") {
            let n = p.errors.len();
            assert!(
                (1..=2).contains(&n),
                "{name}: a missing brace gives one or two errors, got {n}:\n{}",
                render_errors(src, &p)
            );
            assert_eq!(p.errors[0].code, "E0011", "{name}");
        }
        insta::with_settings!({
            snapshot_path => "snapshots",
            prepend_module_to_snapshot => false,
            omit_expression => true,
            description => format!("tests/bad/{name}.mcl"),
        }, {
            insta::assert_snapshot!(format!("bad__{name}"), render_errors(src, &p));
        });
    }
    for code in ["E0001", "E0002", "E0003", "E0004", "E0010", "E0011", "E0012", "E0013", "E0014", "W0015"] {
        assert!(codes_seen.contains(code), "no corpus file produces {code}");
    }
}

// ---------------------------------------------------------------------------
// Robustness: nesting, byte order mark, classic slips recovered as one error.

/// Parses on a thread with a 2 MB stack (tokio's blocking threads, where the
/// language server parses).
fn parse_small_stack(src: String) -> (Vec<&'static str>, Parse) {
    std::thread::Builder::new()
        .stack_size(2 << 20)
        .spawn(move || {
            let p = parse(&src);
            check_invariants(&src, &p);
            let _ = mcl_syntax::format::format(&src);
            (p.errors.iter().map(|d| d.code).collect(), p)
        })
        .unwrap()
        .join()
        .expect("no stack overflow")
}

#[test]
fn nesting_beyond_the_limit_is_one_error_at_the_first_level_too_deep() {
    use mcl_syntax::parser::MAX_NESTING;
    let n = 50_000;
    for (open, close) in
        [("not ( ", " )"), ("try { ", " } catch { C() }"), ("if ", " then { A() }"), ("while ", " do { A() }")]
    {
        let src = format!("mission {{ {}A(){} }}\nmission : after {{ B() }}", open.repeat(n), close.repeat(n));
        let (codes, p) = parse_small_stack(src.clone());
        assert_eq!(codes, ["E0016"], "{open}");
        // The mission body is level 1: the construct at level 65 is reported.
        let at = p.errors[0].span.start as usize;
        assert_eq!(
            at,
            "mission { ".len() + open.len() * (MAX_NESTING - 1) + open.find(['(', '{']).unwrap_or(0),
            "{open}"
        );
        // The next item is parsed as usual.
        assert!(sexp(&p.file).ends_with("(mission after {B()})"), "{open}: {}", sexp(&p.file));
    }
    // Exactly at the limit (the body, 62 `not`s, the call's parentheses): no error.
    let ok = format!("mission {{ {}A(){} }}", "not ( ".repeat(MAX_NESTING - 2), " )".repeat(MAX_NESTING - 2));
    let (codes, _) = parse_small_stack(ok);
    assert!(codes.is_empty(), "{codes:?}");
    // The body, 61 blocks, the innermost condition's and call's parentheses.
    let ok = format!("mission {{ {}A(){} }}", "if ( B() ) { ".repeat(MAX_NESTING - 3), " }".repeat(MAX_NESTING - 3));
    let (codes, _) = parse_small_stack(ok);
    assert!(codes.is_empty(), "a delimited condition is not a level of its own: {codes:?}");
    // Unclosed: the nesting error and one error for the many unclosed delimiters.
    let (codes, p) = parse_small_stack(format!("mission {{ {}A()", "not ( ".repeat(n)));
    assert_eq!(codes, ["E0011", "E0016"]);
    assert!(p.errors[0].notes[0].contains("64 more delimiters"), "{:?}", p.errors[0].notes);
}

#[test]
fn a_byte_order_mark_is_skipped_and_no_column() {
    let src = "\u{feff}mission { A() ; B( }";
    let p = parse(src);
    check_invariants(src, &p);
    assert_eq!(sexp(&p.file), "(mission {A(); B()})");
    assert_eq!(p.errors.iter().map(|d| d.code).collect::<Vec<_>>(), ["E0011"]);
    let idx = LineIndex::new(src);
    let b = src.find('B').unwrap();
    assert_eq!(idx.line_col(src, b).column, 17);
    // Elsewhere it is an invisible character, reported.
    let (codes, _, _) = bad("mission { A() \u{feff}}");
    assert_eq!(codes, ["E0001"]);
}

#[test]
fn a_mission_without_its_opening_brace_is_one_error() {
    let (codes, t, p) = bad("mission : m Depth( 1 ) ; Surface() }\nmission : n { A() }");
    assert_eq!(codes, ["E0010"]);
    assert_eq!(p.errors[0].message, "expected `{` before the mission's body");
    assert_eq!(p.errors[0].span.start, 12);
    assert_eq!(t, "(mission m {Depth(1); Surface()})\n(mission n {A()})");
    // Anonymous: the call is not taken for a parametrised mission's header.
    let (codes, t, _) = bad("mission Depth( 1 ) ; Surface() }");
    assert_eq!(codes, ["E0010"]);
    assert_eq!(t, "(mission {Depth(1); Surface()})");
    // Named without `:` (a second mistake): two errors, the body is kept.
    let (codes, t, _) = bad("mission m  Depth(1); }");
    assert_eq!(codes, ["E0010", "E0010"]);
    assert_eq!(t, "(mission m {Depth(1)})");
}

#[test]
fn an_import_without_semicolon_is_one_error_and_kept() {
    let (codes, t, p) = bad("import \"vehicle.mcl\"\nmission { A() }");
    assert_eq!(codes, ["E0010"]);
    assert_eq!(p.errors[0].span, Span::at(20));
    assert_eq!(t, "(import \"vehicle.mcl\")\n(mission {A()})");
}

#[test]
fn a_keyword_as_a_mission_name_is_one_error() {
    let (codes, t, p) = bad("mission : while { A() ; B() }");
    assert_eq!(codes, ["E0010"]);
    assert!(p.errors[0].message.contains("`while` is a keyword"), "{}", p.errors[0].message);
    assert_eq!(text("mission : while { A() ; B() }", p.errors[0].span), "while");
    assert_eq!(t, "(mission while {A(); B()})");
}

#[test]
fn planning_blocks() {
    let src = "planning {
        type location { x; y; z; }
        type auv : vehicle;
        entity location dock { x = 0; y = -2.5; z = \"deep\"; }
        entity auv ictineu;
        function distance( location, location );
        operator move( vehicle v, location l1, location l2 ) {
            precond { v in l1; not v busy; }
            add { v in l2; }
            del { v in l1; }
            expression { l1 != l2; l2.z <= v.max_depth; distance( l1, l2 ) < 100; }
            cost distance( l1, l2 );
            mcl MclMove( l2.x, l2.y, l2.z, \"keep\", 3, timeout );
        }
        initial { ictineu in dock; cable not_found; distance( dock, dock ) = 0; }
        goal { ictineu in dock; not cable not_found; }
    }
    pddl_map { move( v, a, b ) -> MclMove( b.x, 1 ); }";
    let p = ok(src);
    let Item::Planning(b) = &p.file.items[0] else { panic!() };
    assert_eq!(b.defs.len(), 8);
    let PlanDef::Type(t) = &b.defs[1] else { panic!() };
    assert_eq!((t.name.text.as_str(), t.parent.as_ref().map(|n| n.text.as_str())), ("auv", Some("vehicle")));
    let PlanDef::Operator(o) = &b.defs[5] else { panic!() };
    assert_eq!(o.params.len(), 3);
    assert_eq!(o.parts.len(), 6);
    let OpPartKind::Precond(pre) = &o.parts[0].kind else { panic!() };
    assert!(pre[1].negated.is_some() && pre[1].object.is_none(), "`not v busy`: a negated quality");
    let OpPartKind::Expression(x) = &o.parts[3].kind else { panic!() };
    assert_eq!(x.iter().map(|e| e.op.as_str()).collect::<Vec<_>>(), ["!=", "<=", "<"]);
    assert!(matches!(&x[1].left.kind, OperandKind::Attr(e, a) if e.text == "l2" && a.text == "z"));
    assert!(matches!(&x[2].left.kind, OperandKind::Function(f, args) if f.text == "distance" && args.len() == 2));
    let OpPartKind::Mcl(c) = &o.parts[5].kind else { panic!() };
    assert_eq!(c.args.len(), 6);
    let PlanDef::Facts(init) = &b.defs[6] else { panic!() };
    assert_eq!((init.goal, init.facts.len(), init.values.len()), (false, 2, 1));
    let Item::PddlMap(m) = &p.file.items[1] else { panic!() };
    assert_eq!(m.maps[0].params.len(), 3);
    assert_eq!(m.maps[0].call.name.text, "MclMove");
}

#[test]
fn a_broken_planning_definition_does_not_hide_the_next_ones() {
    let src = "planning {
        type location { x; }
        entity location;
        operator move( vehicle v ) { precond { v in; } add { v at 3; } mcl M(); }
        goal { a in b; }
    }";
    let p = parse(src);
    check_invariants(src, &p);
    assert!(!p.errors.is_empty());
    assert!(p.errors.iter().all(|e| e.code == "E0010"), "{}", render_errors(src, &p));
    let Item::Planning(b) = &p.file.items[0] else { panic!() };
    let kinds: Vec<&str> = b
        .defs
        .iter()
        .map(|d| match d {
            PlanDef::Type(_) => "type",
            PlanDef::Entity(_) => "entity",
            PlanDef::Function(_) => "function",
            PlanDef::Operator(_) => "operator",
            PlanDef::Facts(_) => "facts",
        })
        .collect();
    assert_eq!(kinds, ["type", "operator", "facts"], "{}", render_errors(src, &p));
}
