//! One semantics (issue item 2): the block verifier explores with
//! `mcl_net::explore` under `mcl_net::semantics::select_ready`, the rule the
//! player applies. On every building block of the standard library (tasks,
//! control structures, the call adapter) and on user patterns:
//!
//! * the verifier's graph equals a plain breadth-first search that fires by
//!   `mcl_net::semantics::ready` (same states, same edges);
//! * the player itself (`mcl_runtime::Player`), driven by random events,
//!   timers and aborts, only ever fires along edges of the verifier's graph.

use mcl_compiler::compile::builder::Builder;
use mcl_compiler::compile::structures::Structure;
use mcl_compiler::compile::verify::{self, Child, Harness};
use mcl_compiler::{scope, Database};
use mcl_net::explore::StateId;
use mcl_net::{Marking, TransitionId};
use mcl_runtime::player::{Output, Player, PlayerOptions};
use mcl_syntax::ast::MonitorKind;
use std::collections::{HashMap, HashSet, VecDeque};
use std::sync::Arc;

/// Tasks on every pattern of the standard library and on user patterns.
const PROGRAM: &str = r#"
actions { enableA = APrimitive( c: enable, v: x ); disableA = APrimitive( c: disable ); }
events { aOk; aFail; tick; }
pattern {
    // A user pattern: the primitive may report progress (`tick`) any number of times.
    P_PROGRESS {
        places { begin.1; abort.1; ok.1; fail.1; exe; }
        transitions { T0; TT; T1; T2; TA; }
        arcs {
            begin.1 -> T0; T0 -> exe; exe -> TT; TT -> exe;
            exe -> T1; T1 -> ok.1; exe -> T2; T2 -> fail.1; abort.1 -> TA; exe -> TA;
        }
    }
    // A broken user pattern: only an abort ends it.
    P_DEAD {
        places { begin.1; abort.1; ok.1; fail.1; run; }
        transitions { T0; TA; }
        arcs { begin.1 -> T0; T0 -> run; run -> TA; abort.1 -> TA; }
    }
}
tasks {
    Goal( x ): AchieveOneGoal { a: enableA -> T0; a: disableA -> T1, T6, T7; e: aOk -> T2; e: aFail -> T3; }
    Timed( x, timeout ): AchieveOneGoalTimed { a: enableA -> T0; a: disableA -> T1, T6, T7; e: aOk -> T2; e: aFail -> T3; }
    Now(): Instant { }
    Progress(): P_PROGRESS { e: tick -> TT; e: aOk -> T1; e: aFail -> T2; }
    Dead(): P_DEAD { }
}
"#;

fn harnesses() -> Vec<(String, Harness)> {
    let mut out = Vec::new();
    let mut db = Database::new();
    let file = db.set_text(std::path::Path::new("/virtual/semantics/v.mcl"), PROGRAM);
    let sc = scope::scope(&db, file);
    for task in ["Goal", "Timed", "Now", "Progress", "Dead"] {
        let mut b = Builder::new(task);
        mcl_compiler::compile::add_task_net(&db, sc, &mut b, task, "").unwrap().expect(task);
        let net = b.finish().build().unwrap();
        out.push((format!("task {task}"), verify::task_harness(&net).unwrap()));
    }
    let structures = [
        Structure::Not,
        Structure::Sequence(2),
        Structure::IfThen,
        Structure::IfThenElse,
        Structure::While,
        Structure::TryCatch,
        Structure::ParallelAnd(2),
        Structure::ParallelOr(2),
        Structure::ParallelOr(3),
        Structure::Monitor(vec![MonitorKind::Condition]),
        Structure::Monitor(vec![MonitorKind::WhileCondition]),
    ];
    for s in structures {
        for children in [[Child::Reduced, Child::Reduced], [Child::Instant, Child::Reduced]] {
            out.push((format!("{} {children:?}", s.name()), verify::structure_harness(&s, &children)));
        }
    }
    out.push(("call adapter".into(), verify::call_adapter_harness()));
    out
}

#[test]
fn the_verifier_explores_by_the_firing_rule_of_mcl_net() {
    for (name, h) in harnesses() {
        let ss = h.state_space(100_000);
        assert!(ss.complete(), "{name}");
        // Plain BFS with the shared rule.
        let net = &h.net;
        let m0 = net.initial_marking();
        let mut index: HashMap<Marking, usize> = HashMap::from([(m0.clone(), 0)]);
        let mut queue = VecDeque::from([m0]);
        let mut edges: HashSet<(Vec<u32>, TransitionId, Vec<u32>)> = HashSet::new();
        while let Some(m) = queue.pop_front() {
            let (_, ready) = mcl_net::semantics::ready(net, &m);
            for t in ready {
                let mut m2 = m.clone();
                mcl_net::semantics::fire(net, &mut m2, t).unwrap();
                edges.insert((m.0.clone(), t, m2.0.clone()));
                if !index.contains_key(&m2) {
                    index.insert(m2.clone(), index.len());
                    queue.push_back(m2);
                }
            }
        }
        assert_eq!(ss.len(), index.len(), "{name}: states");
        let mut theirs = HashSet::new();
        for s in ss.states() {
            for &(t, d) in ss.successors(s) {
                theirs.insert((ss.marking(s).0, t, ss.marking(d).0));
            }
        }
        assert_eq!(theirs, edges, "{name}: edges");
    }
}

/// A small deterministic generator for the random walks.
fn next(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[test]
fn the_player_fires_only_along_the_verifiers_edges() {
    for (name, h) in harnesses() {
        let ss = h.state_space(100_000);
        let states: HashMap<Marking, StateId> = ss.states().map(|s| (ss.marking(s), s)).collect();
        let net = Arc::new(h.net.clone());
        let mut covered: HashSet<StateId> = HashSet::new();
        for seed in 0..30u64 {
            let mut rng = seed;
            let mut player = Player::new(net.clone(), PlayerOptions::seeded(seed));
            let mut s = StateId(0);
            let mut now = 0.0;
            let mut follow = |outputs: Vec<Output>, s: &mut StateId| {
                for o in outputs {
                    if let Output::Fired { transition, .. } = o {
                        let to = ss.successors(*s).iter().find(|(t, _)| *t == transition).map(|&(_, d)| d);
                        let id = &net.transition(transition).unwrap().id;
                        *s = to.unwrap_or_else(|| {
                            panic!("{name}, seed {seed}: the player fired `{id}` where the verifier does not")
                        });
                        covered.insert(*s);
                    }
                }
            };
            follow(player.start(now), &mut s);
            for _ in 0..200 {
                if player.outcome().is_some() {
                    break;
                }
                let events = player.awaited_events();
                let deadline = player.next_deadline();
                let pick = next(&mut rng) as usize % (events.len() + usize::from(deadline.is_some())).max(1);
                if pick < events.len() {
                    follow(player.on_event(now, &events[pick]), &mut s);
                } else if let Some(d) = deadline {
                    now = d.max(now);
                    follow(player.on_timer(now), &mut s);
                } else {
                    break;
                }
                assert_eq!(states.get(player.marking()), Some(&s), "{name}, seed {seed}: marking");
            }
        }
        assert!(covered.len() > 1, "{name}: the walks moved");
    }
}
