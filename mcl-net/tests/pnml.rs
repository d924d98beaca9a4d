//! PNML reading, writing and round trips.

use mcl_net::{
    read_pnml, read_pnml_nets, write_pnml, ActionRef, CallBinding, Delay, NetBuilder, Place, Provenance, SourceSpan,
    Transition, TransitionKind,
};

fn sample_net() -> mcl_net::Net {
    let mut b = NetBuilder::new("mission-auv");
    b.name("auv <mission> & \"friends\"").property("vehicle", "auv").property("note", "two\nlines");
    let begin = b.add_place(Place::new("begin").with_tokens(1).with_interface(1).with_provenance(Provenance {
        task: Some("Goto".into()),
        call_site: Some(3),
        structure: Some("sequence".into()),
        path: Some("0.1".into()),
        span: Some(SourceSpan { file: "missions/dam.mcl".into(), start: 10, end: 42 }),
    }));
    let running = b.add_place(Place::new("running").with_name("  spaced\tname\r\n"));
    let ok = b.add_place(Place::new("ok").with_interface(1));
    let start = b.add_transition(Transition::new("start").with_priority(2).with_action(ActionRef {
        action: "Goto".into(),
        primitive: "goto".into(),
        command: "enable".into(),
        params: vec![("x".into(), "24".into()), ("y".into(), "-2.5".into())],
    }));
    if let Some(t) = b.transition_mut(start) {
        t.binding = Some(Box::new(CallBinding {
            task: "Goto".into(),
            call_site: 3,
            label: Some("first".into()),
            args: vec![("way-point".into(), "[24, 12]".into())],
            role: Some("while_condition".into()),
        }));
    }
    let done = b.add_transition(Transition::new("done").with_kind(TransitionKind::Event("goto_ok".into())));
    let timeout =
        b.add_transition(Transition::new("timeout").with_kind(TransitionKind::Timed(Delay::Param("timeout".into()))));
    let tick = b.add_transition(Transition::new("tick").with_kind(TransitionKind::Timed(Delay::Fixed(0.1 + 0.2))));
    b.add_input(begin, start, 1).add_output(start, running, 3);
    b.add_input(running, done, 3).add_output(done, ok, 1);
    b.add_input(running, timeout, 2).add_output(timeout, ok, 1);
    b.add_input(ok, tick, 1).add_output(tick, ok, 1);
    b.build().unwrap()
}

#[test]
fn round_trip_keeps_every_field() {
    let net = sample_net();
    let xml = write_pnml(&net).unwrap();
    let back = read_pnml(&xml).unwrap();
    assert_eq!(back, net);
    // And the text is stable.
    assert_eq!(write_pnml(&back).unwrap(), xml);
}

#[test]
fn written_pnml_is_standard_for_other_tools() {
    let xml = write_pnml(&sample_net()).unwrap();
    assert!(xml.starts_with("<?xml version=\"1.0\" encoding=\"UTF-8\"?>"));
    assert!(xml.contains("<pnml xmlns=\"http://www.pnml.org/version-2009/grammar/pnml\">"));
    assert!(xml.contains("type=\"http://www.pnml.org/version-2009/grammar/ptnet\""));
    assert!(xml.contains("<initialMarking>\n          <text>1</text>"));
    assert!(xml.contains("<inscription>\n          <text>3</text>"));
    assert!(xml.contains("<toolspecific tool=\"mcl\" version=\"1\">"));
}

const PLAIN: &str = r#"<?xml version="1.0"?>
<pnml xmlns="http://www.pnml.org/version-2009/grammar/pnml">
  <net id="n" type="http://www.pnml.org/version-2009/grammar/ptnet">
    <page id="top">
      <place id="p"><name><text>P</text></name><initialMarking><text> 2 </text></initialMarking>
        <graphics><position x="1" y="2"/></graphics></place>
      <page id="inner">
        <transition id="t"><toolspecific tool="other" version="9"><anything deep="yes"><x/></anything></toolspecific></transition>
        <page id="innermost"><place id="q"/></page>
      </page>
      <arc id="a1" source="p" target="t"><inscription><text>2</text></inscription></arc>
    </page>
    <page id="second">
      <arc id="a2" source="t" target="q"/>
    </page>
    <name><text>Net name after the pages</text></name>
    <toolspecific tool="nupn" version="1.1"><size places="2" transitions="1" arcs="2"/></toolspecific>
  </net>
</pnml>"#;

#[test]
fn reads_nested_and_multiple_pages_and_skips_other_tools() {
    let net = read_pnml(PLAIN).unwrap();
    assert_eq!(net.name(), "Net name after the pages");
    let ids: Vec<_> = net.places().iter().map(|p| p.id.as_str()).collect();
    assert_eq!(ids, ["p", "q"]);
    assert_eq!(net.places()[0].name, "P");
    assert_eq!(net.places()[0].initial, 2);
    assert_eq!(net.places()[1].name, "q");
    let t = net.transition_by_id("t").unwrap();
    assert_eq!(net.transitions()[0].kind, TransitionKind::Immediate);
    assert_eq!(net.pre(t), &[(net.place_by_id("p").unwrap(), 2)]);
    assert_eq!(net.post(t), &[(net.place_by_id("q").unwrap(), 1)]);
}

#[test]
fn reads_several_nets() {
    let doc = PLAIN.replace(
        "</net>\n</pnml>",
        "</net>\n<net id=\"m\" type=\"http://www.pnml.org/version-2009/grammar/ptnet\"><page id=\"x\"/></net></pnml>",
    );
    assert_eq!(read_pnml_nets(&doc).unwrap().len(), 2);
    let err = read_pnml(&doc).unwrap_err();
    assert!(err.message.contains("2 nets"), "{err}");
}

fn err(doc: &str) -> mcl_net::PnmlError {
    read_pnml(doc).expect_err("document should be rejected")
}

fn wrap(body: &str) -> String {
    format!(
        "<pnml xmlns=\"http://www.pnml.org/version-2009/grammar/pnml\">\n<net id=\"n\" type=\"http://www.pnml.org/version-2009/grammar/ptnet\">\n<page id=\"pg\">\n{body}\n</page></net></pnml>"
    )
}

#[test]
fn errors_carry_line_and_column() {
    let e = err("<pnml>\n  <net id=\"n\">\n    <page>\n  </net>\n</pnml>");
    assert_eq!((e.line, e.column), (4, 3), "{e}");
    assert!(e.message.contains("malformed XML"), "{e}");

    let e = err(&wrap("<place id=\"p\"><initialMarking><text>-1</text></initialMarking></place>"));
    assert_eq!(e.line, 4, "{e}");
    assert!(e.message.contains("whole number"), "{e}");

    let e = err(&wrap("<place id=\"p\"/>\n<arc id=\"a\" source=\"p\" target=\"nowhere\"/>"));
    assert_eq!((e.line, e.column), (5, 1), "{e}");
    assert!(e.message.contains("nowhere"), "{e}");

    let e = err(&wrap("<place id=\"p\"/><place id=\"q\"/><arc id=\"a\" source=\"p\" target=\"q\"/>"));
    assert!(e.message.contains("place and a transition"), "{e}");

    let e = err(&wrap("<place id=\"p\"/><place id=\"p\"/>"));
    assert!(e.message.contains("duplicate"), "{e}");

    let e = err(&wrap("<referencePlace id=\"r\" ref=\"p\"/>"));
    assert!(e.message.contains("referencePlace"), "{e}");

    let e = err(&wrap("<place id=\"p\"/><transition id=\"t\"/><arc id=\"a\" source=\"p\" target=\"t\"><inscription><text>0</text></inscription></arc>"));
    assert!(e.message.contains("at least 1"), "{e}");

    let e = err(&wrap("<transition id=\"t\"><toolspecific tool=\"mcl\" version=\"1\"><kind type=\"timed\" delay=\"-3\"/></toolspecific></transition>"));
    assert!(e.message.contains("delay"), "{e}");

    let e = err(&wrap("<transition id=\"t\"><toolspecific tool=\"mcl\" version=\"2\"/></transition>"));
    assert!(e.message.contains("version"), "{e}");

    let e = err("<pnml><net id=\"n\" type=\"http://www.pnml.org/version-2009/grammar/symmetricnet\"><page id=\"p\"/></net></pnml>");
    assert!(e.message.contains("unsupported net type"), "{e}");

    let e = err("<pnml><net id=\"n\" type=\"http://www.pnml.org/version-2009/grammar/ptnet\"><page id=\"p\">&bogus;</page></net></pnml>");
    assert!(e.message.contains("bogus"), "{e}");

    let e = err("");
    assert!(e.message.contains("no root"), "{e}");
    let e = err("<pnml></pnml><pnml></pnml>");
    assert!(e.message.contains("root"), "{e}");
    let e = err("<pnml><net>");
    assert!(e.message.contains("not closed"), "{e}");
}

#[test]
fn rejects_deep_nesting_without_overflowing_the_stack() {
    let doc = format!("<pnml>{}{}</pnml>", "<a>".repeat(100_000), "</a>".repeat(100_000));
    let e = err(&doc);
    assert!(e.message.contains("nested"), "{e}");
}

#[test]
fn writer_rejects_characters_xml_cannot_hold() {
    let mut b = NetBuilder::new("n");
    b.add_place(Place::new("p").with_name("bad\u{0}name"));
    let e = write_pnml(&b.build().unwrap()).unwrap_err();
    assert!(e.message.contains("U+0000"), "{e}");
}

#[test]
fn reads_every_mcc_net() {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/data/mcc");
    let entries = std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    let mut n = 0;
    for e in entries.flatten() {
        let path = e.path();
        if path.extension().is_some_and(|x| x == "pnml") {
            let text = std::fs::read_to_string(&path).unwrap();
            let net = read_pnml(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(!net.has_non_immediate());
            let back = read_pnml(&write_pnml(&net).unwrap()).unwrap();
            assert_eq!(back, net, "{}", path.display());
            n += 1;
        }
    }
    assert!(n > 0);
}

/// Provenance is written once per record, with the nodes it belongs to as
/// index ranges; nodes whose name is their id carry no `<name>`; both read
/// back to an equal net, and the nodes share one record again. Files with a
/// record in each node (as written before the table) still load.
#[test]
fn provenance_is_written_once_per_record() {
    let shared = std::sync::Arc::new(Provenance {
        task: None,
        call_site: Some(7),
        structure: Some("call".into()),
        path: Some("m.0".into()),
        span: Some(SourceSpan { file: "m.mcl".into(), start: 1, end: 9 }),
    });
    let other = std::sync::Arc::new(Provenance { structure: Some("sequence".into()), ..Provenance::default() });
    let mut b = NetBuilder::new("n");
    let mut ps = Vec::new();
    for i in 0..6 {
        let prov = if i == 3 { other.clone() } else { shared.clone() };
        let mut p = Place::new(format!("p{i}"));
        p.provenance = prov;
        ps.push(b.add_place(p));
    }
    let mut t = Transition::new("t");
    t.provenance = shared.clone();
    let t = b.add_transition(t);
    b.add_input(ps[0], t, 1).add_output(t, ps[1], 1);
    let net = b.build().unwrap();
    let xml = write_pnml(&net).unwrap();
    assert_eq!(xml.matches("<provenance").count(), 2, "{xml}");
    assert!(xml.contains(r#"places="0-2 4-5" transitions="0""#), "{xml}");
    assert!(xml.contains(r#"places="3""#), "{xml}");
    assert!(!xml.contains("<name>\n        <text>p0"), "names equal to ids are not written: {xml}");
    let back = read_pnml(&xml).unwrap();
    assert_eq!(back, net);
    let p0 = &back.places()[0].provenance;
    assert!(back.places().iter().enumerate().all(|(i, p)| i == 3 || std::sync::Arc::ptr_eq(&p.provenance, p0)));

    let old = r#"<pnml xmlns="http://www.pnml.org/version-2009/grammar/pnml"><net id="n" type="http://www.pnml.org/version-2009/grammar/ptnet"><page id="g">
        <place id="p"><toolspecific tool="mcl" version="1"><provenance structure="call" callSite="7" path="m.0" file="m.mcl" start="1" end="9"/></toolspecific></place>
        </page></net></pnml>"#;
    let n = read_pnml(old).unwrap();
    assert_eq!(n.places()[0].provenance.call_site, Some(7));
    // A range beyond the net is an error with a location, not a panic.
    let bad = xml.replace(r#"places="3""#, r#"places="30""#);
    let e = read_pnml(&bad).unwrap_err().to_string();
    assert!(e.contains("place #30"), "{e}");
}

#[test]
fn page_and_arc_ids_avoid_node_ids_of_their_shape() {
    // Nodes named like the ids the writer makes up (`page0`, `a<i>`): the
    // page and the arcs get other ids, and the net reads back the same.
    let mut b = NetBuilder::new("a2");
    let p = b.add_place(Place::new("page0").with_tokens(1));
    let q = b.add_place(Place::new("a0"));
    let t = b.add_transition(Transition::new("a1_"));
    let u = b.add_transition(Transition::new("a1"));
    b.add_input(p, t, 1).add_output(t, q, 1).add_input(q, u, 1).add_output(u, p, 1);
    let net = b.build().unwrap();
    let xml = write_pnml(&net).unwrap();
    assert!(xml.contains("<page id=\"page0_\">"), "{xml}");
    for id in ["a0_", "a1__", "a2_", "a3"] {
        assert!(xml.contains(&format!("<arc id=\"{id}\"")), "{id}: {xml}");
    }
    assert_eq!(read_pnml(&xml).unwrap(), net);
}

#[test]
fn streamed_pnml_is_the_same_text() {
    let net = sample_net();
    let mut bytes = Vec::new();
    mcl_net::write_pnml_to(&net, &mut bytes).unwrap();
    assert_eq!(String::from_utf8(bytes).unwrap(), write_pnml(&net).unwrap());
}
