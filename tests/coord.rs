//! End to end: the AUV/ASC cooperation of seed 8.4 (examples/auv-asc.mcl)
//! from source to one PNML file per vehicle (seed 6.4, docs/coordination.md).

use mcl_compiler::{Database, Db};
use mcl_coord::{analyze, decentralize, source, Verdict};

#[test]
fn auv_asc_from_source_to_one_pnml_per_vehicle() {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/auv-asc.mcl");
    let db = Database::new();
    let file = db.file(&path);
    let (missions, constraints) = source::load(&db, file).expect("auv-asc.mcl compiles");
    assert_eq!(missions.iter().map(|m| m.name.as_str()).collect::<Vec<_>>(), vec!["auv", "asc"]);
    assert_eq!(constraints.len(), 7);

    let report = analyze(&missions, &constraints).unwrap();
    assert_eq!(report.verdict, Verdict::Free, "{:#?}", report.problems);
    assert_eq!(report.supervisors.len(), 8);

    let vehicles = decentralize(&missions, &report.supervisors).unwrap();
    let dir = std::env::temp_dir().join(format!("mcl-coord-e2e-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut sent = Vec::new();
    let mut received = Vec::new();
    for v in &vehicles {
        let file = dir.join(format!("{}.pnml", v.mission));
        std::fs::write(&file, mcl_net::write_pnml(&v.net).unwrap()).unwrap();
        let back = mcl_net::read_pnml(&std::fs::read_to_string(&file).unwrap()).unwrap();
        assert_eq!(back.place_count(), v.net.place_count());
        let prop = |k: &str| -> Vec<serde_json::Value> {
            let (_, v) = back.properties().iter().find(|(key, _)| key == k).expect(k);
            serde_json::from_str(v).unwrap()
        };
        for s in prop("coord.send") {
            sent.push(format!("{}/{} -> {}", v.mission, s["transition"].as_str().unwrap(), s["to"].as_str().unwrap()));
        }
        for r in prop("coord.receive") {
            let t = back.transition_by_id(r["transition"].as_str().unwrap()).unwrap();
            let mcl_net::TransitionKind::Event(e) = &back.transition(t).unwrap().kind else { panic!("not an event") };
            received.push(format!("{e} -> {}", v.mission));
        }
    }
    sent.sort();
    received.sort();
    // Every firing a vehicle sends is received by the vehicle it is sent to.
    assert_eq!(sent, received);
    assert!(!sent.is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}
