//! The worked example of seed 6.1 as an oracle: two 3-task missions
//! (Figure 6.2), the mutex {P2, P5} with β = 1 (6.5-6.12), the order
//! {P5, P2} (6.13-6.23) and the synchronization {P2, P5} (6.24, 6.25).

use mcl_coord::compact::{place, pw_transform, sequence, transition};
use mcl_coord::supervisor::{apply, synthesize};
use mcl_coord::{centralize, Activity, CallRef, Constraint, Mission, Origin};
use mcl_net::structural::incidence;
use mcl_net::{explore, Net, Options, Semantics};

/// Figure 6.2: `P1 -T1-> P2 -T2-> P3` and `P4 -T3-> P5 -T4-> P6`.
fn v1() -> Net {
    sequence("v1", &["P1", "P2", "P3"], &["T1", "T2"])
}

fn v2() -> Net {
    sequence("v2", &["P4", "P5", "P6"], &["T3", "T4"])
}

/// A compact mission with one activity per task place.
fn mission(name: &str, net: Net, tasks: &[&str], first: &str, last: &str) -> Mission {
    let acts: Vec<Activity> = tasks.iter().map(|t| Activity::region(&net, *t, &[place(&net, t)])).collect();
    let (p0, pf) = (place(&net, first), place(&net, last));
    let mut m = Mission::new(name, net, vec![p0], vec![pf]);
    m.activities = acts;
    m
}

fn matrix(net: &Net) -> Vec<Vec<i64>> {
    let d = incidence(net);
    net.place_ids().map(|p| d.row(p).to_vec()).collect()
}

fn marking(net: &Net) -> Vec<u32> {
    net.initial_marking().0
}

#[test]
fn incidence_of_each_mission_6_1_to_6_4() {
    for net in [v1(), v2()] {
        assert_eq!(matrix(&net), vec![vec![-1, 0], vec![1, -1], vec![0, 1]]);
        assert_eq!(marking(&net), vec![1, 0, 0]);
    }
}

#[test]
fn mutex_p2_p5_beta_1_equations_6_6_to_6_12() {
    let m1 = mission("v1", v1(), &["P1", "P2", "P3"], "P1", "P3");
    let m2 = mission("v2", v2(), &["P4", "P5", "P6"], "P4", "P6");
    let plant = centralize(&[m1, m2]).unwrap();
    // (6.7), (6.8): the centralized net.
    #[rustfmt::skip]
    let d_v1v2 = vec![
        vec![-1, 0, 0, 0],
        vec![1, -1, 0, 0],
        vec![0, 1, 0, 0],
        vec![0, 0, -1, 0],
        vec![0, 0, 1, -1],
        vec![0, 0, 0, 1],
    ];
    assert_eq!(matrix(&plant.net), d_v1v2);
    assert_eq!(marking(&plant.net), vec![1, 0, 0, 1, 0, 0]);

    let c = Constraint::mutex([CallRef::new("v1", "P2"), CallRef::new("v2", "P5")], 1);
    let sups = synthesize(&plant, std::slice::from_ref(&c)).unwrap();
    assert_eq!(sups.len(), 1);
    let s = &sups[0];
    // (6.6): l = [0 1 0 0 1 0], b = 1.
    let mut l = vec![0i64; 6];
    for &(p, w) in &s.l {
        l[p.index()] = w;
    }
    assert_eq!(l, vec![0, 1, 0, 0, 1, 0]);
    assert_eq!(s.b, 1);
    assert_eq!(s.describe(&plant.net), "μ(v1/P2) + μ(v2/P5) ≤ 1");
    // (6.9): D_c = −l·D = [−1 1 −1 1]; (6.10): μ_c0 = 1 − l·μ0 = 1.
    assert_eq!(s.row(4), vec![-1, 1, -1, 1]);
    assert_eq!(s.initial, 1);
    // (6.11), (6.12): the supervised net (the seed's text calls them (6.22),
    // (6.23): SEED-NOTES item 11).
    let net = apply(&plant.net, &sups).unwrap();
    let mut d = d_v1v2.clone();
    d.push(vec![-1, 1, -1, 1]);
    assert_eq!(matrix(&net), d);
    assert_eq!(marking(&net), vec![1, 0, 0, 1, 0, 0, 1]);

    // The constraint holds in every reachable marking and the supervised net
    // still reaches the end of both missions.
    let ss = explore(&net, &Options { semantics: Semantics::Plain, ..Options::default() });
    let (p2, p5) = (place(&net, "v1/P2"), place(&net, "v2/P5"));
    assert!(ss.states().all(|st| ss.tokens(st, p2) + ss.tokens(st, p5) <= 1));
    assert_eq!(ss.dead_states().len(), 1);
    let end = ss.marking(ss.dead_states().next().unwrap());
    assert_eq!(end.0, vec![0, 0, 1, 0, 0, 1, 1]);
}

#[test]
fn order_p5_p2_equations_6_13_to_6_23() {
    let m1 = mission("v1", v1(), &["P1", "P2", "P3"], "P1", "P3");
    let m2 = mission("v2", v2(), &["P4", "P5", "P6"], "P4", "P6");
    let plant = centralize(&[m1, m2]).unwrap();
    // O = {P5, P2}: P2 (waiting) may be marked only once P5 (signalling) has
    // been unmarked.
    let c = Constraint::order(CallRef::new("v2", "P5"), CallRef::new("v1", "P2"));
    let sups = synthesize(&plant, &[c]).unwrap();
    assert_eq!(sups.len(), 1);
    let s = &sups[0];
    // (6.14), (6.15): c = [1 0 0 −1]: v(t1) − v(t4) ≤ 0.
    let mut cv = vec![0i64; 4];
    for &(t, w) in &s.c {
        cv[t.index()] = w;
    }
    assert_eq!(cv, vec![1, 0, 0, -1]);
    assert_eq!(s.describe(&plant.net), "v(v1/T1) - v(v2/T4) ≤ 0");
    assert!(s.l.is_empty());
    assert_eq!(s.b, 0);
    // (6.19): D_c⁺ = max(0, −L·D − C) = [0 0 0 1].
    assert_eq!(s.d_plus(4), vec![0, 0, 0, 1]);
    // (6.20): D_c⁻ = max(0, L·D + C) = [1 0 0 0] (the seed prints the
    // argument of max with the wrong sign: SEED-NOTES item 11).
    assert_eq!(s.d_minus(4), vec![1, 0, 0, 0]);
    // (6.21): μ_c0 = 0.
    assert_eq!(s.initial, 0);
    // (6.22), (6.23).
    let net = apply(&plant.net, &sups).unwrap();
    #[rustfmt::skip]
    let d = vec![
        vec![-1, 0, 0, 0],
        vec![1, -1, 0, 0],
        vec![0, 1, 0, 0],
        vec![0, 0, -1, 0],
        vec![0, 0, 1, -1],
        vec![0, 0, 0, 1],
        vec![-1, 0, 0, 1],
    ];
    assert_eq!(matrix(&net), d);
    assert_eq!(marking(&net), vec![1, 0, 0, 1, 0, 0, 0]);

    // Behaviour: P2 is never marked before P5 has been unmarked.
    let ss = explore(&net, &Options { semantics: Semantics::Plain, record_edges: true, ..Options::default() });
    let t1 = transition(&net, "v1/T1");
    for st in ss.states() {
        let path = ss.path_to(st);
        if let Some(i) = path.iter().position(|&t| t == t1) {
            assert!(path[..i].contains(&transition(&net, "v2/T4")), "T1 fired before T4: {path:?}");
        }
    }
    assert_eq!(ss.dead_states().len(), 1);
}

/// Figure 6.5: the same order after the PW-transformation of P2.
#[test]
fn order_after_pw_transformation_of_p2() {
    let v1 = pw_transform(&v1(), place(&v1(), "P2"), "P2wait", "T2'").unwrap();
    // Definition 6.1.2: •P2wait = {T1}, P2wait• = {T2'}, T2'• = {P2}, •P2 = {T2'}.
    let (p2, p2w, t1, t2w) = (place(&v1, "P2"), place(&v1, "P2wait"), transition(&v1, "T1"), transition(&v1, "T2'"));
    assert_eq!(v1.producers(p2w), &[t1]);
    assert_eq!(v1.consumers(p2w), &[t2w]);
    assert_eq!(v1.producers(p2), &[t2w]);
    let m1 = mission("v1", v1, &["P1", "P2", "P3"], "P1", "P3");
    let m2 = mission("v2", v2(), &["P4", "P5", "P6"], "P4", "P6");
    let plant = centralize(&[m1, m2]).unwrap();
    let sups = synthesize(&plant, &[Constraint::order(CallRef::new("v2", "P5"), CallRef::new("v1", "P2"))]).unwrap();
    // The supervisor now holds T2' (the start of P2), not T1: v1 may finish
    // P1 and wait in P2wait.
    assert_eq!(sups[0].describe(&plant.net), "v(v1/T2') - v(v2/T4) ≤ 0");
    let net = apply(&plant.net, &sups).unwrap();
    let ss = explore(&net, &Options::plain());
    let p2w = place(&net, "v1/P2wait");
    assert!(ss.states().any(|s| ss.tokens(s, p2w) == 1 && ss.tokens(s, place(&net, "v2/P4")) == 1));
    assert_eq!(ss.dead_states().len(), 1);
}

#[test]
fn synchronization_p2_p5_equations_6_24_6_25() {
    let v1 = pw_transform(&v1(), place(&v1(), "P2"), "P2wait", "T2'").unwrap();
    let v2 = pw_transform(&v2(), place(&v2(), "P5"), "P5wait", "T5'").unwrap();
    let m1 = mission("v1", v1, &["P1", "P2", "P3"], "P1", "P3");
    let m2 = mission("v2", v2, &["P4", "P5", "P6"], "P4", "P6");
    let plant = centralize(&[m1, m2]).unwrap();
    let sups = synthesize(&plant, &[Constraint::sync([CallRef::new("v1", "P2"), CallRef::new("v2", "P5")])]).unwrap();
    // (6.25): #S·(#S − 1) = 2 orderings.
    assert_eq!(sups.len(), 2);
    // The two constraints of the seed: −v(T1) + v(T4') ≤ 0 and
    // v(T2') − v(T3) ≤ 0 (the seed calls P5's wait transition T4' here and
    // T5' in 6.2; we name wait transitions after their place).
    assert_eq!(sups[0].describe(&plant.net), "- v(v1/T1) + v(v2/T5') ≤ 0");
    assert_eq!(sups[1].describe(&plant.net), "v(v1/T2') - v(v2/T3) ≤ 0");
    assert_eq!(sups[0].origin, Origin::Sync { constraint: 0, first: 0, second: 1 });
    // Columns: v1/T1, v1/T2, v1/T2', v2/T3, v2/T4, v2/T5'.
    assert_eq!(sups[0].row(6), vec![1, 0, 0, 0, 0, -1]);
    assert_eq!(sups[1].row(6), vec![0, 0, -1, 1, 0, 0]);
    assert!(sups.iter().all(|s| s.initial == 0));

    // Behaviour (Definition 6.1.5): neither task starts before both are
    // waiting; then both start; the missions still end.
    let net = apply(&plant.net, &sups).unwrap();
    let ss = explore(&net, &Options::plain());
    let (p2, p5, p2w, p5w) =
        (place(&net, "v1/P2"), place(&net, "v2/P5"), place(&net, "v1/P2wait"), place(&net, "v2/P5wait"));
    let (p3, p6) = (place(&net, "v1/P3"), place(&net, "v2/P6"));
    for s in ss.states() {
        let started1 = ss.tokens(s, p2) + ss.tokens(s, p3);
        let started2 = ss.tokens(s, p5) + ss.tokens(s, p6);
        if started1 > 0 {
            assert!(ss.tokens(s, p5w) + started2 > 0, "P2 started before P5 arrived");
        }
        if started2 > 0 {
            assert!(ss.tokens(s, p2w) + started1 > 0, "P5 started before P2 arrived");
        }
    }
    assert_eq!(ss.dead_states().len(), 1);
}

/// Seed 6.1.3: the last synchronization of the construction scenario, with
/// four calls, needs 4·3 = 12 supervisors.
#[test]
fn synchronization_of_four_calls_needs_twelve_supervisors() {
    let names = ["auv1", "auv2", "arm1", "arm2"];
    let missions: Vec<Mission> = names
        .iter()
        .map(|n| {
            let net = sequence(n, &["A", "B", "C"], &["TA", "TB"]);
            let net = pw_transform(&net, place(&net, "B"), "Bwait", "TB'").unwrap();
            mission(n, net, &["B"], "A", "C")
        })
        .collect();
    let plant = centralize(&missions).unwrap();
    let c = Constraint::sync(names.iter().map(|n| CallRef::new(*n, "B")));
    let sups = synthesize(&plant, &[c]).unwrap();
    assert_eq!(sups.len(), 12);
    let net = apply(&plant.net, &sups).unwrap();
    let ss = explore(&net, &Options::plain());
    assert_eq!(ss.dead_states().len(), 1);
    // In every reachable marking either no B has started or all have arrived.
    let firsts: Vec<_> = names.iter().map(|n| place(&net, &format!("{n}/A"))).collect();
    let bs: Vec<_> = names.iter().map(|n| place(&net, &format!("{n}/B"))).collect();
    for s in ss.states() {
        let any_started = bs.iter().any(|&b| ss.tokens(s, b) == 1);
        let someone_before = firsts.iter().any(|&a| ss.tokens(s, a) == 1);
        assert!(!(any_started && someone_before), "a B started while a mission had not arrived");
    }
}
