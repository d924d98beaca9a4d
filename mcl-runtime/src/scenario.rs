//! Scenario files: how the mock vehicle answers, in TOML
//! (`docs/scenarios.md`, examples in `examples/scenarios/`).
//!
//! ```toml
//! default_duration = 5.0      # seconds a primitive takes when nothing else is said
//! seed = 7                    # seed of the random draws (default: the run's --seed)
//!
//! [symbols]                   # values of symbolic call arguments
//! timeout = 30
//!
//! [tasks.Goto]                # every call of Goto
//! delay = 12.0                # or [10.0, 20.0]: uniform in that range
//! outcome = "ok"              # "ok" | "fail" | "never"
//!
//! [tasks.Goto.activation.2]   # the 2nd activation of Goto overrides the above
//! outcome = "fail"
//!
//! [tasks.Altitude.label.deploy]   # the call labelled `deploy`
//! probabilities = { ok = 0.8, fail = 0.2 }
//!
//! [[events]]                  # scripted events, sent whatever the vehicle does
//! at = 120.0
//! event = "eventAlarmOk"
//!
//! [[perceptions]]
//! at = 10
//! name = "battery"
//! value = 0.8
//!
//! [[perceptions]]             # when the mock sends an event
//! after = "eventSearchOk"     # every time, or only its `occurrence = n`-th time
//! delay = 2.0                 # seconds after the event (default 0)
//! name = "cable.detected"
//! value = 1
//!
//! [counterexample]            # written by `mcl check --counterexample-scenario`
//! code = "E0406"              # (crate::counterexample::Expected)
//! at = "m.mcl:16"
//! [counterexample.marking]
//! v1 = ["call.1.wait"]
//! ```
//!
//! Unknown keys and malformed values are errors that point at their line
//! and column.

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;
use serde_json::Value;

/// A scenario for the mock vehicle.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Seconds a primitive takes to answer when no rule gives a delay.
    #[serde(default, deserialize_with = "non_negative_opt")]
    pub default_duration: Option<f64>,
    /// Seed of the random draws (probabilities, delay ranges).
    #[serde(default)]
    pub seed: Option<u64>,
    /// Values of symbolic call arguments.
    #[serde(default)]
    pub symbols: BTreeMap<String, Value>,
    /// Rules per task name.
    #[serde(default)]
    pub tasks: BTreeMap<String, TaskRule>,
    /// Events sent at fixed times.
    #[serde(default)]
    pub events: Vec<ScriptedEvent>,
    /// Perceptions sent at fixed times.
    #[serde(default)]
    pub perceptions: Vec<ScriptedPerception>,
    /// The counterexample this scenario replays (`mcl check
    /// --counterexample-scenario`), which `mcl run` reports on.
    #[serde(default)]
    pub counterexample: Option<crate::counterexample::Expected>,
    /// The file name it was read from (for messages).
    #[serde(skip)]
    pub origin: String,
    /// The text it was read from, to locate what [`Scenario::check_against`]
    /// reports (empty for a scenario built in code: locations are 1:1).
    #[serde(skip)]
    pub text: String,
}

/// The names a program offers a scenario: the tasks its missions call,
/// their labelled calls, and the events its nets wait for.
#[derive(Clone, Debug, Default)]
pub struct ProgramNames {
    pub tasks: Vec<String>,
    /// (task, label) of every labelled call.
    pub labels: Vec<(String, String)>,
    pub events: Vec<String>,
}

impl ProgramNames {
    /// The names of the missions compiled into `nets`.
    pub fn of<'a>(nets: impl IntoIterator<Item = &'a mcl_net::Net>) -> Self {
        let mut p = ProgramNames::default();
        for net in nets {
            for t in net.transitions() {
                if let Some(b) = &t.binding {
                    p.tasks.push(b.task.clone());
                    if let Some(l) = &b.label {
                        p.labels.push((b.task.clone(), l.clone()));
                    }
                }
                if let mcl_net::TransitionKind::Event(e) = &t.kind {
                    p.events.push(e.clone());
                }
            }
        }
        for v in [&mut p.tasks, &mut p.events] {
            v.sort();
            v.dedup();
        }
        p.labels.sort();
        p.labels.dedup();
        p
    }
}

/// How a task's primitive ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OutcomeRule {
    /// Send the task's ok event.
    Ok,
    /// Send the task's fail event.
    Fail,
    /// Send nothing.
    Never,
}

/// A delay: fixed, or drawn uniformly in `[min, max]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DelaySpec {
    /// Exactly this many seconds.
    Fixed(f64),
    /// Uniform between the two bounds.
    Range(f64, f64),
}

/// Probabilities of each outcome (weights, normalised by their sum).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(try_from = "RawProbabilities")]
pub struct Probabilities {
    /// Weight of ok.
    pub ok: f64,
    /// Weight of fail.
    pub fail: f64,
    /// Weight of never.
    pub never: f64,
}

impl Probabilities {
    /// The outcome that `u`, uniform in [0, 1), picks with these weights.
    pub fn pick(&self, u: f64) -> OutcomeRule {
        let u = u * (self.ok + self.fail + self.never);
        if u < self.ok {
            OutcomeRule::Ok
        } else if u < self.ok + self.fail {
            OutcomeRule::Fail
        } else {
            OutcomeRule::Never
        }
    }
}

impl DelaySpec {
    /// The delay in seconds; a range takes one draw of `uniform` (in [0, 1)).
    pub fn seconds(&self, uniform: impl FnOnce() -> f64) -> f64 {
        match *self {
            DelaySpec::Fixed(d) => d,
            DelaySpec::Range(lo, hi) => lo + (hi - lo) * uniform(),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawProbabilities {
    #[serde(default)]
    ok: f64,
    #[serde(default)]
    fail: f64,
    #[serde(default)]
    never: f64,
}

impl TryFrom<RawProbabilities> for Probabilities {
    type Error = String;
    fn try_from(r: RawProbabilities) -> Result<Self, String> {
        for (k, v) in [("ok", r.ok), ("fail", r.fail), ("never", r.never)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("probability `{k}` must be a number ≥ 0, found {v}"));
            }
        }
        if r.ok + r.fail + r.never <= 0.0 {
            return Err("probabilities must not all be 0".into());
        }
        Ok(Probabilities { ok: r.ok, fail: r.fail, never: r.never })
    }
}

/// The answer of one call: every field is optional and falls back to the
/// less specific rule (activation, then label, then task, then defaults).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rule {
    /// Fixed outcome.
    #[serde(default)]
    pub outcome: Option<OutcomeRule>,
    /// Random outcome (exclusive with `outcome` at the same level).
    #[serde(default)]
    pub probabilities: Option<Probabilities>,
    /// Seconds between the activation and the answer.
    #[serde(default)]
    pub delay: Option<DelaySpec>,
    /// Event to send instead of the task's ok or fail event.
    #[serde(default)]
    pub event: Option<String>,
}

/// The rule of a task, with overrides per call label and per activation.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskRule {
    /// Fixed outcome.
    #[serde(default)]
    pub outcome: Option<OutcomeRule>,
    /// Random outcome.
    #[serde(default)]
    pub probabilities: Option<Probabilities>,
    /// Seconds between the activation and the answer.
    #[serde(default)]
    pub delay: Option<DelaySpec>,
    /// Event to send instead of the task's ok or fail event.
    #[serde(default)]
    pub event: Option<String>,
    /// Overrides for the calls labelled `Task(...) : label`.
    #[serde(default)]
    pub label: BTreeMap<String, Rule>,
    /// Overrides for the n-th activation of the task (1 is the first).
    #[serde(default)]
    pub activation: BTreeMap<Activation, Rule>,
}

impl TaskRule {
    /// The task-level fields as a [`Rule`].
    pub fn base(&self) -> Rule {
        Rule { outcome: self.outcome, probabilities: self.probabilities, delay: self.delay, event: self.event.clone() }
    }
}

/// The number of an activation (1-based), a table key such as `activation.2`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Activation(pub u32);

impl<'de> Deserialize<'de> for Activation {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        match s.parse::<u32>() {
            Ok(n) if n >= 1 => Ok(Activation(n)),
            _ => Err(de::Error::custom(format!(
                "activation `{s}`: expected the number of an activation, 1 for the first"
            ))),
        }
    }
}

/// An event sent at a fixed time.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScriptedEvent {
    /// Seconds from the start of the mission.
    #[serde(deserialize_with = "non_negative")]
    pub at: f64,
    /// Event name.
    pub event: String,
    /// Sent on purpose although no transition waits for it (to test how a
    /// mission takes an unexpected event); otherwise such an event is an
    /// error when the scenario is loaded (a misspelt name).
    #[serde(default)]
    pub unexpected: bool,
}

/// A perception sent at a fixed time (`at`), or `delay` seconds after the
/// mock vehicle sends an event (`after`; every time, or only its
/// `occurrence`-th time).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScriptedPerception {
    /// Seconds from the start of the mission (exclusive with `after`).
    #[serde(default, deserialize_with = "non_negative_opt")]
    pub at: Option<f64>,
    /// Send it when the mock sends this event (a task's answer or a scripted event).
    #[serde(default)]
    pub after: Option<String>,
    /// With `after`: only after the n-th time the event is sent (1 is the first); default every time.
    #[serde(default, deserialize_with = "positive_opt")]
    pub occurrence: Option<u32>,
    /// With `after`: seconds between the event and the perception (default 0).
    #[serde(default, deserialize_with = "non_negative_opt")]
    pub delay: Option<f64>,
    /// Perception name.
    pub name: String,
    /// Its value (any TOML value).
    pub value: Value,
}

fn non_negative<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let v = f64::deserialize(d)?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(de::Error::custom(format!("expected a number of seconds ≥ 0, found {v}")))
    }
}

fn positive_opt<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u32>, D::Error> {
    let v = i64::deserialize(d)?;
    u32::try_from(v)
        .ok()
        .filter(|&n| n >= 1)
        .map(Some)
        .ok_or_else(|| de::Error::custom(format!("expected 1 for the first time, 2 for the second..., found {v}")))
}

fn non_negative_opt<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    non_negative(d).map(Some)
}

impl<'de> Deserialize<'de> for DelaySpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = DelaySpec;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "a number of seconds ≥ 0, or a range [min, max]")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<DelaySpec, E> {
                if v.is_finite() && v >= 0.0 {
                    Ok(DelaySpec::Fixed(v))
                } else {
                    Err(E::custom(format!("delay must be a number of seconds ≥ 0, found {v}")))
                }
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<DelaySpec, E> {
                self.visit_f64(v as f64)
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<DelaySpec, E> {
                self.visit_f64(v as f64)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<DelaySpec, A::Error> {
                let lo: f64 = seq.next_element()?.ok_or_else(|| de::Error::custom("a delay range needs [min, max]"))?;
                let hi: f64 = seq.next_element()?.ok_or_else(|| de::Error::custom("a delay range needs [min, max]"))?;
                if seq.next_element::<f64>()?.is_some() {
                    return Err(de::Error::custom("a delay range has two numbers, [min, max]"));
                }
                if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi) {
                    return Err(de::Error::custom(format!("delay range [{lo}, {hi}] must satisfy 0 ≤ min ≤ max")));
                }
                Ok(DelaySpec::Range(lo, hi))
            }
        }
        d.deserialize_any(V)
    }
}

impl Scenario {
    /// The rule of activation `n` (1 is the first) of `task`, called with
    /// `label`: the most specific level first (activation, label, task),
    /// field by field, the outcome and the probabilities together from the
    /// most specific level that gives either. Used by the mock vehicle and
    /// the simulator (`mcl-sim`).
    pub fn rule_for(&self, task: &str, label: Option<&str>, n: u32) -> Rule {
        let Some(tr) = self.tasks.get(task) else { return Rule::default() };
        let mut levels: Vec<Rule> = Vec::new();
        if let Some(r) = tr.activation.get(&Activation(n)) {
            levels.push(r.clone());
        }
        if let Some(r) = label.and_then(|l| tr.label.get(l)) {
            levels.push(r.clone());
        }
        levels.push(tr.base());
        let mut r = Rule::default();
        if let Some(l) = levels.iter().find(|l| l.outcome.is_some() || l.probabilities.is_some()) {
            r.outcome = l.outcome;
            r.probabilities = l.probabilities;
        }
        r.delay = levels.iter().find_map(|l| l.delay);
        r.event = levels.iter().find_map(|l| l.event.clone());
        r
    }

    /// Parses a scenario. Errors name the line and column (and `origin`, a
    /// file name for messages).
    pub fn from_toml(text: &str, origin: &str) -> Result<Scenario, String> {
        let mut s: Scenario = toml::from_str(text).map_err(|e| format_toml_error(origin, text, &e))?;
        (s.origin, s.text) = (origin.to_string(), text.to_string());
        for (task, rule) in &s.tasks {
            let levels = std::iter::once((format!("tasks.{task}"), rule.base()))
                .chain(rule.label.iter().map(|(l, r)| (format!("tasks.{task}.label.{l}"), r.clone())))
                .chain(rule.activation.iter().map(|(a, r)| (format!("tasks.{task}.activation.{}", a.0), r.clone())));
            for (path, r) in levels {
                if r.outcome.is_some() && r.probabilities.is_some() {
                    let (line, col) = find_key(text, &path);
                    return Err(format!(
                        "{origin}:{line}:{col}: [{path}] gives both `outcome` and `probabilities`; keep one"
                    ));
                }
            }
        }
        for (i, p) in s.perceptions.iter().enumerate() {
            let problem = match (p.at, &p.after) {
                (Some(_), Some(_)) => Some("gives both `at` and `after`; keep one"),
                (None, None) => Some("needs `at` (seconds) or `after` (an event name)"),
                (Some(_), None) if p.occurrence.is_some() || p.delay.is_some() => {
                    Some("`occurrence` and `delay` go with `after`, not with `at`")
                }
                _ => None,
            };
            if let Some(problem) = problem {
                let (line, col) = nth_table(text, "[[perceptions]]", i);
                return Err(format!("{origin}:{line}:{col}: perception `{}` {problem}", p.name));
            }
        }
        Ok(s)
    }

    /// Reads and parses a scenario file.
    pub fn load(path: &Path) -> Result<Scenario, String> {
        let text = mcl_net::input::read_source(path).map_err(|e| format!("scenario: {e}"))?;
        Scenario::from_toml(&text, &path.display().to_string())
    }

    /// Errors (`file:line:col: ...`, with a did-you-mean when a known name is
    /// close) for what the scenario names and the program does not have: a
    /// task its missions never call, a label no call of that task has, an
    /// event no transition waits for (`event = ...` of a rule, `[[events]]`,
    /// a perception's `after`).
    pub fn check_against(&self, p: &ProgramNames) -> Vec<String> {
        let (origin, text) = (&self.origin, &self.text);
        let mut errors = Vec::new();
        let mut report = |(line, col): (usize, usize), what: String, name: &str, known: &[&str]| {
            let hint = mcl_net::suggest::closest(name, known.iter().copied())
                .map(|b| format!("; did you mean `{b}`?"))
                .unwrap_or_default();
            errors.push(format!("{origin}:{line}:{col}: {what}{hint}"));
        };
        let tasks: Vec<&str> = p.tasks.iter().map(String::as_str).collect();
        let events: Vec<&str> = p.events.iter().map(String::as_str).collect();
        for (name, rule) in &self.tasks {
            if !p.tasks.contains(name) {
                report(
                    find_key(text, &format!("tasks.{name}")),
                    format!("the mission never calls task `{name}`"),
                    name,
                    &tasks,
                );
                continue;
            }
            let labels: Vec<&str> = p.labels.iter().filter(|(t, _)| t == name).map(|(_, l)| l.as_str()).collect();
            for l in rule.label.keys() {
                if !labels.contains(&l.as_str()) {
                    let at = find_key(text, &format!("tasks.{name}.label.{l}"));
                    report(at, format!("no call of `{name}` is labelled `{l}`"), l, &labels);
                }
            }
            let overrides = std::iter::once(rule.event.as_ref())
                .chain(rule.label.values().map(|r| r.event.as_ref()))
                .chain(rule.activation.values().map(|r| r.event.as_ref()));
            for e in overrides.flatten() {
                if !p.events.contains(e) {
                    let at = find_value(text, e);
                    report(
                        at,
                        format!("task `{name}` answers with event `{e}`, which no transition waits for"),
                        e,
                        &events,
                    );
                }
            }
        }
        for e in &self.events {
            if !e.unexpected && !p.events.contains(&e.event) {
                let at = find_value(text, &e.event);
                let what = format!(
                    "event `{}` at {} s: no transition waits for it (add `unexpected = true` to send it on purpose)",
                    e.event, e.at
                );
                report(at, what, &e.event, &events);
            }
        }
        for per in &self.perceptions {
            if let Some(e) = per.after.as_ref().filter(|e| !p.events.contains(e)) {
                report(
                    find_value(text, e),
                    format!("perception `{}` comes after event `{e}`, which no transition waits for", per.name),
                    e,
                    &events,
                );
            }
        }
        errors
    }
}

/// The line and column (1-based) of the string value `"value"` in the
/// text, (1, 1) if not found.
fn find_value(text: &str, value: &str) -> (usize, usize) {
    let quoted = format!("\"{value}\"");
    for (i, line) in text.lines().enumerate() {
        if let Some(c) = line.find(&quoted) {
            return (i + 1, c + 1);
        }
    }
    (1, 1)
}

/// The line and column (1-based) of the `n`-th (0-based) `header` line, (1, 1) if not found.
fn nth_table(text: &str, header: &str, n: usize) -> (usize, usize) {
    text.lines().enumerate().filter_map(|(i, l)| l.find(header).map(|c| (i + 1, c + 1))).nth(n).unwrap_or((1, 1))
}

/// The line and column (1-based) of `[path]` or of the last key of `path`
/// in the text, for messages about a whole table; (1, 1) if not found.
fn find_key(text: &str, path: &str) -> (usize, usize) {
    let header = format!("[{path}]");
    for (i, line) in text.lines().enumerate() {
        if let Some(c) = line.find(&header) {
            return (i + 1, c + 1);
        }
    }
    let last = path.rsplit('.').next().unwrap_or(path);
    for (i, line) in text.lines().enumerate() {
        if let Some(c) = line.find(last) {
            return (i + 1, c + 1);
        }
    }
    (1, 1)
}

fn format_toml_error(origin: &str, text: &str, e: &toml::de::Error) -> String {
    let msg = e.message().trim_end().to_string();
    match e.span() {
        Some(span) => {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
            let src = text.lines().nth(line - 1).unwrap_or("");
            let width = text[span.start.min(text.len())..span.end.min(text.len())]
                .lines()
                .next()
                .map_or(1, |s| s.chars().count().max(1));
            format!(
                "{origin}:{line}:{col}: {msg}\n{:>4} | {src}\n     | {}{}",
                line,
                " ".repeat(col - 1),
                "^".repeat(width)
            )
        }
        None => format!("{origin}: {msg}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_feature() {
        let s = Scenario::from_toml(
            r#"
default_duration = 4
seed = 9
[symbols]
timeout = 30
[tasks.Goto]
delay = [1, 2.5]
outcome = "fail"
[tasks.Goto.activation.2]
outcome = "ok"
[tasks.Alarm.label.al]
probabilities = { ok = 0.8, fail = 0.2 }
event = "eventAlarmOk"
[[events]]
at = 120.0
event = "eventAlarmOk"
[[perceptions]]
at = 10
name = "battery"
value = 0.8
"#,
            "s.toml",
        )
        .unwrap();
        assert_eq!(s.default_duration, Some(4.0));
        assert_eq!(s.symbols["timeout"], serde_json::json!(30));
        let g = &s.tasks["Goto"];
        assert_eq!(g.delay, Some(DelaySpec::Range(1.0, 2.5)));
        assert_eq!(g.activation[&Activation(2)].outcome, Some(OutcomeRule::Ok));
        assert_eq!(s.tasks["Alarm"].label["al"].probabilities.unwrap().ok, 0.8);
        assert_eq!(s.events[0].at, 120.0);
        assert_eq!(s.perceptions[0].value, serde_json::json!(0.8));
        assert_eq!(s.perceptions[0].at, Some(10.0));
    }

    #[test]
    fn perceptions_after_events() {
        let s = Scenario::from_toml(
            "[[perceptions]]\nafter = \"evOk\"\noccurrence = 2\ndelay = 3\nname = \"x\"\nvalue = 1\n",
            "s.toml",
        )
        .unwrap();
        let p = &s.perceptions[0];
        assert_eq!((p.at, p.after.as_deref(), p.occurrence, p.delay), (None, Some("evOk"), Some(2), Some(3.0)));
        let e = Scenario::from_toml(
            "[[events]]\nat = 1\nevent = \"e\"\n[[perceptions]]\nname = \"x\"\nvalue = 1\n",
            "s.toml",
        )
        .unwrap_err();
        assert!(e.starts_with("s.toml:4:1: perception `x` needs `at`"), "{e}");
        let e = Scenario::from_toml(
            "[[perceptions]]\nat = 1\nname = \"x\"\nvalue = 1\n[[perceptions]]\nat = 2\nafter = \"e\"\nname = \"y\"\nvalue = 1\n",
            "s.toml",
        )
        .unwrap_err();
        assert!(e.starts_with("s.toml:5:1: perception `y` gives both"), "{e}");
        let e =
            Scenario::from_toml("[[perceptions]]\nafter = \"e\"\noccurrence = 0\nname = \"y\"\nvalue = 1\n", "s.toml")
                .unwrap_err();
        assert!(e.starts_with("s.toml:3:"), "{e}");
    }

    #[test]
    fn errors_have_line_and_column() {
        let e = Scenario::from_toml("seed = 1\n[tasks.Goto]\ndelai = 3\n", "x.toml").unwrap_err();
        assert!(e.starts_with("x.toml:3:1: unknown field `delai`"), "{e}");
        let e = Scenario::from_toml("[tasks.Goto]\ndelay = -3\n", "x.toml").unwrap_err();
        assert!(e.starts_with("x.toml:2:9:"), "{e}");
        let e = Scenario::from_toml("[tasks.Goto]\noutcome = \"maybe\"\n", "x.toml").unwrap_err();
        assert!(e.starts_with("x.toml:2:11:"), "{e}");
        let e = Scenario::from_toml("[tasks.Goto.activation.zero]\noutcome = \"ok\"\n", "x.toml").unwrap_err();
        assert!(e.contains("x.toml:1:"), "{e}");
        let e =
            Scenario::from_toml("[tasks.Goto]\noutcome = \"ok\"\nprobabilities = { ok = 1 }\n", "x.toml").unwrap_err();
        assert!(e.contains("both"), "{e}");
        let e = Scenario::from_toml("[[events]]\nat = 1\n", "x.toml").unwrap_err();
        assert!(e.contains("missing field `event`"), "{e}");
        let e = Scenario::from_toml("seed = ", "x.toml").unwrap_err();
        assert!(e.starts_with("x.toml:1:"), "{e}");
    }
}
