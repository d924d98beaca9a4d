//! Coordination of compiled missions: the mapping of labelled calls, the
//! AUV/ASC cooperation of seed 8.4 (examples/auv-asc.mcl, Extracts
//! 8.3-8.5), and its per-vehicle nets.

use std::path::PathBuf;

use mcl_compiler::compile::calls::call_nodes;
use mcl_compiler::{Database, Db};
use mcl_coord::decentral::{d_admissibility, minimize_communication, vehicle_nets, Costs};
use mcl_coord::source::load;
use mcl_coord::verify::WitnessKind;
use mcl_coord::{analyze, centralize, decentralize, CallRef, Constraint, ConstraintKind, Mission, Origin, Verdict};
use mcl_net::{explore, Options};

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples").join(name)
}

fn auv_asc() -> (Vec<Mission>, Vec<Constraint>) {
    let db = Database::new();
    let file = db.file(&example("auv-asc.mcl"));
    load(&db, file).expect("auv-asc.mcl compiles")
}

fn program(text: &str) -> (Vec<Mission>, Vec<Constraint>) {
    let dir = std::env::temp_dir().join(format!("mcl-coord-{}-{}", std::process::id(), text.len()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(example("vehicle.mcl"), dir.join("vehicle.mcl")).unwrap();
    let path = dir.join("m.mcl");
    std::fs::write(&path, format!("import \"vehicle.mcl\";\n{text}")).unwrap();
    let db = Database::new();
    let file = db.file(&path);
    load(&db, file).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn labelled_calls_map_to_their_adapter_nodes() {
    let (ms, _) = auv_asc();
    let auv = &ms[0];
    assert_eq!(auv.name, "auv");
    let calls = call_nodes(&auv.net);
    let deploy = calls.iter().find(|c| c.label.as_deref() == Some("deploy_auv")).unwrap();
    assert_eq!(deploy.task, "Altitude");
    let a = auv.activities.iter().find(|a| a.label == "deploy_auv").unwrap();
    let id = |t: mcl_net::TransitionId| auv.net.transition(t).unwrap().id.clone();
    let pid = |p: mcl_net::PlaceId| auv.net.place(p).unwrap().id.clone();
    let n = deploy.call_site;
    assert_eq!(a.started.iter().map(|&t| id(t)).collect::<Vec<_>>(), vec![format!("call{n}.start")]);
    assert_eq!(a.ended.iter().map(|&t| id(t)).collect::<Vec<_>>(), vec![format!("call{n}.release")]);
    assert_eq!(
        a.running.iter().map(|&p| pid(p)).collect::<Vec<_>>(),
        vec![format!("call{n}.run"), format!("call{n}.stopping")]
    );
    assert_eq!(a.withdrawn.iter().map(|&t| id(t)).collect::<Vec<_>>(), vec![format!("call{n}.cancel")]);
    assert_eq!(a.waiting.len(), 1);
    assert!(a.arrived.iter().all(|&t| auv.net.post(t).iter().any(|&(p, _)| p == a.waiting[0])));
    // Only the starts of calls are controllable.
    for (t, &c) in auv.controllable.iter().enumerate() {
        assert_eq!(
            c,
            id(mcl_net::TransitionId(t as u32)).ends_with(".start"),
            "{}",
            id(mcl_net::TransitionId(t as u32))
        );
    }
    // The meaning of the mapping, on the ASC alone (all its markings): a call
    // holds its task's lock exactly while it is in a running place.
    let asc = &ms[1];
    let ss = explore(&asc.net, &Options::default());
    assert!(ss.complete());
    for c in call_nodes(&asc.net) {
        let lock = asc.net.place_by_id(&format!("lock.{}", c.task)).unwrap();
        let others: Vec<_> =
            call_nodes(&asc.net).into_iter().filter(|o| o.task == c.task && o.call_site != c.call_site).collect();
        for s in ss.states() {
            let mine = ss.tokens(s, c.run) + ss.tokens(s, c.stopping);
            let theirs: u32 = others.iter().map(|o| ss.tokens(s, o.run) + ss.tokens(s, o.stopping)).sum();
            assert!(mine <= 1);
            assert_eq!(mine + theirs + ss.tokens(s, lock), 1, "call{} of {}", c.call_site, c.task);
        }
    }
}

#[test]
fn auv_asc_constraints_are_free_of_deadlock() {
    let (ms, cs) = auv_asc();
    assert_eq!(cs.len(), 7);
    assert_eq!(cs[2].kind, ConstraintKind::Sync);
    let r = analyze(&ms, &cs).unwrap();
    assert_eq!(r.verdict, Verdict::Free, "{:#?}", r.problems);
    assert!(r.deadlock_free);
    assert!(r.problems.is_empty());
    // Six orders (one supervisor each) and a sync of two calls (two): no
    // supervisor had to be added.
    assert_eq!(r.added, 0);
    assert_eq!(r.supervisors.len(), 8);
    let ids: Vec<&str> = r.supervisors.iter().map(|s| s.id.as_str()).collect();
    assert_eq!(
        ids,
        vec![
            "coord.order1",
            "coord.order2",
            "coord.sync3.1-2",
            "coord.sync3.2-1",
            "coord.order4",
            "coord.order5",
            "coord.order6",
            "coord.order7"
        ]
    );
    // The order ASC Deploy → AUV Altitude: the AUV's start waits for the end
    // of the ASC's Deploy (its `release`: a call that ends ok, fails or is
    // aborted gives its task back there, once).
    let s = &r.supervisors[0];
    assert_eq!(s.origin, Origin::Order { constraint: 0 });
    let t = |t: mcl_net::TransitionId| r.net.transition(t).unwrap().id.clone();
    assert_eq!(s.consumed_by.iter().map(|&(x, _)| t(x)).collect::<Vec<_>>().len(), 1);
    assert!(t(s.consumed_by[0].0).starts_with("auv/call") && t(s.consumed_by[0].0).ends_with(".start"));
    assert_eq!(s.produced_by.len(), 1);
    assert!(s.produced_by.iter().all(|&(x, _)| t(x).starts_with("asc/call")));
    assert_eq!(s.initial, 0);
    // The supervised net carries a description of each supervisor.
    assert!(r.net.properties().iter().any(|(k, v)| k == "coord.supervisor:coord.order1" && v.contains("≤ 0")));
    // The reductions that make this exhaustive check possible.
    // (3,529 markings for the AUV: zero-delay transitions fire before events,
    // by priority, so a call's release waits for the kills, as on the player.)
    assert!(r.stats.vehicle_states[0] > 3_000, "{:?}", r.stats);
    assert!(r.stats.vehicle_classes[0] < r.stats.vehicle_states[0] / 10);
}

#[test]
fn auv_asc_per_vehicle_nets() {
    let (ms, cs) = auv_asc();
    let plant = centralize(&ms).unwrap();
    let sups = mcl_coord::supervisor::synthesize(&plant, &cs).unwrap();
    // Extract 6.2: every supervisor links the two vehicles.
    let adm = d_admissibility(&plant, &sups);
    assert!(adm.iter().all(|a| !a.d_admissible && a.zeta.is_empty() && a.observed_by.len() == 2));
    // Extract 6.3: each supervisor lives in the vehicle whose start it holds,
    // which is told about the firings it observes in the other vehicle.
    let comm = minimize_communication(&plant, &sups, &Costs::default()).unwrap();
    assert!(comm.epsilon.is_empty());
    for (k, s) in sups.iter().enumerate() {
        let holder = plant.owner_of_transition(s.consumed_by[0].0).unwrap();
        assert_eq!(comm.delta.iter().filter(|&&(_, kk)| kk == k).collect::<Vec<_>>(), vec![&(holder, k)]);
    }
    // 6 orders × 1 ending (`release`) + 2 sync supervisors × their arrival transitions.
    let arrivals: usize = sups[2..4].iter().map(|s| s.produced_by.len()).sum();
    assert_eq!(comm.alpha.len(), 6 + arrivals);
    assert!((comm.cost - (comm.alpha.len() as f64 + 8.0 * 0.001)).abs() < 1e-6);

    let vnets = vehicle_nets(&ms, &plant, &sups, &comm).unwrap();
    assert_eq!(vnets.len(), 2);
    let (auv, asc) = (&vnets[0], &vnets[1]);
    assert_eq!(auv.mission, "auv");
    // The AUV holds the order supervisors whose second call is its own.
    let coord_places = |n: &mcl_net::Net| {
        let mut v: Vec<String> =
            n.places().iter().filter(|p| p.id.starts_with("coord.")).map(|p| p.id.to_string()).collect();
        v.sort();
        v
    };
    // Each sync copy has a place for the arrivals the other vehicle
    // withdraws (its call cancelled before it started).
    assert_eq!(
        coord_places(&auv.net),
        vec!["coord.order1", "coord.order4", "coord.sync3.2-1", "coord.sync3.2-1.withdrawn"]
    );
    assert_eq!(
        coord_places(&asc.net),
        vec![
            "coord.order2",
            "coord.order5",
            "coord.order6",
            "coord.order7",
            "coord.sync3.1-2",
            "coord.sync3.1-2.withdrawn"
        ]
    );
    for (v, id) in [(auv, "coord.sync3.2-1"), (asc, "coord.sync3.1-2")] {
        let t = |s: &str| v.net.transition(v.net.transition_by_id(&format!("{id}.{s}")).unwrap()).unwrap().clone();
        // Taking the credit back goes before any start; dropping the
        // withdrawal (the credit was used) only when it cannot.
        assert_eq!((t("withdraw").priority, t("forget").priority), (Some(2), Some(1)));
    }
    // Every message sent is received, and the other way round.
    for (from, to) in [(auv, asc), (asc, auv)] {
        let mut sent: Vec<String> = from
            .send
            .iter()
            .filter(|(_, m)| m == &to.mission)
            .map(|(t, _)| format!("coord.recv.{}.{t}", from.mission))
            .collect();
        let mut got: Vec<String> =
            to.receive.iter().filter(|(_, m)| m == &from.mission).map(|(t, _)| t.clone()).collect();
        sent.sort();
        got.sort();
        assert_eq!(sent, got);
    }
    // The ASC tells the AUV when its Deploy ends.
    let deploy = call_nodes(&ms[1].net).into_iter().find(|c| c.label.as_deref() == Some("deploy_auv")).unwrap();
    // (A call ends once, at `release`, whether it ended ok, failed or was aborted.)
    assert!(asc.send.contains(&(format!("call{}.release", deploy.call_site), "auv".to_string())));
    for end in ["ok", "fail"] {
        assert!(!asc.send.contains(&(format!("call{}.{end}", deploy.call_site), "auv".to_string())));
    }
    let recv = auv.net.transition_by_id(&format!("coord.recv.asc.call{}.release", deploy.call_site)).unwrap();
    assert_eq!(
        auv.net.transition(recv).unwrap().kind,
        mcl_net::TransitionKind::Event(format!("asc/call{}.release", deploy.call_site))
    );
    // The lists survive PNML.
    for v in &vnets {
        let xml = mcl_net::write_pnml(&v.net).unwrap();
        let back = mcl_net::read_pnml(&xml).unwrap();
        let send = back.properties().iter().find(|(k, _)| k == "coord.send").unwrap();
        let list: Vec<serde_json::Value> = serde_json::from_str(&send.1).unwrap();
        assert_eq!(list.len(), v.send.len());
        assert!(back.properties().iter().any(|(k, _)| k == "coord.receive"));
    }
    // The convenience entry point gives the same nets.
    let again = decentralize(&ms, &sups).unwrap();
    assert_eq!(
        again.iter().map(|v| v.send.clone()).collect::<Vec<_>>(),
        vnets.iter().map(|v| v.send.clone()).collect::<Vec<_>>()
    );
}

#[test]
fn a_cycle_of_orders_between_compiled_missions_is_an_unavoidable_deadlock() {
    let (ms, cs) = program(
        "mission : a { Goto( p1 ) : first ; Goto( p2 ) : second }
         mission : b { Goto( p3 ) : first ; Goto( p4 ) : second }
         constraints {
             order { a:second, b:first }
             order { b:second, a:first }
         }",
    );
    let r = analyze(&ms, &cs).unwrap();
    assert_eq!(r.verdict, Verdict::Deadlock);
    assert_eq!(r.problems.len(), 1, "{:#?}", r.problems);
    let p = &r.problems[0];
    assert_eq!(p.kind, WitnessKind::Dead);
    assert_eq!(p.constraints, vec![0, 1]);
    let mut w = p.waiting.clone();
    w.sort();
    assert_eq!(w, vec!["a:first", "b:first"]);
    assert!(p.refusal.is_some(), "{p:#?}");
    // The counterexample replays on the centralized net and ends dead.
    let mut m = r.net.initial_marking();
    for id in &p.counterexample {
        mcl_net::semantics::fire(&r.net, &mut m, r.net.transition_by_id(id).unwrap()).unwrap();
    }
    assert!(mcl_net::semantics::enabled(&r.net, &m).is_empty());
}

#[test]
fn mutex_between_compiled_missions_holds_and_is_free_of_deadlock() {
    let (ms, cs) = program(
        "mission : a { parallel { Goto( p1 ) : g } and { Surface() : s } }
         mission : b { Goto( p3 ) : g ; Surface() : s }
         constraints {
             mutex { a:g, b:g } = 1
             mutex { a:s, b:s, a:g } = 2
         }",
    );
    let r = analyze(&ms, &cs).unwrap();
    assert_eq!(r.verdict, Verdict::Free, "{:#?}", r.problems);
    let ss = explore(&r.net, &Options::default());
    assert!(ss.complete());
    let run = |m: &str, l: &str| {
        let i = ms.iter().position(|x| x.name == m).unwrap();
        let a = ms[i].activities.iter().find(|a| a.label == l).unwrap();
        a.running
            .iter()
            .map(|&p| r.net.place_by_id(&format!("{m}/{}", ms[i].net.place(p).unwrap().id)).unwrap())
            .collect::<Vec<_>>()
    };
    let sum = |s, ps: &[mcl_net::PlaceId]| ps.iter().map(|&p| ss.tokens(s, p)).sum::<u32>();
    for s in ss.states() {
        assert!(sum(s, &run("a", "g")) + sum(s, &run("b", "g")) <= 1);
        assert!(sum(s, &run("a", "s")) + sum(s, &run("b", "s")) + sum(s, &run("a", "g")) <= 2);
    }
    assert!(ss.dead_states().all(|d| {
        let m = ss.marking(d);
        ["a/mission.ok", "a/mission.fail"].iter().any(|id| m.get(r.net.place_by_id(id).unwrap()) == 1)
            && ["b/mission.ok", "b/mission.fail"].iter().any(|id| m.get(r.net.place_by_id(id).unwrap()) == 1)
    }));
    let _ = CallRef::new("a", "g");
}
