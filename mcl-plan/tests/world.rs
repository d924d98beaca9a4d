//! The world modeler on the seed's own fact-provider scripts (Extracts 7.6
//! and 7.7, copied as printed: raw `<` in attributes, `recovery\_location`).

use mcl_plan::world::{parse_scripts, Entity, Operand, Percept, WorldModeler};
use mcl_plan::{parse_domain, parse_problem, Fact};

const EXTRACT_7_6: &str = r#"<script id="low_battery">
  <condition value1="auv.battery" type1="perception"
operator="<" value2="30" type2="literal"/>
  <del value1="ictineu" type1="vehicle" prop="batteryOk"/>
  <add value1="ictineu" type1="vehicle" prop="batteryLow"/>
</script>"#;

const EXTRACT_7_7: &str = r#"<script id="recovery\_location">
  <condition value1="auv.x" type1="perception"
    operator=">" value2="-2" type2="literal"/>
  <condition value1="auv.x" type1="perception"
    operator="<" value2="2" type2="literal"/>
  <condition value1="auv.y" type1="perception"
    operator=">" value2="-2" type2="literal"/>
  <condition value1="auv.y" type1="perception"
    operator="<" value2="2" type2="literal"/>
  <condition value1="auv.z" type1="perception"
    operator="<" value2="0.2" type2="literal"/>
  <condition value1="auv.z" type1="perception"
    operator=">" value2="0.0" type2="literal"/>
  <del value1="ictineu" type1="vehicle" prop="in"
    value2="forall" type2="location"/>
  <add value1="ictineu" type1="vehicle" prop="in"
    value2="recovery" type2="location"/>
</script>"#;

fn modeler() -> WorldModeler {
    let d = parse_domain(
        "d",
        "(define (domain auv) (:types vehicle location)
           (:predicates (in ?v - vehicle ?l - location) (batteryok ?v - vehicle) (batterylow ?v - vehicle)))",
    )
    .unwrap();
    let p = parse_problem(
        "p",
        "(define (problem p) (:domain auv) (:objects ictineu - vehicle dock survey recovery - location)
           (:init (in ictineu dock) (in ictineu survey) (batteryok ictineu)) (:goal (in ictineu recovery)))",
    )
    .unwrap();
    let scripts = parse_scripts("scripts.xml", &format!("{EXTRACT_7_6}\n{EXTRACT_7_7}")).unwrap();
    WorldModeler::new(scripts, &d, &p).unwrap()
}

fn facts(w: &WorldModeler) -> Vec<String> {
    w.facts().iter().map(|f| f.to_string()).collect()
}

#[test]
fn parses_the_seeds_scripts() {
    let s = parse_scripts("x", &format!("{EXTRACT_7_6}{EXTRACT_7_7}")).unwrap();
    assert_eq!(s.len(), 2);
    assert_eq!(s[0].id, "low_battery");
    assert_eq!(s[1].id, "recovery_location");
    assert_eq!(s[0].conditions[0].left, Operand::Perception("auv.battery".into()));
    assert_eq!(s[0].conditions[0].right, Operand::Literal(Percept::Num(30.0)));
    assert_eq!(s[1].conditions.len(), 6);
    assert_eq!(s[1].del[0].args[1].0, Entity::Forall);
    // Escaped operators and a root element are accepted too.
    let s = parse_scripts("x", "<world><script id='a'><condition value1='p' type1='perception' operator='&lt;=' value2='1' type2='literal'/></script></world>").unwrap();
    assert_eq!(s[0].conditions.len(), 1);
}

#[test]
fn script_errors_are_located() {
    let e = parse_scripts("w.xml", "<script id='a'>\n<condition value1='p' type1='perception' operator='~' value2='1' type2='literal'/>\n</script>").unwrap_err();
    assert!(e.starts_with("w.xml:2: unknown operator \"~\""), "{e}");
    let e = parse_scripts("w.xml", "<script id='a'>\n<add value1='x' prop='p'/></script>").unwrap_err();
    assert!(e.contains("`<add>` needs the attribute `type1`"), "{e}");
    let e = parse_scripts("w.xml", "<add value1='x' type1='t' prop='p'/>").unwrap_err();
    assert!(e.contains("outside a `<script>`"), "{e}");
    let e = parse_scripts("w.xml", "<script id='a'>").unwrap_err();
    assert!(e.contains("not closed"), "{e}");
    let e = parse_scripts(
        "w.xml",
        "<script id='a'><condition value1='p' type1='sensor' operator='=' value2='1' type2='literal'/></script>",
    )
    .unwrap_err();
    assert!(e.contains("must be \"perception\" or \"literal\""), "{e}");
    // Unknown objects and types in effects.
    let d = parse_domain("d", "(define (domain auv) (:types vehicle) (:predicates (ok ?v - vehicle)))").unwrap();
    let p = parse_problem(
        "p",
        "(define (problem p) (:domain auv) (:objects ictineu - vehicle) (:init) (:goal (ok ictineu)))",
    )
    .unwrap();
    let s = parse_scripts("x", EXTRACT_7_7).unwrap();
    assert!(WorldModeler::new(s, &d, &p).unwrap_err().contains("unknown type `location`"));
    let s = parse_scripts(
        "x",
        &EXTRACT_7_6.replace(
            "\"ictineu\" type1=\"vehicle\" prop=\"batteryLow\"",
            "\"sparus\" type1=\"vehicle\" prop=\"batteryLow\"",
        ),
    )
    .unwrap();
    assert!(WorldModeler::new(s, &d, &p).unwrap_err().contains("`sparus` is not an object of type `vehicle`"));
}

#[test]
fn low_battery_extract_7_6() {
    let mut w = modeler();
    assert!(w.perceive("auv.battery", Percept::Num(55.0)).is_empty());
    assert!(facts(&w).contains(&"(batteryok ictineu)".to_string()));
    let ch = w.perceive("auv.battery", Percept::Num(29.5));
    assert_eq!(ch.len(), 2);
    assert_eq!(
        (ch[0].fact.to_string(), ch[0].added, ch[1].fact.to_string(), ch[1].added),
        ("(batteryok ictineu)".into(), false, "(batterylow ictineu)".into(), true)
    );
    assert_eq!(ch[0].script, "low_battery");
    // Nothing changes when the script applies again.
    assert!(w.perceive("auv.battery", Percept::Num(20.0)).is_empty());
}

#[test]
fn recovery_location_extract_7_7_with_forall() {
    let mut w = modeler();
    w.perceive("auv.x", Percept::Num(0.5));
    w.perceive("auv.y", Percept::Num(-1.0));
    // auv.z not received yet: its conditions are false.
    assert!(facts(&w).contains(&"(in ictineu dock)".to_string()));
    let ch = w.perceive("auv.z", Percept::Num(0.1));
    assert_eq!(ch.len(), 3, "{ch:?}");
    assert_eq!(facts(&w), ["(batteryok ictineu)", "(in ictineu recovery)"]);
    // Too deep: the script does not apply; the facts stay.
    w.set_facts([Fact::new("in", &["ictineu", "dock"])]);
    assert!(w.perceive("auv.z", Percept::Num(5.0)).is_empty());
    assert_eq!(facts(&w), ["(in ictineu dock)"]);
    assert_eq!(w.perception("auv.z"), Some(&Percept::Num(5.0)));
}

#[test]
fn text_perceptions_compare_as_text() {
    let d = parse_domain("d", "(define (domain a) (:types robot) (:predicates (docked ?r - robot)))").unwrap();
    let p =
        parse_problem("p", "(define (problem p) (:domain a) (:objects r - robot) (:init) (:goal (docked r)))").unwrap();
    let s = parse_scripts("x", r#"<script id="d"><condition value1="status" type1="perception" operator="=" value2="docked" type2="literal"/><add value1="r" type1="robot" prop="docked"/></script>"#).unwrap();
    let mut w = WorldModeler::new(s, &d, &p).unwrap();
    assert!(w.perceive("status", Percept::parse("moving")).is_empty());
    assert_eq!(w.perceive("status", Percept::parse("docked")).len(), 1);
}
