//! Property tests: random nets round-trip through PNML; mutated PNML never
//! makes the reader panic.

use mcl_net::{
    read_pnml, write_pnml, ActionRef, CallBinding, Delay, Net, NetBuilder, Place, PlaceId, Provenance, SourceSpan,
    Transition, TransitionId, TransitionKind,
};
use proptest::prelude::*;

/// Text with the characters that need escaping, whitespace and non-ASCII.
fn text() -> impl Strategy<Value = String> {
    "[a-zA-Z0-9 _&<>\"'\t\n\r\u{e9}\u{4e2d}\u{1F600}:;#=/.-]{0,10}"
}

fn opt_text() -> impl Strategy<Value = Option<String>> {
    prop::option::of(text())
}

fn provenance() -> impl Strategy<Value = Provenance> {
    (
        opt_text(),
        prop::option::of(any::<u32>()),
        opt_text(),
        opt_text(),
        prop::option::of((text(), any::<u32>(), any::<u32>())),
    )
        .prop_map(|(task, call_site, structure, path, span)| Provenance {
            task,
            call_site,
            structure,
            path,
            span: span.map(|(file, start, end)| SourceSpan { file, start, end }),
        })
}

fn delay() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(0.0),
        0.0f64..1e6,
        prop::num::f64::NORMAL.prop_map(f64::abs),
        prop::num::f64::SUBNORMAL.prop_map(f64::abs),
    ]
}

fn kind() -> impl Strategy<Value = TransitionKind> {
    prop_oneof![
        Just(TransitionKind::Immediate),
        text().prop_map(TransitionKind::Event),
        delay().prop_map(|d| TransitionKind::Timed(Delay::Fixed(d))),
        text().prop_map(|p| TransitionKind::Timed(Delay::Param(p))),
    ]
}

fn action() -> impl Strategy<Value = ActionRef> {
    (text(), text(), text(), prop::collection::vec((text(), text()), 0..3))
        .prop_map(|(action, primitive, command, params)| ActionRef { action, primitive, command, params })
}

type TransitionSpec = (String, TransitionKind, Vec<ActionRef>, Option<u32>, Option<CallBinding>, Provenance);

fn binding() -> impl Strategy<Value = CallBinding> {
    (text(), any::<u32>(), opt_text(), prop::collection::vec((text(), text()), 0..3), opt_text())
        .prop_map(|(task, call_site, label, args, role)| CallBinding { task, call_site, label, args, role })
}

#[derive(Debug, Clone)]
struct Spec {
    id: String,
    name: String,
    props: Vec<(String, String)>,
    places: Vec<(String, u32, u32, Provenance)>,
    transitions: Vec<TransitionSpec>,
    arcs: Vec<(bool, usize, usize, u32)>,
}

fn spec() -> impl Strategy<Value = Spec> {
    (
        text(),
        text(),
        prop::collection::vec((text(), text()), 0..3),
        prop::collection::vec((text(), 0u32..4, 0u32..4, provenance()), 0..6),
        prop::collection::vec(
            (
                text(),
                kind(),
                prop::collection::vec(action(), 0..3),
                prop::option::of(any::<u32>()),
                prop::option::of(binding()),
                provenance(),
            ),
            0..6,
        ),
        prop::collection::vec((any::<bool>(), 0usize..6, 0usize..6, 1u32..5), 0..14),
    )
        .prop_map(|(id, name, props, places, transitions, arcs)| Spec {
            id,
            name,
            props,
            places,
            transitions,
            arcs,
        })
}

fn build(s: &Spec) -> Net {
    // Ids are unique by construction; the random part exercises escaping.
    let mut b = NetBuilder::new(format!("net{}", s.id));
    b.name(s.name.clone());
    for (k, v) in &s.props {
        b.property(k.clone(), v.clone());
    }
    for (i, (name, m, iface, prov)) in s.places.iter().enumerate() {
        b.add_place(
            Place::new(format!("p{i}{name}"))
                .with_name(name.clone())
                .with_tokens(*m)
                .with_interface(*iface)
                .with_provenance(prov.clone()),
        );
    }
    for (i, (name, kind, actions, prio, binding, prov)) in s.transitions.iter().enumerate() {
        let mut t = Transition::new(format!("t{i}{name}"))
            .with_name(name.clone())
            .with_kind(kind.clone())
            .with_provenance(prov.clone());
        t.actions = actions.clone();
        t.priority = *prio;
        t.binding = binding.clone().map(Box::new);
        b.add_transition(t);
    }
    let (np, nt) = (s.places.len(), s.transitions.len());
    if np > 0 && nt > 0 {
        for &(input, p, t, w) in &s.arcs {
            let (p, t) = (PlaceId((p % np) as u32), TransitionId((t % nt) as u32));
            if input {
                b.add_input(p, t, w);
            } else {
                b.add_output(t, p, w);
            }
        }
    }
    b.build().expect("generated nets are valid")
}

#[derive(Debug, Clone)]
enum Mutation {
    Delete(usize, usize),
    Insert(usize, String),
    Duplicate(usize, usize),
    Truncate(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let snippet = prop_oneof![
        Just("<".to_string()),
        Just(">".to_string()),
        Just("&".to_string()),
        Just("\"".to_string()),
        Just("</place>".to_string()),
        Just("<page id=\"x\">".to_string()),
        Just("<toolspecific tool=\"mcl\" version=\"1\"><kind type=\"timed\"/></toolspecific>".to_string()),
        Just("<text>99999999999</text>".to_string()),
        Just("&#0;".to_string()),
        Just("<![CDATA[x]]>".to_string()),
        "[ -~]{1,8}",
    ];
    prop_oneof![
        (any::<usize>(), 1usize..20).prop_map(|(a, n)| Mutation::Delete(a, n)),
        (any::<usize>(), snippet).prop_map(|(a, s)| Mutation::Insert(a, s)),
        (any::<usize>(), 1usize..200).prop_map(|(a, n)| Mutation::Duplicate(a, n)),
        any::<usize>().prop_map(Mutation::Truncate),
    ]
}

fn apply(doc: &str, muts: &[Mutation]) -> String {
    let mut chars: Vec<char> = doc.chars().collect();
    for m in muts {
        let len = chars.len().max(1);
        match m {
            Mutation::Delete(a, n) => {
                let a = a % len;
                let b = (a + n).min(chars.len());
                if a < b {
                    chars.drain(a..b);
                }
            }
            Mutation::Insert(a, s) => {
                let a = a % (chars.len() + 1);
                chars.splice(a..a, s.chars());
            }
            Mutation::Duplicate(a, n) => {
                let a = a % len;
                let b = (a + n).min(chars.len());
                if a < b {
                    let piece: Vec<char> = chars[a..b].to_vec();
                    chars.splice(b..b, piece);
                }
            }
            Mutation::Truncate(a) => chars.truncate(a % len),
        }
    }
    chars.into_iter().collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn random_nets_round_trip(s in spec()) {
        let net = build(&s);
        let xml = write_pnml(&net).unwrap();
        let back = read_pnml(&xml).unwrap();
        prop_assert_eq!(&back, &net);
        prop_assert_eq!(write_pnml(&back).unwrap(), xml);
    }

    #[test]
    fn mutated_pnml_never_panics(s in spec(), muts in prop::collection::vec(mutation(), 1..6)) {
        let xml = write_pnml(&build(&s)).unwrap();
        let doc = apply(&xml, &muts);
        match read_pnml(&doc) {
            Ok(net) => {
                // Whatever was accepted is a valid net that round-trips.
                if let Ok(again) = write_pnml(&net) {
                    prop_assert_eq!(read_pnml(&again).unwrap(), net);
                }
            }
            Err(e) => {
                let lines = doc.lines().count() + 1;
                prop_assert!(e.line <= lines, "line {} of {}", e.line, lines);
                prop_assert!(!e.message.is_empty());
            }
        }
    }
}
