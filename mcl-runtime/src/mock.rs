//! A mock vehicle: a *sans-IO* state machine that plays the vehicle's AAC.
//!
//! It receives the player's actions ([`MockVehicle::on_action`]) and keeps an
//! agenda of the messages it will send: the answers of the primitives, and
//! the events and perceptions scripted by a [`Scenario`]. A driver asks for
//! [`MockVehicle::next_deadline`] and takes the due messages with
//! [`MockVehicle::pop_due`].
//!
//! # Rules
//!
//! * **Activation.** Actions are grouped by task (the action's `task`, or its
//!   `primitive` when it has none). An action of a task that is not active
//!   and whose command is not `disable` *activates* it (normally the
//!   `enable` sent when the task starts): the mock decides then how and when
//!   the primitive answers, and schedules that answer. Further actions of an
//!   active task change nothing.
//! * **Deactivation.** A `disable` action ends the activation and *cancels*
//!   its answer if it is still pending (an aborted primitive says nothing).
//! * **The answer** of the n-th activation of task `T` called at call site
//!   `c` (with label `l` and role `r`, looked up in the net) comes from the
//!   scenario's most specific rule: `[tasks.T.activation.n]`, then
//!   `[tasks.T.label.l]`, then `[tasks.T]`, field by field. Without a rule,
//!   the outcome depends on the role: a call inside a `monitor` condition
//!   (`monitor_condition`) never answers, a call inside a `while` condition
//!   (`while_condition`) fails, so that loops end, unless it is under an odd
//!   number of `not`s (`negated_while_condition`: it ends ok, and the
//!   negated condition fails); any other call ends ok.
//!   The delay defaults to the scenario's `default_duration`, else
//!   [`DEFAULT_DURATION`]. The event sent is the first ok (or fail) event of
//!   the task, from the net property `task_events:T`, unless the rule names
//!   one (`event = "..."`).
//! * **Activation ids.** Every answer names its activation: the `seq` of
//!   the action that activated the task (`docs/aac-protocol.md` §6), so
//!   that the player can drop an answer that crossed the `disable` of its
//!   run on the wire. Scripted events name none.
//! * **Duplicates.** An action whose `seq` is not above the last one seen is
//!   dropped (the link contract: a re-sent action is executed once).
//! * Messages due at the same time leave in the order they were scheduled.

use std::collections::{BTreeMap, HashMap};

use mcl_net::Net;
use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::link::{Action, Inbound};
use crate::scenario::{OutcomeRule, Rule, Scenario};

/// Seconds a primitive takes to answer when nothing else is said.
pub const DEFAULT_DURATION: f64 = 5.0;

pub use mcl_net::TaskEvents;

/// What the mock needs to know about a call site.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CallInfo {
    /// Task called.
    pub task: String,
    /// The call's label.
    pub label: Option<String>,
    /// `monitor_condition`, `while_condition`, `negated_while_condition`,
    /// `if_condition` or none.
    pub role: Option<String>,
}

/// The task and call tables of a compiled net.
pub fn tables_of(net: &Net) -> (HashMap<String, TaskEvents>, HashMap<u32, CallInfo>) {
    let tasks = net.task_events().map(|(t, e)| (t.to_string(), e)).collect();
    let mut calls = HashMap::new();
    for t in net.transitions() {
        if let Some(b) = &t.binding {
            calls.insert(b.call_site, CallInfo { task: b.task.clone(), label: b.label.clone(), role: b.role.clone() });
        }
    }
    (tasks, calls)
}

#[derive(Clone, Debug, PartialEq)]
struct Pending {
    msg: Inbound,
    /// The task whose answer this is (None for scripted messages).
    task: Option<String>,
}

type Key = (u64, u64);

#[derive(Clone, Debug)]
struct Active {
    /// Agenda key of the pending answer, if any.
    pending: Option<Key>,
}

/// The mock vehicle. See the [module documentation](self).
#[derive(Clone, Debug)]
pub struct MockVehicle {
    tasks: HashMap<String, TaskEvents>,
    calls: HashMap<u32, CallInfo>,
    scenario: Scenario,
    default_duration: f64,
    rng: ChaCha8Rng,
    agenda: BTreeMap<Key, Pending>,
    next_id: u64,
    active: HashMap<String, Active>,
    activations: HashMap<String, u32>,
    last_seq: u64,
    initialised: bool,
    warnings: Vec<String>,
    /// (task, outcome) pairs already warned about.
    warned: std::collections::HashSet<(String, &'static str)>,
    /// Times each event was sent (for perceptions scripted `after` an event).
    sent: HashMap<String, u32>,
}

fn key(t: f64, id: u64) -> Key {
    (t.max(0.0).to_bits(), id)
}

impl MockVehicle {
    /// A mock for the mission `net`, answering by `scenario`. Random draws use
    /// the scenario's seed, else `seed`.
    pub fn from_net(net: &Net, scenario: Scenario, seed: u64) -> Self {
        let (tasks, calls) = tables_of(net);
        MockVehicle::new(tasks, calls, scenario, seed)
    }

    /// A mock from explicit tables.
    pub fn new(
        tasks: HashMap<String, TaskEvents>,
        calls: HashMap<u32, CallInfo>,
        scenario: Scenario,
        seed: u64,
    ) -> Self {
        let seed = scenario.seed.unwrap_or(seed);
        MockVehicle {
            tasks,
            calls,
            default_duration: scenario.default_duration.unwrap_or(DEFAULT_DURATION),
            scenario,
            rng: ChaCha8Rng::seed_from_u64(seed ^ 0x6d6f_636b), // "mock": independent of the player's stream
            agenda: BTreeMap::new(),
            next_id: 0,
            active: HashMap::new(),
            activations: HashMap::new(),
            last_seq: 0,
            initialised: false,
            warnings: Vec::new(),
            warned: Default::default(),
            sent: HashMap::new(),
        }
    }

    /// The scenario.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    fn schedule(&mut self, t: f64, msg: Inbound, task: Option<String>) -> Key {
        self.next_id += 1;
        let k = key(t, self.next_id);
        self.agenda.insert(k, Pending { msg, task });
        k
    }

    /// Schedules the scenario's scripted events and perceptions (once) and
    /// returns them.
    pub fn initial(&mut self) -> Vec<(f64, Inbound)> {
        if self.initialised {
            return Vec::new();
        }
        self.initialised = true;
        let mut out: Vec<(f64, Inbound)> = Vec::new();
        for e in &self.scenario.events {
            out.push((e.at, Inbound::Event { event: e.event.clone(), activation: None, n: None }));
        }
        for p in &self.scenario.perceptions {
            if let Some(at) = p.at {
                out.push((at, Inbound::Perception { name: p.name.clone(), value: p.value.clone(), n: None }));
            }
        }
        out.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (t, m) in &out {
            self.schedule(*t, m.clone(), None);
        }
        out
    }

    /// The player sent `a` at time `now`. Returns the messages this schedules.
    pub fn on_action(&mut self, now: f64, a: &Action) -> Vec<(f64, Inbound)> {
        if a.seq <= self.last_seq {
            return Vec::new();
        }
        self.last_seq = a.seq;
        let task: &str = a.task.as_deref().unwrap_or(&a.primitive);
        if a.command == "disable" {
            if let Some(act) = self.active.remove(task) {
                if let Some(k) = act.pending {
                    self.agenda.remove(&k);
                }
            }
            return Vec::new();
        }
        if self.active.contains_key(task) {
            return Vec::new();
        }
        let n = match self.activations.get_mut(task) {
            Some(c) => {
                *c += 1;
                *c
            }
            None => {
                self.activations.insert(task.to_string(), 1);
                1
            }
        };
        let call = a.call_site.and_then(|c| self.calls.get(&c));
        let rule = self.rule_for(task, call.and_then(|c| c.label.as_deref()), n);
        let role = call.and_then(|c| c.role.as_deref());
        let outcome = match (rule.outcome, rule.probabilities) {
            (Some(o), _) => o,
            (None, Some(p)) => p.pick(self.uniform()),
            (None, None) => match role {
                Some("monitor_condition") => OutcomeRule::Never,
                Some("while_condition") => OutcomeRule::Fail,
                // `while ( not ( C() ) )`: C ends ok, so that the loop ends.
                Some("negated_while_condition") => OutcomeRule::Ok,
                _ => OutcomeRule::Ok,
            },
        };
        let delay = match rule.delay {
            None => self.default_duration,
            Some(d) => d.seconds(|| self.uniform()),
        };
        let event = match outcome {
            OutcomeRule::Never => None,
            OutcomeRule::Ok | OutcomeRule::Fail => rule.event.clone().or_else(|| {
                let evs = self.tasks.get(task);
                let e = evs.and_then(|e| if outcome == OutcomeRule::Ok { e.ok.first() } else { e.fail.first() });
                let what = if outcome == OutcomeRule::Ok { "ok" } else { "fail" };
                // Said once per task and outcome, not at every activation.
                if e.is_none() && self.warned.insert((task.to_string(), what)) {
                    self.warnings.push(format!(
                        "mock: task `{task}` binds no event that ends it {what}, so the mock vehicle cannot answer it {what}: \
                         it will not answer (bind the primitive's {what} event in the task, or name one in the scenario: \
                         `[tasks.{task}]` with `event = \"...\"`)"
                    ));
                }
                e.cloned()
            }),
        };
        let mut out = Vec::new();
        let at = event.map(|event| {
            let t = now + delay;
            let msg = Inbound::Event { event, activation: Some(a.seq), n: None };
            out.push((t, msg.clone()));
            (t, self.schedule(t, msg, Some(task.to_string())))
        });
        self.active.insert(task.to_string(), Active { pending: at.map(|x| x.1) });
        out
    }

    fn uniform(&mut self) -> f64 {
        (self.rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// The rule of activation `n` of `task` (called with `label`).
    fn rule_for(&self, task: &str, label: Option<&str>, n: u32) -> Rule {
        self.scenario.rule_for(task, label, n)
    }

    /// The time of the next scheduled message.
    pub fn next_deadline(&self) -> Option<f64> {
        self.agenda.keys().next().map(|&(k, _)| f64::from_bits(k))
    }

    /// Number of scheduled messages.
    pub fn pending(&self) -> usize {
        self.agenda.len()
    }

    /// Removes and returns the first message due at or before `now`.
    pub fn pop_due(&mut self, now: f64) -> Option<(f64, Inbound)> {
        let (&k, _) = self.agenda.iter().next()?;
        let t = f64::from_bits(k.0);
        if t > now {
            return None;
        }
        let p = self.agenda.remove(&k)?;
        self.delivered(k, &p);
        Some((t, p.msg))
    }

    /// Removes the earliest scheduled message equal to `msg` (it was
    /// delivered before a restart; an event journaled without its
    /// activation, by an older version, matches by name). False if there
    /// is none.
    pub fn take_delivered(&mut self, msg: &Inbound) -> bool {
        let same = |p: &Inbound| match (p, msg) {
            (Inbound::Event { event: a, activation: x, .. }, Inbound::Event { event: b, activation: y, .. }) => {
                a == b && (y.is_none() || x == y)
            }
            _ => p == msg,
        };
        let Some(k) = self.agenda.iter().find(|(_, p)| same(&p.msg)).map(|(k, _)| *k) else { return false };
        if let Some(p) = self.agenda.remove(&k) {
            self.delivered(k, &p);
        }
        true
    }

    fn delivered(&mut self, k: Key, p: &Pending) {
        // Perceptions scripted `after` this event.
        if let Inbound::Event { event, .. } = &p.msg {
            let n = self.sent.entry(event.clone()).or_insert(0);
            *n += 1;
            let n = *n;
            let t = f64::from_bits(k.0);
            let due: Vec<(f64, Inbound)> = self
                .scenario
                .perceptions
                .iter()
                .filter(|s| s.after.as_deref() == Some(event.as_str()) && s.occurrence.is_none_or(|o| o == n))
                .map(|s| {
                    (
                        t + s.delay.unwrap_or(0.0),
                        Inbound::Perception { name: s.name.clone(), value: s.value.clone(), n: None },
                    )
                })
                .collect();
            for (at, m) in due {
                self.schedule(at, m, None);
            }
        }
        if let Some(task) = &p.task {
            if let Some(a) = self.active.get_mut(task) {
                if a.pending == Some(k) {
                    a.pending = None;
                }
            }
        }
    }

    /// Warnings since the last call.
    pub fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }
}

impl crate::vehicle::VirtualVehicle for MockVehicle {
    fn initial(&mut self) -> Vec<(f64, Inbound)> {
        MockVehicle::initial(self)
    }
    fn on_action(&mut self, now: f64, a: &Action) {
        MockVehicle::on_action(self, now, a);
    }
    fn next_deadline(&self) -> Option<f64> {
        MockVehicle::next_deadline(self)
    }
    fn pop_due(&mut self, now: f64) -> Option<(f64, Inbound)> {
        MockVehicle::pop_due(self, now)
    }
    fn take_delivered(&mut self, msg: &Inbound) -> bool {
        MockVehicle::take_delivered(self, msg)
    }
    fn take_warnings(&mut self) -> Vec<String> {
        MockVehicle::take_warnings(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn action(seq: u64, task: &str, command: &str, call_site: u32) -> Action {
        Action {
            seq,
            action: format!("{command}{task}"),
            primitive: format!("{task}Primitive"),
            command: command.into(),
            params: Default::default(),
            task: Some(task.into()),
            call_site: Some(call_site),
        }
    }

    fn mock(scenario: &str) -> MockVehicle {
        let mut tasks = HashMap::new();
        for t in ["Goto", "Alarm", "Cond"] {
            tasks.insert(t.to_string(), TaskEvents { ok: vec![format!("ev{t}Ok")], fail: vec![format!("ev{t}Fail")] });
        }
        let mut calls = HashMap::new();
        calls.insert(1, CallInfo { task: "Goto".into(), label: Some("first".into()), role: None });
        calls.insert(2, CallInfo { task: "Alarm".into(), label: None, role: Some("monitor_condition".into()) });
        calls.insert(3, CallInfo { task: "Cond".into(), label: None, role: Some("while_condition".into()) });
        calls.insert(4, CallInfo { task: "Goto".into(), label: None, role: None });
        MockVehicle::new(tasks, calls, Scenario::from_toml(scenario, "s").unwrap(), 1)
    }

    fn ev(e: &str) -> Inbound {
        Inbound::Event { event: e.into(), activation: None, n: None }
    }

    /// The answer to the action `seq`.
    fn ans(e: &str, seq: u64) -> Inbound {
        Inbound::Event { event: e.into(), activation: Some(seq), n: None }
    }

    #[test]
    fn default_rules_by_role() {
        let mut m = mock("");
        assert_eq!(m.on_action(0.0, &action(1, "Goto", "enable", 1)), vec![(5.0, ans("evGotoOk", 1))]);
        assert!(m.on_action(0.0, &action(2, "Alarm", "enable", 2)).is_empty());
        assert_eq!(m.on_action(1.0, &action(3, "Cond", "enable", 3)), vec![(6.0, ans("evCondFail", 3))]);
        assert_eq!(m.pop_due(4.0), None);
        assert_eq!(m.pop_due(5.0), Some((5.0, ans("evGotoOk", 1))));
        // A duplicate is dropped; a disable cancels the pending answer.
        assert!(m.on_action(6.0, &action(3, "Cond", "disable", 3)).is_empty());
        assert!(m.on_action(6.0, &action(4, "Cond", "disable", 3)).is_empty());
        assert_eq!(m.next_deadline(), None);
    }

    #[test]
    fn a_task_that_cannot_be_answered_is_reported_once() {
        // `Other` is in no task_events: its activations cannot be answered.
        let mut m = mock("");
        for seq in [1, 3, 5] {
            assert!(m.on_action(0.0, &action(seq, "Other", "enable", 9)).is_empty());
            assert!(m.on_action(0.0, &action(seq + 1, "Other", "disable", 9)).is_empty());
        }
        let w = m.take_warnings();
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].contains("task `Other` binds no event that ends it ok"), "{}", w[0]);
    }

    #[test]
    fn scenario_levels_and_scripted_messages() {
        let mut m = mock(
            r#"
default_duration = 2
[tasks.Goto]
delay = 10
[tasks.Goto.label.first]
outcome = "fail"
[tasks.Goto.activation.3]
outcome = "never"
[[events]]
at = 7
event = "evAlarmOk"
"#,
        );
        assert_eq!(m.initial(), vec![(7.0, ev("evAlarmOk"))]);
        assert_eq!(m.on_action(0.0, &action(1, "Goto", "enable", 1)), vec![(10.0, ans("evGotoFail", 1))]);
        m.on_action(1.0, &action(2, "Goto", "disable", 1));
        assert_eq!(m.on_action(1.0, &action(3, "Goto", "enable", 4)), vec![(11.0, ans("evGotoOk", 3))]);
        m.on_action(2.0, &action(4, "Goto", "disable", 4));
        assert!(m.on_action(2.0, &action(5, "Goto", "enable", 4)).is_empty());
        assert_eq!(m.pop_due(100.0), Some((7.0, ev("evAlarmOk"))));
        assert_eq!(m.pop_due(100.0), None);
    }

    #[test]
    fn perceptions_after_events() {
        let mut m = mock(
            r#"
[tasks.Goto]
delay = 10
[[perceptions]]
after = "evGotoOk"
name = "moved"
value = true
[[perceptions]]
after = "evGotoOk"
occurrence = 2
delay = 1.5
name = "second"
value = 2
"#,
        );
        let p = |n: &str, v: serde_json::Value| Inbound::Perception { name: n.into(), value: v, n: None };
        assert!(m.initial().is_empty());
        m.on_action(0.0, &action(1, "Goto", "enable", 4));
        assert_eq!(m.pop_due(10.0), Some((10.0, ans("evGotoOk", 1))));
        assert_eq!(m.pop_due(10.0), Some((10.0, p("moved", serde_json::json!(true)))));
        assert_eq!(m.pop_due(100.0), None);
        m.on_action(10.0, &action(2, "Goto", "disable", 4));
        m.on_action(10.0, &action(3, "Goto", "enable", 4));
        assert_eq!(m.pop_due(20.0), Some((20.0, ans("evGotoOk", 3))));
        assert_eq!(m.pop_due(20.0), Some((20.0, p("moved", serde_json::json!(true)))));
        assert_eq!(m.pop_due(21.0), None);
        assert_eq!(m.pop_due(21.5), Some((21.5, p("second", serde_json::json!(2)))));
        // A cancelled answer is never sent, so nothing follows it.
        m.on_action(20.0, &action(4, "Goto", "disable", 4));
        m.on_action(20.0, &action(5, "Goto", "enable", 4));
        m.on_action(25.0, &action(6, "Goto", "disable", 4));
        assert_eq!(m.next_deadline(), None);
    }

    #[test]
    fn probabilities_are_seeded() {
        let draw = |seed| {
            let mut m = mock("[tasks.Goto]\nprobabilities = { ok = 0.5, fail = 0.5 }\n");
            m.rng = ChaCha8Rng::seed_from_u64(seed);
            (0..40u64)
                .map(|i| {
                    let r = m.on_action(0.0, &action(2 * i + 1, "Goto", "enable", 4));
                    m.on_action(0.0, &action(2 * i + 2, "Goto", "disable", 4));
                    r[0].1.clone()
                })
                .collect::<Vec<_>>()
        };
        let a = draw(3);
        assert_eq!(a, draw(3));
        let oks = a.iter().filter(|e| matches!(e, Inbound::Event { event, .. } if event == "evGotoOk")).count();
        assert!((8..32).contains(&oks), "{oks}");
    }
}
