//! Feature tests on `$0` cursor fixtures, without the transport.

use super::fixture::{apply_edits, Fixture, VEHICLE};
use super::*;
use mcl_syntax::ast::Item;
use tower_lsp_server::ls_types::*;

const MISSION: &str = r#"import "vehicle.mcl";

mission : auv {
    Depth( 15, "achieve" ) : dive ;
    parallel {
        Depth( 15, "keep" )
    } or {
        Goto( [24, 12] ) : go
    }
}

mission : asc {
    Void() : wait ;
    Goto( [0, 0] )
}

constraints {
    order { auv:go, asc:wait }
}
"#;

fn with_cursor(text: &str, needle: &str) -> String {
    let i = text.find(needle).unwrap_or_else(|| panic!("`{needle}` not in fixture"));
    let mut t = text.to_string();
    t.insert_str(i, "$0");
    t
}

/// A fixture of the vehicle and the mission, with the cursor before the
/// first `needle` of `which` ("mission" or "vehicle").
fn fx(which: &str, needle: &str) -> Fixture {
    let (m, v) = if which == "mission" {
        (with_cursor(MISSION, needle), VEHICLE.to_string())
    } else {
        (MISSION.to_string(), with_cursor(VEHICLE, needle))
    };
    Fixture::new(&[("mission.mcl", &m), ("vehicle.mcl", &v)])
}

fn defs(f: &Fixture) -> Vec<String> {
    let a = f.analysis();
    let (file, off) = f.cursor();
    navigation::goto_definition(&a, file, off).iter().map(|l| f.show(l)).collect()
}

fn refs(f: &Fixture) -> Vec<String> {
    let a = f.analysis();
    let (file, off) = f.cursor();
    navigation::references(&a, file, off, true).iter().map(|l| f.show(l)).collect()
}

#[test]
fn definition_of_task_call_is_in_the_imported_file() {
    assert_eq!(defs(&fx("mission", "Goto( [24")), ["vehicle.mcl:15:5: Goto"]);
    // At the end of the name too.
    assert_eq!(defs(&fx("mission", "( [24")), ["vehicle.mcl:15:5: Goto"]);
}

#[test]
fn definition_of_actions_events_and_patterns() {
    assert_eq!(defs(&fx("vehicle", "enableGoto -> T0")), ["vehicle.mcl:2:5: enableGoto"]);
    assert_eq!(defs(&fx("vehicle", "eventDepthFail -> T3")), ["vehicle.mcl:10:19: eventDepthFail"]);
    // The standard library's pattern: shown from a copy on disk, if any.
    let f = fx("vehicle", "AchieveOneGoal {\n        a: enableGoto");
    let a = f.analysis();
    let (file, off) = f.cursor();
    let sym = navigation::symbol_at(&a, file, off).map(|(_, s)| s);
    assert!(matches!(sym, Some(index::Sym::Def(d)) if d.in_stdlib));
}

#[test]
fn definition_of_an_import_is_the_imported_file() {
    assert_eq!(defs(&fx("mission", "vehicle.mcl\"")), ["vehicle.mcl:1:1: "]);
}

#[test]
fn rename_a_mission_parameter_but_not_a_task_parameter() {
    let f = Fixture::new(&[
        (
            "m.mcl",
            "import \"vehicle.mcl\";\nmission Move( x$0, y ) {\n    Goto( [x, y] ) ;\n    Depth( x, \"a\" )\n}\n",
        ),
        ("vehicle.mcl", VEHICLE),
    ]);
    let a = f.analysis();
    let (file, off) = f.cursor();
    let edit = navigation::rename(&a, file, off, "px").unwrap();
    assert_eq!(
        f.apply(&edit)[0].1,
        "import \"vehicle.mcl\";\nmission Move( px, y ) {\n    Goto( [px, y] ) ;\n    Depth( px, \"a\" )\n}\n"
    );
    let f = fx("vehicle", "way-point ): AchieveOneGoal");
    let a = f.analysis();
    let (file, off) = f.cursor();
    assert!(navigation::prepare_rename(&a, file, off).unwrap_err().0.contains("task parameter"));
}

#[test]
fn definition_of_transition_in_binding_is_in_the_pattern() {
    let f = Fixture::new(&[(
        "p.mcl",
        "pattern {\n  P {\n    places { begin.1; abort.1; ok.1; fail.1; }\n    transitions { Ta; Tb; }\n    arcs { begin -> Ta; Ta -> ok; abort -> Tb; }\n  }\n}\nevents { ev; }\ntasks {\n  T(): P { e: ev -> $0Ta; }\n}\n",
    )]);
    assert_eq!(defs(&f), ["p.mcl:4:19: Ta"]);
    assert_eq!(refs(&f), ["p.mcl:4:19: Ta", "p.mcl:5:21: Ta", "p.mcl:5:25: Ta", "p.mcl:10:21: Ta"]);
}

#[test]
fn places_in_arcs_resolve_to_their_declaration() {
    let f = Fixture::new(&[(
        "p.mcl",
        "pattern {\n  P {\n    places { begin.1; abort.1; ok.1; fail.1; off(1); }\n    transitions { Ta; }\n    arcs { begin -> Ta; $0off -> Ta; Ta -> off; Ta -> ok; }\n  }\n}\n",
    )]);
    assert_eq!(defs(&f), ["p.mcl:3:46: off"]);
    assert_eq!(refs(&f).len(), 3);
}

#[test]
fn labels_and_missions_in_constraints() {
    assert_eq!(defs(&fx("mission", "go, asc")), ["mission.mcl:8:28: go"]);
    assert_eq!(defs(&fx("mission", "asc:wait")), ["mission.mcl:12:11: asc"]);
    assert_eq!(refs(&fx("mission", "wait ;")), ["mission.mcl:13:14: wait", "mission.mcl:18:25: wait"]);
}

#[test]
fn references_of_a_task_across_files() {
    let r = refs(&fx("vehicle", "Goto( way-point )"));
    assert_eq!(r, ["mission.mcl:8:9: Goto", "mission.mcl:14:5: Goto", "vehicle.mcl:15:5: Goto"]);
    let without_decl = {
        let f = fx("vehicle", "Goto( way-point )");
        let a = f.analysis();
        let (file, off) = f.cursor();
        navigation::references(&a, file, off, false).len()
    };
    assert_eq!(without_decl, 2);
}

#[test]
fn rename_a_task_everywhere() {
    let f = fx("mission", "Goto( [0");
    let a = f.analysis();
    let (file, off) = f.cursor();
    let prep = navigation::prepare_rename(&a, file, off).unwrap();
    assert!(
        matches!(prep, PrepareRenameResponse::RangeWithPlaceholder { ref placeholder, .. } if placeholder == "Goto")
    );
    let edit = navigation::rename(&a, file, off, "GoTo").unwrap();
    let files = f.apply(&edit);
    assert_eq!(files.len(), 2);
    assert_eq!(files[0].1.matches("GoTo(").count(), 2, "{}", files[0].1);
    assert!(files[1].1.contains("GoTo( way-point ): AchieveOneGoal"));
    assert!(!files[1].1.contains("Goto("));
}

#[test]
fn rename_a_label_renames_constraint_references() {
    let f = fx("mission", "go\n");
    let a = f.analysis();
    let (file, off) = f.cursor();
    let edit = navigation::rename(&a, file, off, "arrive").unwrap();
    let text = &f.apply(&edit)[0].1;
    assert!(text.contains("Goto( [24, 12] ) : arrive"));
    assert!(text.contains("order { auv:arrive, asc:wait }"));
}

#[test]
fn rename_refuses_keywords_stdlib_and_bad_names() {
    let f = fx("mission", "parallel");
    let a = f.analysis();
    let (file, off) = f.cursor();
    assert_eq!(navigation::prepare_rename(&a, file, off).unwrap_err().0, "keywords cannot be renamed");
    let f = fx("vehicle", "AchieveOneGoal {\n        a: enableGoto");
    let a = f.analysis();
    let (file, off) = f.cursor();
    assert!(navigation::prepare_rename(&a, file, off).unwrap_err().0.contains("standard library"));
    let f = fx("mission", "Goto( [0");
    let a = f.analysis();
    let (file, off) = f.cursor();
    assert_eq!(navigation::rename(&a, file, off, "while").unwrap_err().0, "`while` is a keyword");
    assert_eq!(navigation::rename(&a, file, off, "a b").unwrap_err().0, "`a b` is not an identifier");
}

fn hover_text(f: &Fixture) -> String {
    let a = f.analysis();
    let (file, off) = f.cursor();
    match hover::hover(&a, file, off).map(|h| h.contents) {
        Some(HoverContents::Markup(m)) => m.value,
        other => format!("{other:?}"),
    }
}

#[test]
fn hover_on_a_call_shows_the_task() {
    insta::assert_snapshot!(hover_text(&fx("mission", "Goto( [24")), @r#"
    ```mcl
    Goto( way-point ): AchieveOneGoal
    ```
    Task on primitive `GotoPrimitive`.

    **Parameters:** `way-point`

    **Actions**
    - `enableGoto` → `T0`: `GotoPrimitive( c: enable, v: way-point )`
    - `disableGoto` → `T1`, `T6`, `T7`: `GotoPrimitive( c: disable )`

    **Events**
    - `eventGotoOk` → `T2`
    - `eventGotoFail` → `T3`

    **Pattern** `AchieveOneGoal`: 13 places, 10 transitions, 32 arcs (standard library)

    ---
    Go to one way-point.

    *Defined in `vehicle.mcl`.*
    "#);
}

#[test]
fn hover_on_keywords_describes_the_structure() {
    let t = hover_text(&fx("mission", "parallel"));
    assert!(t.starts_with("```mcl\nparallel { A } or { B }\n```\n**parallel-or** (control structure)"), "{t}");
    let t = hover_text(&fx("mission", "or {"));
    assert!(t.contains("**parallel-or**"), "{t}");
}

#[test]
fn hover_on_a_constraint_states_its_messages_and_bytes() {
    // The AUV tells the ASC the end of `go`, once.
    let m = "import \"vehicle.mcl\";\nmission : auv { Void() : go ; Goto( [0, 0] ) }\nmission : asc { Void() : wait }\nconstraints {\n    $0order { auv:go, asc:wait }\n}\n";
    let f = Fixture::new(&[("mission.mcl", m), ("vehicle.mcl", VEHICLE)]);
    let t = hover_text(&f);
    assert!(t.contains("**order** (coordination constraint)"), "{t}");
    assert!(t.contains("**Link**: a run sends at most 1 coordination messages for it, 1 bytes each"), "{t}");
    // The fixture's own order deadlocks (E0406): no link text.
    let t = hover_text(&fx("mission", "order {"));
    assert!(t.contains("**order**") && !t.contains("**Link**"), "{t}");
}

#[test]
fn hover_on_action_event_label_and_mission() {
    let t = hover_text(&fx("vehicle", "enableDepth -> T0"));
    assert!(t.starts_with("```mcl\nenableDepth = DepthPrimitive( c: enable, v: depth, v: mode )\n```"), "{t}");
    assert!(t.contains("- `Depth` → `T0`"), "{t}");
    let t = hover_text(&fx("vehicle", "eventGotoFail;"));
    assert!(t.contains("**Fires**\n- `Goto` → `T3`"), "{t}");
    let t = hover_text(&fx("mission", "go, asc"));
    assert!(t.contains("Goto( [24, 12] ) : go"), "{t}");
    let t = hover_text(&fx("mission", "auv {"));
    assert!(t.contains("mission : auv { ... }"), "{t}");
    assert!(t.contains("**Labels** `dive` `go`"), "{t}");
}

fn completion_labels(text: &str) -> Vec<String> {
    let f = Fixture::new(&[("main.mcl", text), ("vehicle.mcl", VEHICLE)]);
    let a = f.analysis();
    let (file, off) = f.cursor();
    completion::completion(&a, file, off, true).into_iter().map(|c| c.label).collect()
}

#[test]
fn completion_in_a_mission_offers_tasks_and_structures() {
    let items = {
        let f = Fixture::new(&[
            ("main.mcl", "import \"vehicle.mcl\";\nmission {\n    Depth( 1, \"a\" ) ;\n    Go$0\n}\n"),
            ("vehicle.mcl", VEHICLE),
        ]);
        let a = f.analysis();
        let (file, off) = f.cursor();
        completion::completion(&a, file, off, true)
    };
    let goto = items.iter().find(|c| c.label == "Goto").expect("Goto offered");
    match &goto.text_edit {
        Some(CompletionTextEdit::Edit(e)) => {
            assert_eq!(e.new_text, "Goto(${1:way-point})");
            assert_eq!((e.range.start.character, e.range.end.character), (4, 6));
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(goto.insert_text_format, Some(InsertTextFormat::SNIPPET));
    let labels: Vec<&str> = items.iter().map(|c| c.label.as_str()).collect();
    for l in ["Depth", "Void", "while", "parallel or", "monitor condition", "try catch"] {
        assert!(labels.contains(&l), "{l} in {labels:?}");
    }
}

#[test]
fn completion_in_task_bodies() {
    let base = |body: &str| {
        format!("import \"vehicle.mcl\";\ntasks {{\n    T( x ): AchieveOneGoal {{\n        {body}\n    }}\n}}\n")
    };
    let actions = completion_labels(&base("a: $0"));
    assert_eq!(actions, ["disableDepth", "disableGoto", "enableDepth", "enableGoto"]);
    let events = completion_labels(&base("e: ev$0"));
    assert_eq!(events, ["eventDepthFail", "eventDepthOk", "eventGotoFail", "eventGotoOk"]);
    let trs = completion_labels(&base("a: enableGoto -> T0, $0"));
    assert_eq!(trs, ["TT0", "TT1", "TT2", "TT3", "T0", "T1", "T2", "T3", "T6", "T7"]);
    let start = completion_labels(&base("$0"));
    assert_eq!(start, ["a:", "e:"]);
    let pats = completion_labels("tasks {\n    T( x ): $0\n}\n");
    assert_eq!(pats, ["AchieveOneGoal", "AchieveOneGoalTimed", "Instant"]);
}

#[test]
fn completion_in_constraints_and_at_top_level() {
    let text = MISSION.replace("order { auv:go, asc:wait }", "order { auv:$0 }");
    let f = Fixture::new(&[("mission.mcl", &text), ("vehicle.mcl", VEHICLE)]);
    let a = f.analysis();
    let (file, off) = f.cursor();
    let labels: Vec<String> = completion::completion(&a, file, off, true).into_iter().map(|c| c.label).collect();
    assert_eq!(labels, ["dive", "go"]);
    let text = MISSION.replace("order { auv:go, asc:wait }", "order { $0 }");
    let labels = completion_labels(&text);
    assert!(labels.contains(&"asc:".to_string()) && labels.contains(&"auv:go".to_string()), "{labels:?}");
    let top = completion_labels("mission { Void() }\n$0");
    assert!(top.contains(&"tasks".to_string()) && top.contains(&"mission :".to_string()), "{top:?}");
    // Nothing inside comments and strings.
    assert!(completion_labels("mission {\n  // Go$0\n  Void()\n}").is_empty());
}

#[test]
fn signature_help_tracks_the_active_parameter() {
    let f = Fixture::new(&[
        ("main.mcl", "import \"vehicle.mcl\";\nmission {\n    Depth( [1, 2], $0\n}\n"),
        ("vehicle.mcl", VEHICLE),
    ]);
    let a = f.analysis();
    let (file, off) = f.cursor();
    let h = completion::signature_help(&a, file, off).expect("signature");
    assert_eq!(h.signatures[0].label, "Depth( depth, mode )");
    assert_eq!(h.active_parameter, Some(1));
    let p = &h.signatures[0].parameters.as_ref().unwrap()[1];
    assert!(matches!(p.label, ParameterLabel::LabelOffsets([14, 18])));
}

#[test]
fn document_symbols_are_blocks_then_definitions() {
    let f = fx("mission", "auv");
    let a = f.analysis();
    let syms = outline::document_symbols(&a, f.file("mission.mcl"));
    fn show(s: &DocumentSymbol, depth: usize, out: &mut String) {
        out.push_str(&format!("{}{} {:?}\n", "  ".repeat(depth), s.name, s.kind));
        for c in s.children.iter().flatten() {
            show(c, depth + 1, out);
        }
    }
    let mut out = String::new();
    for s in &syms {
        show(s, 0, &mut out);
    }
    insta::assert_snapshot!(out, @r#"
    import "vehicle.mcl" File
    auv Module
      dive Key
      go Key
    asc Module
      wait Key
    constraints Namespace
      order { auv:go, asc:wait } Operator
    "#);
    let v = outline::document_symbols(&a, f.file("vehicle.mcl"));
    let names: Vec<&str> = v.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["actions", "events", "tasks"]);
    assert_eq!(v[2].children.as_ref().unwrap()[0].detail.as_deref(), Some("Goto( way-point ): AchieveOneGoal"));
}

#[test]
fn workspace_symbols_match_fuzzily() {
    let f = fx("mission", "auv");
    let a = f.analysis();
    let names: Vec<String> = outline::workspace_symbols(&a, "evgo").into_iter().map(|s| s.name).collect();
    assert_eq!(names, ["eventGotoOk", "eventGotoFail"]);
}

#[test]
fn folding_ranges_cover_blocks_and_comments() {
    let f = Fixture::new(&[(
        "a.mcl",
        "// one\n// two\nmission {\n    try {\n        Void()\n    } catch {\n        Void()\n    }\n}\n",
    )]);
    let a = f.analysis();
    let r: Vec<(u32, u32, Option<FoldingRangeKind>)> =
        outline::folding_ranges(&a, f.file("a.mcl")).into_iter().map(|r| (r.start_line, r.end_line, r.kind)).collect();
    assert_eq!(r, [(0, 1, Some(FoldingRangeKind::Comment)), (2, 7, None), (3, 4, None), (5, 6, None)]);
}

#[test]
fn semantic_tokens_classify_names_by_role() {
    let f = fx("mission", "auv");
    let a = f.analysis();
    let file = f.file("mission.mcl");
    let text = a.text(file);
    let shown: Vec<String> = semantic::classified(&a, file)
        .into_iter()
        .take(14)
        .map(|(s, t, m)| {
            format!(
                "{} {}{}",
                &text[s.range()],
                semantic::TYPES[t as usize].as_str(),
                if m != 0 { format!(" {m}") } else { String::new() }
            )
        })
        .collect();
    assert_eq!(
        shown,
        [
            "import keyword",
            "\"vehicle.mcl\" string",
            "mission keyword",
            "auv namespace 1",
            "Depth function",
            "15 number",
            "\"achieve\" string",
            "dive decorator 1",
            "parallel keyword",
            "Depth function",
            "15 number",
            "\"keep\" string",
            "or keyword",
            "Goto function",
        ]
    );
    // Encoded tokens: one per classified token here (no multi-line comment).
    assert_eq!(semantic::semantic_tokens(&a, file).len(), semantic::classified(&a, file).len());
}

#[test]
fn inlay_hints_name_the_parameters() {
    let f = fx("mission", "auv");
    let a = f.analysis();
    let file = f.file("mission.mcl");
    let hints: Vec<String> = semantic::inlay_hints(&a, file, mcl_syntax::Span::new(0, 10_000))
        .into_iter()
        .map(|h| match h.label {
            InlayHintLabel::String(s) => format!("{}:{} {s}", h.position.line + 1, h.position.character + 1),
            _ => String::new(),
        })
        .collect();
    assert_eq!(
        hints,
        ["4:12 depth:", "4:16 mode:", "6:16 depth:", "6:20 mode:", "8:15 way-point:", "14:11 way-point:"]
    );
}

fn fixes(files: &[(&str, &str)]) -> Vec<(String, Vec<(String, String)>)> {
    let f = Fixture::new(files);
    let a = f.analysis();
    let (file, off) = f.cursor();
    fixes::code_actions(&a, file, mcl_syntax::Span::at(off))
        .into_iter()
        .map(|c| (c.title, f.apply(c.edit.as_ref().unwrap())))
        .collect()
}

#[test]
fn quick_fix_did_you_mean_and_create_task() {
    let got = fixes(&[
        ("main.mcl", "import \"vehicle.mcl\";\nmission {\n    $0Gotoo( [1, 2] )\n}\n"),
        ("vehicle.mcl", VEHICLE),
    ]);
    assert_eq!(got[0].0, "Replace with `Goto`");
    assert_eq!(got[0].1[0].1, "import \"vehicle.mcl\";\nmission {\n    Goto( [1, 2] )\n}\n");
    assert_eq!(got[1].0, "Create task `Gotoo`");
    assert_eq!(got[1].1[0].0, "vehicle.mcl");
    assert!(
        got[1].1[0].1.contains(
            "    Void(): Instant { }\n    Gotoo( arg1 ): AchieveOneGoal {\n        // a: enableGotoo -> T0;\n"
        ),
        "{}",
        got[1].1[0].1
    );
}

#[test]
fn quick_fix_create_task_in_a_new_block() {
    let got = fixes(&[("main.mcl", "mission {\n    $0Survey( depth, [1, 2] )\n}\n")]);
    assert_eq!(got.len(), 1);
    assert_eq!(got[0].0, "Create task `Survey`");
    insta::assert_snapshot!(got[0].1[0].1, @r"
    tasks {
        Survey( depth, arg2 ): AchieveOneGoal {
            // a: enableSurvey -> T0;
            // a: disableSurvey -> T1, T6, T7;
            // e: eventSurveyOk -> T2;
            // e: eventSurveyFail -> T3;
        }
    }

    mission {
        Survey( depth, [1, 2] )
    }
    ");
    // The result is a valid program.
    let f = Fixture::new(&[("x.mcl", &got[0].1[0].1)]);
    assert!(mcl_compiler::check_file(&f.db, f.file("x.mcl")).is_empty());
}

#[test]
fn quick_fix_declare_event_and_action() {
    let text = "events {\n    ok;\n}\nactions {\n    enableX = XPrimitive( c: enable );\n}\ntasks {\n    X(): AchieveOneGoal {\n        a: enableX -> T0;\n        a: $0disableX -> T1, T6, T7;\n        e: ok -> T2;\n        e: failed -> T3;\n    }\n}\nmission { X() }\n";
    let got = fixes(&[("main.mcl", text)]);
    assert_eq!(got[0].0, "Declare action `disableX`");
    assert!(
        got[0].1[0].1.contains("    enableX = XPrimitive( c: enable );\n    disableX = XPrimitive( c: disable );\n}"),
        "{}",
        got[0].1[0].1
    );
    let text = text.replace("a: $0disableX", "a: disableX").replace("e: failed", "e: $0failed");
    let got = fixes(&[("main.mcl", &text)]);
    assert_eq!(got[0].0, "Declare event `failed`");
    assert!(got[0].1[0].1.starts_with("events {\n    ok;\n    failed;\n}"), "{}", got[0].1[0].1);
}

#[test]
fn quick_fix_arity() {
    let got =
        fixes(&[("main.mcl", "import \"vehicle.mcl\";\nmission {\n    Depth( $015 )\n}\n"), ("vehicle.mcl", VEHICLE)]);
    assert_eq!(got[0].0, "Add the missing argument: mode");
    assert!(got[0].1[0].1.contains("Depth( 15, mode )"));
    let got = fixes(&[
        ("main.mcl", "import \"vehicle.mcl\";\nmission {\n    Goto( $024, 12, 3 )\n}\n"),
        ("vehicle.mcl", VEHICLE),
    ]);
    assert_eq!(got[0].0, "Remove 2 extra arguments");
    assert!(got[0].1[0].1.contains("Goto( 24 )"), "{}", got[0].1[0].1);
    let got =
        fixes(&[("main.mcl", "import \"vehicle.mcl\";\nmission {\n    Depth($0)\n}\n"), ("vehicle.mcl", VEHICLE)]);
    assert!(got[0].1[0].1.contains("Depth( depth, mode )"), "{}", got[0].1[0].1);
}

#[test]
fn diagnostics_map_labels_in_other_files_to_related_information() {
    let f = Fixture::new(&[
        ("main.mcl", "import \"vehicle.mcl\";\nmission {\n    Goto( 1, 2 )\n}\n"),
        ("vehicle.mcl", VEHICLE),
    ]);
    let a = f.analysis();
    let d = diagnostics::full(&a, f.file("main.mcl"));
    assert_eq!(d.len(), 1);
    let d = &d[0];
    assert_eq!(d.code, Some(NumberOrString::String("E0201".into())));
    assert_eq!(d.severity, Some(DiagnosticSeverity::ERROR));
    assert!(
        d.message.starts_with("task `Goto` takes 1 argument but 2 were given\nhelp: a composite value"),
        "{}",
        d.message
    );
    let rel: Vec<String> =
        d.related_information.iter().flatten().map(|r| format!("{} — {}", f.show(&r.location), r.message)).collect();
    assert_eq!(rel, ["vehicle.mcl:15:5: Goto — `Goto( way-point )` is declared here"]);
}

#[test]
fn utf16_positions_after_non_ascii_text() {
    // `é` is one UTF-16 unit but two bytes; `𝄞` is two units and four bytes.
    let f = Fixture::new(&[
        ("main.mcl", "import \"vehicle.mcl\";\n/* é𝄞 */ mission { Gotoo( [1] ) }\n"),
        ("vehicle.mcl", VEHICLE),
    ]);
    let a = f.analysis();
    let d = diagnostics::full(&a, f.file("main.mcl"));
    assert_eq!(d[0].range.start, Position { line: 1, character: 20 });
    assert_eq!(d[0].range.end, Position { line: 1, character: 25 });
}

#[test]
fn apply_edits_helper_works_backwards() {
    let e = |l1, c1, l2, c2, t: &str| TextEdit {
        range: Range { start: Position { line: l1, character: c1 }, end: Position { line: l2, character: c2 } },
        new_text: t.into(),
    };
    assert_eq!(apply_edits("abc\ndef", &[e(0, 1, 0, 2, "X"), e(1, 0, 1, 3, "Y")]), "aXc\nY");
}

/// Every feature at every token of the example corpus: nothing panics, and
/// every call, binding and constraint reference of these valid programs
/// resolves to a definition.
#[test]
fn every_feature_on_the_examples() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples");
    let mut paths: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "mcl"))
        .collect();
    paths.sort();
    assert!(paths.len() >= 8);
    let mut world = World::default();
    let db = mcl_compiler::Database::new();
    for p in &paths {
        let p = mcl_compiler::db::normalize(p);
        let uri = Uri::from_file_path(&p).unwrap();
        world.by_uri.insert(uri.as_str().to_string(), p.clone());
        world.docs.insert(p.clone(), DocInfo { uri, path: p, version: 1 });
    }
    let a = Analysis::new(&db, &world);
    let mut resolved = 0;
    for p in &paths {
        let file = a.file_at(&mcl_compiler::db::normalize(p));
        let text = a.text(file);
        assert!(diagnostics::full(&a, file).iter().all(|d| d.severity != Some(DiagnosticSeverity::ERROR)), "{p:?}");
        for occ in index::occurrences(a.db, file) {
            let must_resolve = matches!(
                occ.role,
                index::Role::Ref(_) | index::Role::BindingTransition { .. } | index::Role::LabelRef { .. }
            );
            if must_resolve {
                let sym = navigation::symbol_at(&a, file, occ.span.start as usize);
                assert!(sym.is_some(), "{p:?}: `{}` ({:?}) does not resolve", occ.name, occ.role);
                resolved += 1;
            }
        }
        for (i, (_, span)) in mcl_syntax::lexer::lex(text).tokens.iter().enumerate().step_by(3) {
            let o = span.start as usize;
            let _ = hover::hover(&a, file, o);
            let _ = navigation::goto_definition(&a, file, o);
            if i % 4 == 0 {
                let _ = navigation::references(&a, file, o, true);
            }
            let _ = navigation::prepare_rename(&a, file, o);
            let _ = completion::completion(&a, file, o, true);
            let _ = completion::signature_help(&a, file, o);
            let _ = navigation::highlights(&a, file, o);
        }
        let _ = outline::document_symbols(&a, file);
        let _ = outline::folding_ranges(&a, file);
        let _ = semantic::semantic_tokens(&a, file);
        let _ = semantic::inlay_hints(&a, file, mcl_syntax::Span::new(0, text.len()));
        let _ = fixes::code_actions(&a, file, mcl_syntax::Span::new(0, text.len()));
    }
    assert!(resolved > 300, "{resolved}");
}

#[test]
fn transitions_of_a_pnml_pattern_go_to_the_pnml_file() {
    let path = mcl_compiler::db::normalize(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/pnml-pattern.mcl"),
    );
    let text = std::fs::read_to_string(&path).unwrap();
    let db = mcl_compiler::Database::new();
    let world = World::default();
    let a = Analysis::new(&db, &world);
    let file = a.file_at(&path);
    let at = text.find("T2, TA;").unwrap();
    let locs = navigation::goto_definition(&a, file, at);
    assert_eq!(locs.len(), 1);
    assert!(locs[0].uri.as_str().ends_with("/examples/patterns/sonar.xml"), "{:?}", locs[0]);
    let xml = std::fs::read_to_string(path.parent().unwrap().join("patterns/sonar.xml")).unwrap();
    let line = xml.lines().nth(locs[0].range.start.line as usize).unwrap();
    assert!(line.contains("id=\"T2\""), "{line}");
    assert!(navigation::prepare_rename(&a, file, at).unwrap_err().0.contains("PNML"));
    let h = hover::hover(&a, file, at).unwrap();
    let HoverContents::Markup(m) = h.contents else { panic!() };
    assert!(m.value.starts_with("```mcl\nT2\n```\ntransition of pattern `P_SONAR`"), "{}", m.value);
}

const APPENDIX_C: &str = include_str!("../../../examples/appendix-c.mcl");

/// The hover text at the first `needle` of `text` (plus `delta` bytes).
fn hover_at(text: &str, needle: &str, delta: usize) -> String {
    let i = text.find(needle).unwrap_or_else(|| panic!("`{needle}`")) + delta;
    let f = Fixture::new(&[("a.mcl", &format!("{}$0{}", &text[..i], &text[i..])), ("vehicle.mcl", VEHICLE)]);
    hover_text(&f)
}

#[test]
fn hover_on_every_keyword() {
    // Every keyword of Appendix C's program (every control structure, the
    // `_mutex_` spellings, every block).
    let f = Fixture::new(&[("a.mcl", APPENDIX_C)]);
    let a = f.analysis();
    let file = f.file("a.mcl");
    let mut seen = std::collections::BTreeSet::new();
    for (tok, span) in mcl_syntax::lexer::lex(APPENDIX_C).tokens {
        let word = &APPENDIX_C[span.range()];
        let expected = match tok {
            mcl_syntax::lexer::Token::Kw(_) if !matches!(word, "at") => {
                if matches!(
                    word,
                    "import"
                        | "actions"
                        | "events"
                        | "pattern"
                        | "places"
                        | "transitions"
                        | "arcs"
                        | "tasks"
                        | "mission"
                        | "constraints"
                ) {
                    "(block)"
                } else {
                    "(control structure)"
                }
            }
            mcl_syntax::lexer::Token::Ident("_mutex_" | "_order_" | "_sync_") => "(coordination constraint)",
            _ => continue,
        };
        for at in [span.start, span.end - 1] {
            let h = hover::hover(&a, file, at as usize).unwrap_or_else(|| panic!("no hover on `{word}` at {at}"));
            let HoverContents::Markup(m) = h.contents else { panic!() };
            assert!(m.value.contains(expected), "`{word}`: {}", m.value);
        }
        seen.insert(word.to_string());
    }
    for w in [
        "monitor",
        "condition",
        "while_condition",
        "do",
        "try",
        "catch",
        "while",
        "not",
        "if",
        "else",
        "parallel",
        "or",
        "and",
    ] {
        assert!(seen.contains(w), "{w} not in the example");
    }
    // The usual constraint spellings, and `then` written for `else` (seed Table B.4).
    let text = MISSION.replace(
        "order { auv:go, asc:wait }",
        "order { auv:go, asc:wait }\n    mutex { auv:dive, asc:wait } = 1\n    sync { auv:go, asc:wait }",
    );
    assert!(hover_at(&text, "order {", 2).contains("**order** (coordination constraint)"));
    assert!(hover_at(&text, "mutex {", 0).contains("At most N of the listed calls"));
    assert!(hover_at(&text, "sync {", 4).contains("**sync**"));
    let text = MISSION.replace("Void() : wait ;", "if ( Void() ) { Void() } then { Void() } ;");
    assert!(hover_at(&text, "then {", 1).contains("**if-then-else**"), "{}", hover_at(&text, "then {", 1));
    assert!(hover_at(&text, "if (", 0).contains("**if-then-else**"));
    // Not on names, nor on the structure's blocks.
    assert!(!hover_at(&text, "} then", 0).contains("control structure"));
}

#[test]
fn folding_covers_every_block_kind() {
    for (name, text) in [("appendix-c", APPENDIX_C), ("mission", MISSION)] {
        let f = Fixture::new(&[("a.mcl", text), ("vehicle.mcl", VEHICLE)]);
        let a = f.analysis();
        let file = f.file("a.mcl");
        let idx = a.line_index(file);
        let folds = outline::folding_ranges(&a, file);
        let starts: std::collections::HashSet<u32> = folds.iter().map(|r| r.start_line).collect();
        let line = |s: Span| idx.line_of(s.start as usize) as u32;
        let want = |s: Span, what: &str| {
            let (l1, l2) = (line(s), idx.line_of(s.end as usize) as u32);
            if l2 > l1 + 1 {
                assert!(starts.contains(&l1), "{name}: {what} at line {l1} has no fold: {folds:?}");
            }
        };
        for item in &a.ast(file).items {
            match item {
                Item::Actions(b) => want(b.span, "actions"),
                Item::Events(b) => want(b.span, "events"),
                Item::Patterns(b) => {
                    want(b.span, "pattern block");
                    b.patterns.iter().for_each(|p| want(p.span, "pattern"));
                }
                Item::Tasks(b) => {
                    want(b.span, "tasks");
                    b.tasks.iter().for_each(|t| want(t.span, "task"));
                }
                Item::Mission(m) => {
                    want(m.span, "mission");
                    mcl_syntax::visit::walk_block(&m.body, &mut |s| {
                        for c in mcl_syntax::visit::child_blocks(s) {
                            want(c.span, "structure block");
                        }
                    });
                }
                Item::Constraints(b) => want(b.span, "constraints"),
                Item::Planning(b) => {
                    want(b.span, "planning");
                    b.defs.iter().for_each(|d| want(d.span(), "planning definition"));
                }
                Item::PddlMap(b) => want(b.span, "pddl_map"),
                Item::Import(_) => {}
            }
        }
        for c in &mcl_compiler::queries::parse(a.db, file).comments {
            if c.kind == mcl_syntax::lexer::CommentKind::Block {
                want(c.span, "block comment");
            }
        }
    }
    // Runs of line comments, a block comment, nested structures of every kind.
    let text = "// a\n// b\n// c\nmission {\n    /* x\n       y\n    */\n    monitor {\n        while ( Void() ) {\n            Void()\n        }\n    } condition ( Void() ) do {\n        not ( Void() )\n    }\n}\n";
    let f = Fixture::new(&[("a.mcl", text)]);
    let a = f.analysis();
    let r: Vec<(u32, u32)> =
        outline::folding_ranges(&a, f.file("a.mcl")).into_iter().map(|r| (r.start_line, r.end_line)).collect();
    for want in [(0, 2), (3, 13), (4, 6), (7, 10), (8, 9), (11, 12)] {
        assert!(r.contains(&want), "{want:?} in {r:?}");
    }
}

#[test]
fn completion_in_every_context() {
    let at = |before: &str, after: &str| -> Vec<String> {
        let i = APPENDIX_C.find(&format!("{before}{after}")).unwrap_or_else(|| panic!("{before}")) + before.len();
        let word = after.split([' ', ';', ',', '\n']).next().unwrap().len();
        completion_labels(&format!("{}$0{}", &APPENDIX_C[..i], &APPENDIX_C[i + word..]))
    };
    // Labels after `mission :` (spaces allowed) and bare labels in `_sync_ {`.
    assert_eq!(at("order { m2:", "asc_ready"), ["asc_ready", "usbl", "receive"]);
    let spaced = APPENDIX_C.replace("order { m2:asc_ready", "_order_ { m2 : asc_ready");
    let i = spaced.find("m2 : asc_ready").unwrap() + 5;
    assert_eq!(completion_labels(&format!("{}$0{}", &spaced[..i], &spaced[i + 9..])), ["asc_ready", "usbl", "receive"]);
    let refs = at("sync { ", "send,");
    assert!(refs.contains(&"m1:send".to_string()) && refs.contains(&"m2:".to_string()), "{refs:?}");
    // Transitions in task bodies, after `->` and after `,`.
    let trs = ["TT0", "TT1", "TT2", "TT3", "T0", "T1", "T2", "T3", "T6", "T7"];
    assert_eq!(at("a: disableInit -> ", "T1, T6"), trs);
    assert_eq!(at("e: eventInitOk -> ", "T2;"), trs);
    assert_eq!(at("a: disableInit -> T1, ", "T6, T7"), trs);
    // Arcs: a place is followed by a transition, a transition by a place.
    assert_eq!(at("begin.1 -> ", "TT0;\n            off"), trs);
    let places = at("T0 -> ", "exe;\n            exe");
    assert!(places.contains(&"exe".to_string()) && !places.contains(&"T1".to_string()), "{places:?}");
    let any = at("arcs {\n            ", "begin.1 -> TT0");
    assert!(any.contains(&"exe".to_string()) && any.contains(&"T1".to_string()), "{any:?}");
    // Patterns after `):`, tasks in a monitor's condition.
    assert_eq!(
        at("Init(): ", "P_TASK {\n        a: enableInit"),
        ["AchieveOneGoal", "AchieveOneGoalTimed", "Instant", "P_TASK", "P_TIMEOUT"]
    );
    assert!(at("} while_condition ( ", "SonarDetect( object )").contains(&"SonarDetect".to_string()));
}
