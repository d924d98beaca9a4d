//! Counterexamples you can run (`mcl check --counterexample-scenario`,
//! docs/scenarios.md *Counterexamples*): a firing sequence that a verifier
//! reports (a deadlock of coordinated missions, E0406; a task stuck by its
//! pattern, E0601) becomes a scenario for the mock vehicle under which
//! `mcl run --mock --virtual-time` takes the same interleaving and ends
//! stuck in the same marking.
//!
//! * **Every task call is left unanswered** (`outcome = "never"` for every
//!   task): the vehicle sends only the events of the counterexample, as
//!   scripted `[[events]]`.
//! * **Each event of the sequence has its own instant**, [`STEP`] seconds
//!   after the previous input, or halfway to the next pending timer when
//!   that comes sooner (an event due with a timer would come second). The
//!   player fires immediate and zero-delay transitions on its own at each
//!   instant, and timed ones at their deadlines: [`build`] finds those
//!   instants by playing the sequence on the [`Player`] itself, so the
//!   schedule follows the player's firing rule exactly. Its only free
//!   choice is among transitions ready at one instant: the seeds
//!   `0..SEEDS` are tried until one follows the sequence, and the dry
//!   run's seed (its players draw on other nets) among the first
//!   [`RUN_SEEDS`].
//! * **Self-checking.** The scenario is written only once a replay of its
//!   text, in process, with the mock and the player in virtual time
//!   (`driver::run_virtual`, or `multi::run_virtual` for the vehicle nets
//!   of coordinated missions: [`check_single`], [`check_vehicles`]), ended
//!   stuck in the marking the diagnostic names; otherwise [`build`] says
//!   why no replay could be built.
//! * **The `[counterexample]` table** ([`Expected`]) tells `mcl run` what
//!   to expect: the code and place of the diagnostic, and per mission the
//!   marking it must end in. [`reproduced`] compares a run with it, from
//!   the run's `fire` records.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::sync::{Arc, Mutex};

use mcl_net::{Marking, Net, TransitionId, TransitionKind};
use serde::{Deserialize, Serialize};

use crate::driver::{run_virtual, Collect, End, Limits, Session};
use crate::mock::MockVehicle;
use crate::player::{Outcome, Output, Player, PlayerOptions};
use crate::trace::{Record, RecordKind, SourceMap, Tracer};

/// Seconds between two events of a replay (when no timer is due sooner).
pub const STEP: f64 = 1.0;

/// How many seeds of the player [`build`] tries.
pub const SEEDS: u64 = 64;

/// Prefix of the places a vehicle net adds for coordination (its copies of
/// supervisors): never compared with a counterexample's marking.
pub const COORD_PREFIX: &str = "coord.";

/// Separator between a mission's name and a node id in a centralized net.
pub const SEP: char = '/';

/// The `[counterexample]` table of a scenario: the diagnostic it replays
/// and the marking each mission must end in, stuck.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Expected {
    /// The diagnostic's code (`E0406`, `E0601`).
    pub code: String,
    /// `file:line` of the diagnostic.
    pub at: String,
    /// Its message.
    #[serde(default)]
    pub message: String,
    /// What is wrong in the marking: `dead`, `blocked` or `stuck` (E0406),
    /// `block` (E0601).
    #[serde(default)]
    pub kind: String,
    /// The calls that wait for ever, as the diagnostic names them.
    #[serde(default)]
    pub waiting: Vec<String>,
    /// Per mission: its marked places at the end (`id`, or `id*k` for `k`
    /// tokens), places named `coord.*` left out.
    pub marking: BTreeMap<String, Vec<String>>,
    /// Per mission of a coordinated run: when its mission begins, in
    /// seconds of virtual time (`[counterexample.start]`; a mission not
    /// named begins at 0). A counterexample may need a vehicle to take its
    /// first steps after another's events.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub start: BTreeMap<String, f64>,
    /// Coordination messages that arrive late (`[[counterexample.delay]]`,
    /// virtual time only): a counterexample may need a vehicle to receive a
    /// message only after another vehicle's event, as over a real link.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub delay: Vec<Delay>,
}

/// One late coordination message of a counterexample scenario: message
/// number `seq` from mission `from` to mission `to` (numbered from 1 per
/// receiver, as the trace's `coord_send` records number them) reaches `to`
/// at `at` seconds of virtual time, and the later messages of that link
/// after it (`multi::Vehicle::delaying`).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Delay {
    /// The sending mission.
    pub from: String,
    /// The receiving mission.
    pub to: String,
    /// The message's number on the link `from` → `to`.
    pub seq: u64,
    /// When it is delivered, in seconds of virtual time.
    pub at: f64,
}

/// A firing sequence to replay.
#[derive(Clone, Copy, Debug)]
pub struct Counterexample<'a> {
    /// The net `path` fires in: one mission's net, or (`centralized`) the
    /// centralized net of several, whose node ids and event names are
    /// `mission/id` and whose places `coord.*` are supervisors.
    pub net: &'a Net,
    /// Transitions of `net`, from its initial marking.
    pub path: &'a [TransitionId],
    /// True for a centralized net; false for one mission's net, named
    /// `mission`.
    pub centralized: bool,
    /// The mission of a single net (its name in `[counterexample.marking]`).
    pub mission: &'a str,
    /// Missions of a centralized net to compare although the path does not
    /// move them (those whose first call waits from the start).
    pub waiting: &'a [String],
}

impl Counterexample<'_> {
    /// The mission and local id of a node id.
    fn split<'b>(&'b self, id: &'b str) -> Option<(&'b str, &'b str)> {
        if self.centralized {
            id.split_once(SEP)
        } else {
            Some((self.mission, id))
        }
    }

    /// The missions the sequence moves (the only ones compared).
    fn missions(&self) -> BTreeSet<String> {
        if !self.centralized {
            return BTreeSet::from([self.mission.to_string()]);
        }
        self.path
            .iter()
            .filter_map(|&t| self.net.transition(t))
            .filter_map(|t| t.id.split_once(SEP).map(|(m, _)| m.to_string()))
            .chain(self.waiting.iter().cloned())
            .collect()
    }

    /// The marking the sequence ends in, per mission it moves: what
    /// [`Expected::marking`] holds.
    pub fn marking(&self, m: &Marking) -> BTreeMap<String, Vec<String>> {
        let missions = self.missions();
        let mut out: BTreeMap<String, Vec<String>> = missions.iter().map(|m| (m.clone(), Vec::new())).collect();
        for (mission, list) in self.marked(m) {
            if let Some(l) = out.get_mut(&mission) {
                *l = list;
            }
        }
        out
    }

    /// The marked places of every mission that has some.
    fn marked(&self, m: &Marking) -> BTreeMap<String, Vec<String>> {
        let mut out: BTreeMap<String, Vec<String>> = BTreeMap::new();
        for (p, n) in m.support() {
            let Some(place) = self.net.place(p) else { continue };
            let Some((mission, id)) = self.split(&place.id) else { continue };
            if id.starts_with(COORD_PREFIX) {
                continue;
            }
            out.entry(mission.to_string()).or_default().push(if n == 1 { id.to_string() } else { format!("{id}*{n}") });
        }
        out
    }
}

/// The events of a replay: (time, mission, event), in order.
#[derive(Clone, Debug, PartialEq)]
pub struct Schedule {
    /// The player's seed.
    pub seed: u64,
    /// When each event is sent, to which mission.
    pub events: Vec<(f64, String, String)>,
    /// The marking the player ended in, per mission (as [`Expected::marking`]).
    pub marking: BTreeMap<String, Vec<String>>,
    /// When each mission that starts late begins (as [`Expected::start`]).
    pub start: BTreeMap<String, f64>,
}

/// The local name of the event that starts a late mission in the net that
/// [`schedule_late`] plays (a `coord.` name: never compared, never sent).
const START: &str = "coord.start";

/// The missions of a centralized `cx` that take their first step after a
/// step of another mission, and those it names waiting that it never
/// moves (they start after the whole path): those a dry run may have to
/// start late (each vehicle of the verifier moves at its own pace, while a
/// dry run starts them one after the other at once, each settling before
/// the next).
pub fn late_missions(cx: &Counterexample<'_>) -> Vec<String> {
    let mut seen: BTreeSet<&str> = BTreeSet::new();
    let mut late = Vec::new();
    for t in cx.path.iter().filter_map(|&t| cx.net.transition(t)) {
        let Some((mission, _)) = t.id.split_once(SEP) else { continue };
        if seen.insert(mission) && seen.len() > 1 {
            late.push(mission.to_string());
        }
    }
    if !seen.is_empty() {
        late.extend(cx.waiting.iter().filter(|w| !seen.contains(w.as_str())).cloned());
        late.dedup();
    }
    late
}

/// `net` where every transition of each mission of `late` waits for a
/// token that the event `mission/coord.start` puts once (the mission's
/// start); the ids of `net`'s nodes are kept.
fn gated(net: &Net, late: &[String]) -> Result<Net, String> {
    let mut b = net.to_builder();
    for m in late {
        let idle = b.add_place(mcl_net::Place::new(format!("{m}{SEP}{COORD_PREFIX}unstarted")).with_tokens(1));
        let on = b.add_place(mcl_net::Place::new(format!("{m}{SEP}{COORD_PREFIX}started")));
        let event = format!("{m}{SEP}{START}");
        let go = b.add_transition(mcl_net::Transition::new(event.clone()).with_kind(TransitionKind::Event(event)));
        b.add_input(idle, go, 1).add_output(go, on, 1);
        let prefix = format!("{m}{SEP}");
        for t in net.transition_ids() {
            if net.transition(t).is_some_and(|x| x.id.starts_with(&prefix)) {
                b.add_input(on, t, 1).add_output(t, on, 1);
            }
        }
    }
    b.build().map_err(|e| e.to_string())
}

/// Plays `cx.path` on a [`Player`] with `seed`: each event transition of
/// the path is its event, sent at its own instant; immediate, zero-delay
/// and timed transitions are left to the player, which must fire them in
/// the path's order, up to the order of transitions fired at one instant:
/// an immediate or zero-delay step it does not take is passed over (it
/// drew another order there), and the marking it ends in decides.
pub fn schedule(cx: &Counterexample<'_>, seed: u64) -> Result<Schedule, String> {
    schedule_late(cx, seed, &[], LateStart::First)
}

/// When a late mission of [`schedule_late`] begins.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LateStart {
    /// Just before its first step in the path.
    First,
    /// Just before its first event or timer in the path (its immediate and
    /// zero-delay steps before it come with its start), or after the path:
    /// a counterexample may let a vehicle leave ready transitions unfired
    /// while another moves, which a player never does.
    FirstWait,
}

/// [`schedule`] where each mission of `late` (a centralized net's) begins
/// only at the point `when` of the path, at an instant of its own
/// ([`Schedule::start`]); the others begin at 0.
pub fn schedule_late(cx: &Counterexample<'_>, seed: u64, late: &[String], when: LateStart) -> Result<Schedule, String> {
    schedule_with(cx, seed, late, when, false)
}

/// [`schedule_late`]; with `lenient`, the events and timers of the path
/// that the player cannot take are kept (an event at its instant) or passed
/// over instead of failing: the schedule of a path that needs a late
/// message ([`Delay`]), which the player on the net of `cx`, where every
/// vehicle sees every firing at once, cannot follow.
fn schedule_with(
    cx: &Counterexample<'_>,
    seed: u64,
    late: &[String],
    when: LateStart,
    lenient: bool,
) -> Result<Schedule, String> {
    let net = Arc::new(if late.is_empty() { cx.net.clone() } else { gated(cx.net, late)? });
    // Each late mission's start, where `when` says.
    let mut path: Vec<TransitionId> = Vec::with_capacity(cx.path.len() + late.len());
    let mut started: BTreeSet<&str> = BTreeSet::new();
    for &t in cx.path {
        if let Some((m, tr)) = net.transition(t).and_then(|x| Some((x.id.split_once(SEP)?.0, x))) {
            let waits = !tr.kind.is_immediate() && !tr.kind.is_deferred();
            if late.iter().any(|l| l == m) && (when == LateStart::First || waits) && started.insert(m) {
                let go = net.transition_by_id(&format!("{m}{SEP}{START}")).ok_or("no start event")?;
                path.push(go);
            }
        }
        path.push(t);
    }
    // The late missions that the path never moves start after it.
    for m in late.iter().filter(|m| !started.contains(m.as_str())) {
        path.push(net.transition_by_id(&format!("{m}{SEP}{START}")).ok_or("no start event")?);
    }
    let mut player = Player::new(net.clone(), PlayerOptions::seeded(seed));
    let mut pending: Vec<TransitionId> = Vec::new();
    let take = |outs: &[Output], pending: &mut Vec<TransitionId>| {
        pending.extend(outs.iter().filter_map(|o| match o {
            Output::Fired { transition, .. } => Some(*transition),
            _ => None,
        }));
    };
    let name = |t: TransitionId| net.transition(t).map_or_else(|| format!("#{}", t.0), |x| x.id.to_string());
    take(&player.start(0.0), &mut pending);
    let mut events = Vec::new();
    let mut start = BTreeMap::new();
    for (i, &t) in path.iter().enumerate() {
        if let Some(k) = pending.iter().position(|&p| p == t) {
            pending.remove(k);
            continue;
        }
        let Some(tr) = net.transition(t) else { return Err(format!("step {}: no transition #{}", i + 1, t.0)) };
        if tr.kind.is_immediate() || tr.kind.is_deferred() {
            // The player chose another order among the transitions ready at
            // one instant (its draws, not the path's): passed over; the
            // marking it ends in decides ([`build`]).
            continue;
        }
        if player.outcome().is_some() {
            return Err(format!("step {}: `{}`: the mission has already ended", i + 1, tr.id));
        }
        match &tr.kind {
            TransitionKind::Event(e) => {
                let now = player.now();
                let at = match player.next_deadline() {
                    Some(d) if d < now + STEP => now + (d - now) / 2.0,
                    _ => now + STEP,
                };
                if at <= now {
                    return Err(format!("step {}: no instant is left for event `{e}` before a timer", i + 1));
                }
                let outs = player.on_event_from(at, e, None);
                let fired = outs.iter().find_map(|o| match o {
                    Output::Event { transition, .. } => Some(*transition),
                    _ => None,
                });
                if fired != Some(t) && !lenient {
                    return Err(match fired {
                        Some(x) => format!("step {}: event `{e}` fired `{}`, not `{}`", i + 1, name(x), tr.id),
                        None => format!("step {}: event `{e}` found `{}` not enabled", i + 1, tr.id),
                    });
                }
                take(&outs, &mut pending);
                if let Some(k) = pending.iter().position(|&p| p == t) {
                    pending.remove(k);
                }
                let (mission, local) = cx.split(e).unwrap_or((cx.mission, e));
                if local == START && late.iter().any(|l| l == mission) {
                    start.insert(mission.to_string(), at);
                } else {
                    events.push((at, mission.to_string(), local.to_string()));
                }
            }
            TransitionKind::Timed(_) => {
                let Some(&(_, due)) = player.timers().iter().find(|(x, _)| *x == t) else {
                    if lenient {
                        continue;
                    }
                    return Err(format!("step {}: the timer of `{}` is not running", i + 1, tr.id));
                };
                let outs = player.on_timer(due);
                take(&outs, &mut pending);
                match pending.iter().position(|&p| p == t) {
                    Some(k) => {
                        pending.remove(k);
                    }
                    None if lenient => {}
                    None => return Err(format!("step {}: timer `{}` did not fire at {due} s", i + 1, tr.id)),
                }
            }
            TransitionKind::Immediate => {}
        }
    }
    Ok(Schedule { seed, events, marking: cx.marking(player.marking()), start })
}

/// The text of a scenario that replays `schedule`, leaving every task of
/// `tasks` unanswered, with the `[counterexample]` table `expected`. With
/// `per_mission`, events go to `[[missions.NAME.events]]` (a coordinated
/// run), else to `[[events]]`.
pub fn scenario_text(schedule: &Schedule, tasks: &[String], expected: &Expected, per_mission: bool) -> String {
    let q = |s: &str| serde_json::to_string(s).unwrap_or_else(|_| "\"\"".into());
    // A bare key when it can be one.
    let key = |s: &str| {
        if !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-') {
            s.to_string()
        } else {
            q(s)
        }
    };
    let list = |v: &[String]| format!("[{}]", v.iter().map(|s| q(s)).collect::<Vec<_>>().join(", "));
    let mut s = String::new();
    let _ = writeln!(s, "# A run of the counterexample of {} at {}.", expected.code, expected.at);
    let _ = writeln!(s, "# Made by `mcl check --counterexample-scenario`; replay it with");
    let _ = writeln!(s, "#   mcl run --mock --virtual-time FILE --scenario THIS.toml");
    let _ = writeln!(s, "# Every task is left unanswered; the vehicle sends only the events of the");
    let _ = writeln!(s, "# counterexample, each at its own instant, so that the player takes the same");
    let _ = writeln!(s, "# interleaving and ends stuck in the marking below (docs/scenarios.md).");
    let _ = writeln!(s, "seed = {}", schedule.seed);
    let _ = writeln!(s, "\n[counterexample]");
    let _ = writeln!(s, "code = {}", q(&expected.code));
    let _ = writeln!(s, "at = {}", q(&expected.at));
    let _ = writeln!(s, "message = {}", q(&expected.message));
    let _ = writeln!(s, "kind = {}", q(&expected.kind));
    let _ = writeln!(s, "waiting = {}", list(&expected.waiting));
    let _ = writeln!(s, "\n[counterexample.marking]");
    for (m, places) in &expected.marking {
        let _ = writeln!(s, "{} = {}", key(m), list(places));
    }
    if !expected.start.is_empty() {
        let _ = writeln!(s, "\n[counterexample.start]");
        for (m, t) in &expected.start {
            let _ = writeln!(s, "{} = {t:?}", key(m));
        }
    }
    for d in &expected.delay {
        let _ = writeln!(s, "\n[[counterexample.delay]]");
        let _ = writeln!(s, "from = {}\nto = {}\nseq = {}\nat = {:?}", q(&d.from), q(&d.to), d.seq, d.at);
    }
    for t in tasks {
        let _ = writeln!(s, "\n[tasks.{}]\noutcome = \"never\"", key(t));
    }
    for (at, mission, event) in &schedule.events {
        if per_mission {
            let _ = writeln!(s, "\n[[missions.{}.events]]", key(mission));
        } else {
            let _ = writeln!(s, "\n[[events]]");
        }
        let _ = writeln!(s, "at = {at:?}\nevent = {}", q(event));
    }
    s
}

/// Builds the scenario of `cx`: for each seed in `0..SEEDS`, the schedule
/// of the path ([`schedule`]), kept when the player ends in `expected`'s
/// marking, and its text ([`scenario_text`]) kept when `check` (a replay of
/// the text with the mock: [`check_single`], [`check_vehicles`]) accepts
/// it. Errors say why no seed gave a replay.
///
/// A counterexample of the verifier of coordinated missions may rely on a
/// vehicle taking its first steps later than another (each vehicle moves
/// at its own pace there). When no seed follows the path with every
/// vehicle starting at once, the missions that take their first step after
/// another's ([`late_missions`]) start late, each just
/// before its first step ([`Expected::start`], [`schedule_late`]), then
/// just before its first event or timer ([`LateStart::FirstWait`]); failing
/// that, the shortest path of the same net to the same marking
/// ([`SEARCH_STATES`] markings at most, the player's firing rule) is tried
/// instead; when there is none, the error says so.
pub fn build(
    cx: &Counterexample<'_>,
    tasks: &[String],
    expected: &Expected,
    per_mission: bool,
    check: impl Fn(&str) -> Result<(), String>,
) -> Result<String, String> {
    let why = match build_on(cx, tasks, expected, per_mission, &check, (&[], LateStart::First)) {
        Ok(text) => return Ok(text),
        Err(why) => why,
    };
    let late = if cx.centralized { late_missions(cx) } else { Vec::new() };
    let why = if late.is_empty() {
        why
    } else {
        let first = match build_on(cx, tasks, expected, per_mission, &check, (&late, LateStart::First)) {
            Ok(text) => return Ok(text),
            Err(e) => format!("{why}; with {} starting late: {e}", late.join(", ")),
        };
        match build_on(cx, tasks, expected, per_mission, &check, (&late, LateStart::FirstWait)) {
            Ok(text) => return Ok(text),
            Err(e) => format!("{first}; and later: {e}"),
        }
    };
    let why = match build_other(cx, tasks, expected, per_mission, &check) {
        Ok(text) => return Ok(text),
        Err(e) => format!("{why}; {e}"),
    };
    if !cx.centralized {
        return Err(why);
    }
    build_delayed(cx, tasks, expected, &check, &late).map_err(|e| format!("{why}; with a late message: {e}"))
}

/// [`build`] along the shortest path of the same net to the same marking.
fn build_other(
    cx: &Counterexample<'_>,
    tasks: &[String],
    expected: &Expected,
    per_mission: bool,
    check: &impl Fn(&str) -> Result<(), String>,
) -> Result<String, String> {
    let ss = mcl_net::explore(cx.net, &mcl_net::Options { max_states: SEARCH_STATES, ..Default::default() });
    let target = ss
        .states()
        .find(|&s| !ss.is_vanishing(s) && same_marking(&expected.marking, &cx.marked(&ss.marking(s))).is_ok());
    let Some(target) = target else {
        return Err(format!(
            "and no run {}reaches that marking when every vehicle starts at once",
            if ss.complete() { "" } else { "within the markings explored " }
        ));
    };
    let path = ss.path_to(target);
    let other = Counterexample { path: &path, ..*cx };
    build_on(&other, tasks, expected, per_mission, check, (&[], LateStart::First))
        .map_err(|e| format!("and along another run: {e}"))
}

/// A centralized `cx` whose path no player follows: the schedule of its
/// events ([`schedule_with`], lenient; every vehicle at once, then those of
/// `late` starting late as in [`build_on`]) with one coordination message
/// delivered late ([`Delay`]): each message of each link, number 1 up to
/// the sender's steps in the path, at each instant halfway between two
/// inputs of the schedule (or [`STEP`] / 2 after the last), until `check`
/// accepts one. The verifier lets a vehicle leave a transition unfired that
/// a message allowed while another vehicle's event withdraws what allowed
/// it; a real link that delivers that message after the event does the same.
fn build_delayed(
    cx: &Counterexample<'_>,
    tasks: &[String],
    expected: &Expected,
    check: &impl Fn(&str) -> Result<(), String>,
    late: &[String],
) -> Result<String, String> {
    let missions: Vec<String> = cx.missions().into_iter().collect();
    let mut why = String::from("no schedule of the events");
    let ways = [(&[][..], LateStart::First), (late, LateStart::First), (late, LateStart::FirstWait)];
    for (k, &(l, when)) in ways.iter().enumerate() {
        if k > 0 && l.is_empty() {
            continue;
        }
        let Some(sch) = (0..SEEDS).find_map(|seed| schedule_with(cx, seed, l, when, true).ok()) else { continue };
        let mut inputs: Vec<f64> = sch.events.iter().map(|e| e.0).chain(sch.start.values().copied()).collect();
        inputs.sort_by(f64::total_cmp);
        inputs.dedup();
        let mut ats: Vec<f64> = inputs.windows(2).map(|w| (w[0] + w[1]) / 2.0).collect();
        ats.extend(inputs.last().map(|t| t + STEP / 2.0));
        for from in &missions {
            let prefix = format!("{from}{SEP}");
            let steps =
                cx.path.iter().filter(|&&t| cx.net.transition(t).is_some_and(|x| x.id.starts_with(&prefix))).count()
                    as u64;
            for to in missions.iter().filter(|t| *t != from) {
                for seq in 1..=steps {
                    for &at in &ats {
                        let delay = vec![Delay { from: from.clone(), to: to.clone(), seq, at }];
                        let want = Expected { start: sch.start.clone(), delay, ..expected.clone() };
                        let text = scenario_text(&sch, tasks, &want, true);
                        match check(&text) {
                            Ok(()) => return Ok(text),
                            Err(e) => why = format!("no late message makes a dry run reproduce it ({e})"),
                        }
                    }
                }
            }
        }
    }
    Err(why)
}

/// Largest number of markings [`build`] explores to find another path.
pub const SEARCH_STATES: usize = 200_000;

fn build_on(
    cx: &Counterexample<'_>,
    tasks: &[String],
    expected: &Expected,
    per_mission: bool,
    check: &impl Fn(&str) -> Result<(), String>,
    (late, when): (&[String], LateStart),
) -> Result<String, String> {
    let mut why = String::from("no seed tried");
    let mut schedules = 0;
    for seed in 0..SEEDS {
        if schedules == SCHEDULES {
            break;
        }
        let sch = match schedule_late(cx, seed, late, when) {
            Ok(s) => s,
            Err(e) => {
                why = format!("the player cannot follow the counterexample ({e})");
                continue;
            }
        };
        if let Err(e) = same_marking(&expected.marking, &sch.marking) {
            why = format!("the player does not end where the counterexample does ({e})");
            continue;
        }
        schedules += 1;
        let want = Expected { start: sch.start.clone(), ..expected.clone() };
        // The dry run's players draw on other nets (the vehicle nets, or
        // with the mock): its seed is the schedule's, else one of the first
        // few that reproduces it.
        for run_seed in std::iter::once(seed).chain((0..RUN_SEEDS).filter(|&s| s != seed)) {
            let text = scenario_text(&Schedule { seed: run_seed, ..sch.clone() }, tasks, &want, per_mission);
            match check(&text) {
                Ok(()) => return Ok(text),
                Err(e) => why = format!("a dry run of the scenario does not reproduce it ({e})"),
            }
        }
    }
    Err(why)
}

/// How many schedules that end in the counterexample's marking
/// [`build`] checks by a dry run at most, per way of starting the vehicles.
pub const SCHEDULES: usize = 4;

/// How many seeds of the dry run [`build`] tries per schedule (besides the
/// schedule's own).
pub const RUN_SEEDS: u64 = 16;

/// Compares markings (as [`Expected::marking`]) on the missions of `want`.
fn same_marking(want: &BTreeMap<String, Vec<String>>, got: &BTreeMap<String, Vec<String>>) -> Result<(), String> {
    for (m, places) in want {
        let mut a = places.clone();
        let mut b = got.get(m).cloned().unwrap_or_default();
        a.sort();
        b.sort();
        if a != b {
            return Err(format!("mission `{m}` ends in {{{}}}, expected {{{}}}", b.join(", "), a.join(", ")));
        }
    }
    Ok(())
}

/// The transition a `fire` record names.
fn fire_of(r: &Record) -> Option<&str> {
    match &r.kind {
        RecordKind::Fire { transition, .. } => Some(transition.as_str()),
        _ => None,
    }
}

/// The marking each mission of a run ended in, per [`Expected::marking`],
/// rebuilt by firing its `fire` records on its net (`nets`: mission name
/// and net; a record without a mission belongs to the only net). An
/// `event` record naming a transition that no `fire` record of it follows
/// was applied without one (a coordinated vehicle takes the messages that
/// arrived before it started into its initial marking): it is fired too.
pub fn final_markings(nets: &[(String, &Net)], records: &[Record]) -> Result<BTreeMap<String, Vec<String>>, String> {
    let mut out = BTreeMap::new();
    for (name, net) in nets {
        let mut m = net.initial_marking();
        let mine: Vec<&Record> = records
            .iter()
            .filter(|r| r.mission.as_deref().is_none_or(|x| x == name.as_str() || nets.len() == 1))
            .collect();
        // The transition of a `fire` record, or of an `event` record that
        // no `fire` of the same transition follows.
        let fired = mine.iter().enumerate().filter_map(|(i, r)| match &r.kind {
            RecordKind::Fire { transition, .. } => Some(transition.as_str()),
            RecordKind::Event { transition, .. }
                if mine.get(i + 1).is_none_or(|n| fire_of(n) != Some(transition.as_str())) =>
            {
                Some(transition.as_str())
            }
            _ => None,
        });
        for id in fired {
            let t = net.transition_by_id(id).ok_or_else(|| format!("mission `{name}` has no transition `{id}`"))?;
            mcl_net::semantics::fire(net, &mut m, t).map_err(|e| format!("mission `{name}`: `{id}`: {e}"))?;
        }
        let cx = Counterexample { net, path: &[], centralized: false, mission: name, waiting: &[] };
        let mut marked = cx.marking(&m);
        out.append(&mut marked);
    }
    Ok(out)
}

/// Whether a run reproduced `expected`: every mission it names ended in its
/// marking, stuck (`stuck`: the missions whose run ended stuck) unless that
/// marking is the mission's end (`mission.ok`, `mission.fail`: a mission
/// that ended while another waits for ever). `Err` says how the run
/// differs.
pub fn reproduced(
    expected: &Expected,
    nets: &[(String, &Net)],
    records: &[Record],
    stuck: &[String],
) -> Result<(), String> {
    for m in expected.marking.keys() {
        if !nets.iter().any(|(n, _)| n == m) {
            return Err(format!("the program has no mission `{m}`"));
        }
        let ended = expected.marking[m].iter().any(|p| {
            let id = p.split('*').next().unwrap_or(p);
            id == crate::player::MISSION_OK || id == crate::player::MISSION_FAIL
        });
        if !ended && !stuck.contains(m) {
            return Err(format!("mission `{m}` did not end stuck"));
        }
    }
    let got = final_markings(nets, records)?;
    same_marking(&expected.marking, &got)
}

/// The `[counterexample]` table of a scenario text, if it has one.
pub fn expected_of(text: &str) -> Option<Expected> {
    let table: toml::Table = toml::from_str(text).ok()?;
    table.get("counterexample")?.clone().try_into().ok()
}

/// Replays a scenario text on one mission's net with the mock vehicle in
/// virtual time, and checks the run against its `[counterexample]` table.
pub fn check_single(net: &Arc<Net>, mission: &str, text: &str) -> Result<(), String> {
    let scenario = crate::scenario::Scenario::from_toml(text, "counterexample scenario")?;
    let expected = scenario.counterexample.clone().ok_or("the scenario has no [counterexample] table")?;
    let seed = scenario.seed.unwrap_or(0);
    let mut sink = Collect::default();
    let mut sources = SourceMap::new();
    let tracer = Tracer::new(net, Some(mission.to_string()), &mut sources);
    let player =
        Player::new(net.clone(), PlayerOptions { symbols: scenario.symbols.clone(), ..PlayerOptions::seeded(seed) });
    let mut mock = MockVehicle::from_net(net, scenario, seed);
    mock.initial();
    let end = {
        let mut s = Session::new(player, tracer, &mut sink);
        run_virtual(&mut s, &mut mock, Limits::virtual_time(None))?
    };
    let stuck = is_stuck(&end).then(|| mission.to_string()).into_iter().collect::<Vec<_>>();
    reproduced(&expected, &[(mission.to_string(), net.as_ref())], &sink.0, &stuck)
}

/// True when a run ended stuck (nothing more could happen, or the player
/// found nothing to fire).
pub fn is_stuck(end: &End) -> bool {
    matches!(end, End::Quiescent { .. } | End::Outcome(Outcome::Stuck))
}

/// Replays a scenario text on the vehicle nets of coordinated missions
/// (`multi::run_virtual`, in-process transport) and checks the run against
/// its `[counterexample]` table.
pub fn check_vehicles(nets: &[(String, Arc<Net>)], text: &str) -> Result<(), String> {
    let expected = expected_of(text).ok_or("the scenario has no [counterexample] table")?;
    let names: Vec<String> = nets.iter().map(|(n, _)| n.clone()).collect();
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the runtime: {e}"))?;
    let sink = Arc::new(Mutex::new(Collect::default()));
    let shared: crate::multi::SharedSink = sink.clone();
    let mut sources = SourceMap::new();
    let mut parts = Vec::new();
    for (name, net) in nets {
        let scenario = crate::multi::scenario_for(text, "counterexample scenario", name)?;
        let seed = scenario.seed.unwrap_or(0);
        let opts = PlayerOptions { symbols: scenario.symbols.clone(), ..PlayerOptions::seeded(seed) };
        let tracer = Tracer::new(net, Some(name.clone()), &mut sources);
        let mock = MockVehicle::from_net(net, scenario, seed);
        parts.push((name.clone(), net.clone(), opts, tracer, mock));
    }
    let end = rt.block_on(async {
        let mut vs = Vec::new();
        for ((name, net, opts, tracer, mock), tr) in parts.into_iter().zip(crate::coord::in_process(&names)) {
            let start = expected.start.get(&name).copied().unwrap_or(0.0);
            let mut v = crate::multi::Vehicle::new(&name, net, opts, tracer, mock, Box::new(tr))?.starting_at(start);
            for d in expected.delay.iter().filter(|d| d.from == name) {
                v = v.delaying(&d.to, d.seq, d.at);
            }
            vs.push(v);
        }
        crate::multi::run_virtual(vs, shared, Limits::virtual_time(None)).await
    })?;
    let stuck: Vec<String> = end.ends.iter().filter(|(_, e, _)| is_stuck(e)).map(|(n, _, _)| n.clone()).collect();
    let records = sink.lock().map_err(|_| "the replay failed".to_string())?.0.clone();
    let refs: Vec<(String, &Net)> = nets.iter().map(|(n, net)| (n.clone(), net.as_ref())).collect();
    reproduced(&expected, &refs, &records, &stuck)
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcl_net::{NetBuilder, Place, Transition};

    /// begin -> T0 (immediate) -> run; run -> T1 (event `go`) -> mid;
    /// mid -> T2 (timed 3 s) -> end; `end` has no way out.
    fn net() -> Net {
        let mut b = NetBuilder::new("m");
        let begin = b.add_place(Place::new("begin").with_tokens(1));
        let run = b.add_place(Place::new("run"));
        let mid = b.add_place(Place::new("mid"));
        let end = b.add_place(Place::new("end"));
        let t0 = b.add_transition(Transition::new("T0"));
        let t1 = b.add_transition(Transition::new("T1").with_kind(TransitionKind::Event("go".into())));
        let t2 = b.add_transition(Transition::new("T2").with_kind(TransitionKind::Timed(mcl_net::Delay::Fixed(3.0))));
        b.add_input(begin, t0, 1);
        b.add_output(t0, run, 1);
        b.add_input(run, t1, 1);
        b.add_output(t1, mid, 1);
        b.add_input(mid, t2, 1);
        b.add_output(t2, end, 1);
        b.build().unwrap()
    }

    #[test]
    fn events_get_instants_and_timers_their_deadlines() {
        let n = net();
        let path: Vec<TransitionId> = ["T0", "T1", "T2"].iter().map(|id| n.transition_by_id(id).unwrap()).collect();
        let cx = Counterexample { net: &n, path: &path, centralized: false, mission: "m", waiting: &[] };
        let s = schedule(&cx, 0).unwrap();
        assert_eq!(s.events, vec![(STEP, "m".to_string(), "go".to_string())]);
        assert_eq!(s.marking["m"], ["end"]);
        let mut m = n.initial_marking();
        for &t in &path {
            mcl_net::semantics::fire(&n, &mut m, t).unwrap();
        }
        let expected =
            Expected { code: "E0000".into(), at: "x:1".into(), marking: cx.marking(&m), ..Default::default() };
        let net = Arc::new(n.clone());
        let text = build(&cx, &[], &expected, false, |t| check_single(&net, "m", t)).unwrap();
        assert!(text.contains("[[events]]\nat = 1.0\nevent = \"go\""), "{text}");
        assert_eq!(expected_of(&text).unwrap(), expected);
        // A path the player cannot take (T2 before the event): the
        // shortest path to the same marking replaces it.
        let bad = [path[0], path[2]];
        let cx = Counterexample { net: &n, path: &bad, centralized: false, mission: "m", waiting: &[] };
        let e = schedule(&cx, 0).unwrap_err();
        assert!(e.contains("not running"), "{e}");
        assert_eq!(build(&cx, &[], &expected, false, |t| check_single(&net, "m", t)).unwrap(), text);
        // A marking no run reaches: no scenario.
        let nowhere = Expected {
            marking: BTreeMap::from([("m".to_string(), vec!["run".to_string(), "mid".to_string()])]),
            ..expected
        };
        let e = build(&cx, &[], &nowhere, false, |t| check_single(&net, "m", t)).unwrap_err();
        assert!(e.contains("no run reaches that marking"), "{e}");
    }

    #[test]
    fn late_messages_are_written_and_read_back() {
        let expected = Expected {
            code: "E0406".into(),
            at: "x:1".into(),
            marking: BTreeMap::from([("b".to_string(), vec!["p".to_string()])]),
            delay: vec![Delay { from: "a".into(), to: "b".into(), seq: 2, at: 2.5 }],
            ..Default::default()
        };
        let s = Schedule { seed: 0, events: Vec::new(), marking: BTreeMap::new(), start: BTreeMap::new() };
        let text = scenario_text(&s, &[], &expected, true);
        assert!(text.contains("[[counterexample.delay]]\nfrom = \"a\"\nto = \"b\"\nseq = 2\nat = 2.5"), "{text}");
        assert_eq!(expected_of(&text).unwrap(), expected);
    }

    #[test]
    fn a_run_that_ends_elsewhere_is_not_a_reproduction() {
        let n = net();
        let expected = Expected {
            code: "E0000".into(),
            at: "x:1".into(),
            marking: BTreeMap::from([("m".to_string(), vec!["mid".to_string()])]),
            ..Default::default()
        };
        let s = Schedule {
            seed: 0,
            events: vec![(1.0, "m".into(), "go".into())],
            marking: BTreeMap::new(),
            start: BTreeMap::new(),
        };
        let text = scenario_text(&s, &[], &expected, false);
        // The timer of T2 fires after the event: the run ends in `end`.
        let e = check_single(&Arc::new(n), "m", &text).unwrap_err();
        assert!(e.contains("{end}") && e.contains("{mid}"), "{e}");
    }
}
