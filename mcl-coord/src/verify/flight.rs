//! The exact product: the vehicles as their players run them, with the
//! coordination messages *in flight* (docs/coordination.md, "Messages in
//! flight").
//!
//! Each vehicle plays its own vehicle net (`crate::decentralize`: its
//! mission, its supervisor copies, its receive transitions and the
//! single-holder mutex nodes) as `mcl_runtime::multi` runs it over a real
//! link: an input (its start, an event of its mission, a timer) fires, the
//! net *stabilizes* (ready immediate transitions, then zero-delay ones, by
//! priority, every choice explored), and the runtime's reaction follows at
//! once, as one step: the messages of its `coord.send` firings, the
//! requests and returns of the borrowed mutex tokens (`Live::arbitrate`),
//! and the delivery of the inbox (the messages whose receive transitions
//! can fire, taken as one batch, `Live::deliver`; once its mission has
//! ended, a vehicle's supervisor places still serve). A message sent waits
//! in the FIFO buffer of its link (in order, once, any delay), and its
//! arrival at the receiver is a separate step, after which the receiver
//! reacts at once (a real link) or takes more messages first and reacts to
//! them together (a virtual-time run). A vehicle may start late:
//! the messages that arrived before fire on its initial marking first
//! (`Live::start`). Time is abstracted as in the vehicle graphs (`lts.rs`):
//! any event of a mission and any running timer may come next.
//!
//! Every run of the players over any link is a path of this product, and
//! every path is a run: a verdict it gives is exact. It is used to decide
//! the deadlocks that the interleaving product reports (`mod.rs`): when
//! every state it reaches can still reach the end of every mission that can
//! end alone, no player can be stuck, and the group is free.

use std::collections::hash_map::Entry as MapEntry;

use mcl_net::semantics::{is_enabled_with, select_ready};
use mcl_net::{Net, PlaceId, TransitionId, TransitionKind};
use mcl_runtime::coord::TokenMutex;
use rustc_hash::{FxHashMap, FxHashSet};

use crate::decentral::VehicleNet;
use crate::model::Mission;

/// Largest number of firings one stabilization may explore (a livelock, or
/// too many orders of its choices, beyond it).
const SETTLE_STEPS: usize = 100_000;

/// A vehicle's phase.
const NOT_STARTED: u8 = 0;
const RUNNING: u8 = 1;
/// Its mission ended ok or failed (a final place marked, stable).
const ENDED: u8 = 2;
/// Its player stopped without a final place (nothing non-immediate enabled).
const STOPPED: u8 = 3;

/// One vehicle of the exact product.
#[derive(Clone, PartialEq, Eq, Hash)]
struct VState {
    phase: u8,
    marking: Vec<u32>,
    /// Per borrowed mutex: tokens asked for and not yet granted.
    asked: Vec<u32>,
    /// Messages arrived and not yet taken (ids into [`Flight::msgs`]).
    inbox: Vec<u32>,
    /// Messages arrived that the vehicle has not reacted to yet: a
    /// virtual-time run hands a vehicle every message of another's
    /// reaction before it reacts (`Fleet::exchange_messages`), a real link
    /// one at a time; until it reacts, it takes no input.
    pending: bool,
}

/// A state of the exact product: the vehicles and, per ordered pair of
/// vehicles, the messages on their way (`links[from * n + to]`, oldest first).
#[derive(Clone, PartialEq, Eq, Hash)]
struct State {
    vs: Vec<VState>,
    links: Vec<Vec<u32>>,
}

/// A vehicle's state with the messages its step sent, in order, and the
/// transitions it fired (for [`stuck_run`]).
type Run = (VState, Vec<u32>, Vec<TransitionId>);

/// A message: the receiving vehicle and the event it raises there.
struct Msg {
    to: usize,
    event: String,
}

/// What one vehicle needs.
struct Veh {
    net: Net,
    /// Per transition: the messages its firing sends.
    sends: Vec<Vec<u32>>,
    /// Per transition: a transition of the mission that its mock or its
    /// clock fires (an event of the mission or a timer), not a message.
    input: Vec<bool>,
    /// Per transition: it never fires while one of these places is marked
    /// (the off-nominal answers, in nominal runs).
    quiet: Vec<Vec<PlaceId>>,
    /// Per transition: every place it touches is a supervisor copy.
    coord_only: Vec<bool>,
    tokens: Vec<TokenMutex>,
    /// Per borrowed mutex: the message that gives a token back.
    ret: Vec<Option<u32>>,
    finals: Vec<PlaceId>,
}

/// The verdict of the exact product.
#[derive(Debug, PartialEq, Eq)]
pub(super) enum Flown {
    /// Every reachable state can still reach the end of every mission that
    /// can end alone.
    Free,
    /// Some player can be stuck.
    Stuck,
    /// Past the cap, a livelock, or vehicle nets it cannot read.
    Unknown,
}

/// The exact product of the vehicles `group` (indices into `missions` and
/// `nets`, in the same order), `can_end` per vehicle of the group; with
/// `quiet`, the off-nominal answers never come. At most `max` states.
pub(super) fn fly(
    missions: &[Mission],
    nets: &[VehicleNet],
    group: &[usize],
    can_end: &[bool],
    quiet: bool,
    max: usize,
) -> Flown {
    match Flight::new(missions, nets, group, quiet) {
        Some(f) => f.explore(can_end, max, false).0,
        None => Flown::Unknown,
    }
}

/// Checks that the firings of a run of the players (`fires`: the vehicle,
/// an index into `missions` and `nets`, and the transition of its vehicle
/// net, in the order the run took them) are a path of the exact product
/// of every vehicle: each step of the product fires, in one vehicle, a
/// block of consecutive firings of the run (as a multiset: the order
/// inside one stabilization is the engine's draw). At most `max` pairs of
/// a state and a position in the run are explored. The error says how far
/// the run was followed.
pub fn follows(
    missions: &[Mission],
    nets: &[VehicleNet],
    fires: &[(usize, TransitionId)],
    max: usize,
) -> Result<(), String> {
    let all: Vec<usize> = (0..nets.len().min(missions.len())).collect();
    let f = Flight::new(missions, nets, &all, false).ok_or("the vehicle nets cannot be read")?;
    let mut seen: FxHashSet<(State, usize)> = FxHashSet::default();
    let init = (f.initial(), 0usize);
    seen.insert(init.clone());
    let mut queue = std::collections::VecDeque::from([init]);
    let mut furthest = 0usize;
    while let Some((s, pos)) = queue.pop_front() {
        furthest = furthest.max(pos);
        if pos == fires.len() {
            return Ok(());
        }
        let next = f.successors(&s).ok_or("a stabilization passed its step limit")?;
        for (x, v, log) in next {
            let k = log.len();
            let block = fires.get(pos..pos + k).filter(|b| b.iter().all(|&(w, _)| w == v));
            let Some(block) = block else { continue };
            let mut a: Vec<TransitionId> = block.iter().map(|&(_, t)| t).collect();
            let mut b = log;
            a.sort_unstable();
            b.sort_unstable();
            if a == b && seen.insert((x.clone(), pos + k)) {
                if seen.len() > max {
                    return Err(format!("more than {max} states explored; followed {furthest} firings"));
                }
                queue.push_back((x, pos + k));
            }
        }
    }
    Err(format!("no path of the exact product fires the run past its first {furthest} firings"))
}

/// A run of the players, over links that may delay their messages, to a
/// stuck state of the exact product.
pub struct StuckRun {
    /// Per step: the vehicle (an index into the missions) and the
    /// transitions of its vehicle net that the step fired, in order.
    pub steps: Vec<(usize, Vec<TransitionId>)>,
    /// The marking of each vehicle net in the stuck state.
    pub markings: Vec<Vec<u32>>,
}

/// The run to a stuck state of the exact product of every vehicle of
/// `nets` (the vehicle nets of `missions`, in order), if it has one within
/// `max` states: a dead one when there is one on the way of its depth-first
/// search, else one from which some mission can no longer end. With
/// `quiet`, the off-nominal answers never come. Every mission counts as
/// able to end alone.
pub fn stuck_run(missions: &[Mission], nets: &[VehicleNet], quiet: bool, max: usize) -> Option<StuckRun> {
    let all: Vec<usize> = (0..nets.len().min(missions.len())).collect();
    let f = Flight::new(missions, nets, &all, quiet)?;
    f.explore(&vec![true; all.len()], max, true).1
}

struct Flight {
    vehs: Vec<Veh>,
    msgs: Vec<Msg>,
}

impl Flight {
    fn new(missions: &[Mission], nets: &[VehicleNet], group: &[usize], quiet: bool) -> Option<Flight> {
        let names: Vec<&str> = group.iter().map(|&v| nets.get(v).map(|n| n.mission.as_str())).collect::<Option<_>>()?;
        let mut msgs: Vec<Msg> = Vec::new();
        let mut ids: FxHashMap<(usize, String), u32> = FxHashMap::default();
        let mut intern = |to: usize, event: String| -> u32 {
            *ids.entry((to, event.clone())).or_insert_with(|| {
                msgs.push(Msg { to, event });
                msgs.len() as u32 - 1
            })
        };
        let mut vehs = Vec::new();
        for (i, &v) in group.iter().enumerate() {
            let (vn, m) = (nets.get(v)?, missions.get(v)?);
            let net = vn.net.clone();
            let nt = net.transition_count();
            let table = mcl_runtime::coord::send_table(&net).ok()?;
            let tokens = mcl_runtime::coord::token_table(&net).ok()?;
            let mut sends = vec![Vec::new(); nt];
            for t in net.transition_ids() {
                let id = net.transitions()[t.index()].id.to_string();
                for to in table.get(&id).into_iter().flatten() {
                    // A message to a vehicle of another group changes nothing here.
                    if let Some(j) = names.iter().position(|n| n == to) {
                        sends[t.index()].push(intern(j, format!("{}/{id}", names[i])));
                    }
                }
            }
            let ret = tokens
                .iter()
                .map(|k| {
                    names.iter().position(|n| *n == k.holder).map(|h| intern(h, format!("{}/{}", names[i], k.ret)))
                })
                .collect();
            let receive: FxHashSet<&str> = vn.receive.iter().map(|(t, _)| t.as_str()).collect();
            let token_events: FxHashSet<&str> =
                tokens.iter().flat_map(|k| [k.request.as_str(), k.ret.as_str()]).collect();
            let input = net
                .transitions()
                .iter()
                .map(|tr| match &tr.kind {
                    TransitionKind::Event(e) => {
                        !receive.contains(tr.id.as_str()) && !token_events.contains(e.as_str()) && !e.contains('/')
                    }
                    TransitionKind::Timed(_) => !tr.kind.is_deferred(),
                    TransitionKind::Immediate => false,
                })
                .collect();
            let mut quiet_ps = vec![Vec::new(); nt];
            if quiet {
                for (t, ps) in &m.off_nominal {
                    let Some(tr) = m.net.transitions().get(t.index()) else { continue };
                    let Some(t2) = net.transition_by_id(&tr.id) else { continue };
                    quiet_ps[t2.index()] =
                        ps.iter().filter_map(|p| m.net.place(*p).and_then(|x| net.place_by_id(&x.id))).collect();
                }
            }
            let is_coord = |p: PlaceId| net.place(p).is_some_and(|x| x.id.starts_with("coord."));
            let coord_only =
                net.transition_ids().map(|t| net.pre(t).iter().chain(net.post(t)).all(|&(p, _)| is_coord(p))).collect();
            let finals = m.final_places.iter().filter_map(|p| m.net.place(*p).and_then(|x| net.place_by_id(&x.id)));
            let finals = finals.collect();
            vehs.push(Veh { sends, input, quiet: quiet_ps, coord_only, tokens, ret, finals, net });
        }
        Some(Flight { vehs, msgs })
    }

    fn initial(&self) -> State {
        let n = self.vehs.len();
        State {
            vs: self
                .vehs
                .iter()
                .map(|v| VState {
                    phase: NOT_STARTED,
                    marking: v.net.places().iter().map(|p| p.initial).collect(),
                    asked: vec![0; v.tokens.len()],
                    inbox: Vec::new(),
                    pending: false,
                })
                .collect(),
            links: vec![Vec::new(); n * n],
        }
    }

    /// Explores the product from its initial state; with `record`, the
    /// run to the stuck state found ([`StuckRun`]).
    fn explore(&self, can_end: &[bool], max: usize, record: bool) -> (Flown, Option<StuckRun>) {
        let n = self.vehs.len();
        let mut index: FxHashMap<State, u32> = FxHashMap::default();
        let mut states: Vec<State> = vec![self.initial()];
        index.insert(states[0].clone(), 0);
        let mut succ: Vec<Vec<u32>> = Vec::new();
        // How each state was first reached: (parent, vehicle, its firings).
        let mut parent: Vec<(u32, usize, Vec<TransitionId>)> = vec![(u32::MAX, 0, Vec::new())];
        let run_to = |target: u32, states: &[State], parent: &[(u32, usize, Vec<TransitionId>)]| {
            let mut steps = Vec::new();
            let mut cur = target;
            while let Some((p, v, log)) = parent.get(cur as usize).filter(|x| x.0 != u32::MAX) {
                steps.push((*v, log.clone()));
                cur = *p;
            }
            steps.reverse();
            let markings = states[target as usize].vs.iter().map(|v| v.marking.clone()).collect();
            Some(StuckRun { steps, markings })
        };
        let is_target = |s: &State| (0..n).all(|v| !can_end[v] || s.vs[v].phase == ENDED);
        // Depth first: a stuck state is met early, and one ends the search.
        let mut stack = vec![0u32];
        let mut done = vec![false];
        while let Some(i) = stack.pop() {
            if done[i as usize] {
                continue;
            }
            done[i as usize] = true;
            if i % 4096 == 0 {
                crate::interrupt::poll();
            }
            let Some(next) = self.successors(&states[i as usize]) else { return (Flown::Unknown, None) };
            if next.is_empty() && !is_target(&states[i as usize]) {
                let run = if record { run_to(i, &states, &parent) } else { None };
                return (Flown::Stuck, run);
            }
            let mut out = Vec::with_capacity(next.len());
            for (s, v, log) in next {
                let j = match index.entry(s) {
                    MapEntry::Occupied(e) => *e.get(),
                    MapEntry::Vacant(e) => {
                        if states.len() >= max {
                            return (Flown::Unknown, None);
                        }
                        let j = states.len() as u32;
                        states.push(e.key().clone());
                        e.insert(j);
                        done.push(false);
                        if record {
                            parent.push((i, v, log));
                        }
                        j
                    }
                };
                out.push(j);
                if !done[j as usize] {
                    stack.push(j);
                }
            }
            if succ.len() <= i as usize {
                succ.resize(i as usize + 1, Vec::new());
            }
            succ[i as usize] = out;
        }
        succ.resize(states.len(), Vec::new());
        // Every state must still reach a target.
        let mut pred: Vec<Vec<u32>> = vec![Vec::new(); states.len()];
        for (s, out) in succ.iter().enumerate() {
            for &t in out {
                pred[t as usize].push(s as u32);
            }
        }
        let mut co = vec![false; states.len()];
        let mut stack: Vec<u32> = (0..states.len() as u32).filter(|&s| is_target(&states[s as usize])).collect();
        for &s in &stack {
            co[s as usize] = true;
        }
        while let Some(s) = stack.pop() {
            for &p in &pred[s as usize] {
                if !co[p as usize] {
                    co[p as usize] = true;
                    stack.push(p);
                }
            }
        }
        match co.iter().position(|&c| !c) {
            None => (Flown::Free, None),
            Some(s) => (Flown::Stuck, if record { run_to(s as u32, &states, &parent) } else { None }),
        }
    }

    /// The successors of `s`: each vehicle's inputs and each link's
    /// delivery. `None`: a stabilization passed [`SETTLE_STEPS`].
    fn successors(&self, s: &State) -> Option<Vec<(State, usize, Vec<TransitionId>)>> {
        let n = self.vehs.len();
        let mut out = Vec::new();
        for v in 0..n {
            let vs = &s.vs[v];
            let runs = match vs.phase {
                NOT_STARTED => self.start(v, vs.clone())?,
                _ if vs.pending => {
                    self.react(v, (VState { pending: false, ..vs.clone() }, Vec::new(), Vec::new()), &[])?
                }
                RUNNING => {
                    let veh = &self.vehs[v];
                    let mut runs = Vec::new();
                    for t in veh.net.transition_ids() {
                        if !veh.input[t.index()]
                            || !self.enabled(v, &vs.marking, t)
                            || veh.quiet[t.index()].iter().any(|p| vs.marking[p.index()] > 0)
                        {
                            continue;
                        }
                        let mut m = vs.marking.clone();
                        fire(&veh.net, &mut m, t);
                        for (m2, fired) in self.stabilize(v, m, vec![t])? {
                            let st = self.ended(v, VState { marking: m2, ..vs.clone() });
                            runs.extend(self.react(v, (st, Vec::new(), Vec::new()), &fired)?);
                        }
                    }
                    runs
                }
                _ => Vec::new(),
            };
            for (st, sent, log) in runs {
                let mut x = s.clone();
                x.vs[v] = st;
                for m in sent {
                    x.links[v * n + self.msgs[m as usize].to].push(m);
                }
                out.push((x, v, log));
            }
        }
        // Deliveries: the oldest message of each link arrives.
        for from in 0..n {
            for to in 0..n {
                let Some(&m) = s.links[from * n + to].first() else { continue };
                let mut vs = s.vs[to].clone();
                vs.inbox.push(m);
                // It reacts at once (a real link), or takes more messages
                // first (a virtual-time run, `VState::pending`).
                let runs = if vs.phase == NOT_STARTED || vs.pending {
                    vec![(vs, Vec::new(), Vec::new())]
                } else {
                    let mut runs = self.react(to, (vs.clone(), Vec::new(), Vec::new()), &[])?;
                    runs.push((VState { pending: true, ..vs }, Vec::new(), Vec::new()));
                    runs
                };
                for (st, sent, log) in runs {
                    let mut x = s.clone();
                    x.links[from * n + to].remove(0);
                    x.vs[to] = st;
                    for m in sent {
                        x.links[to * n + self.msgs[m as usize].to].push(m);
                    }
                    out.push((x, to, log));
                }
            }
        }
        Some(out)
    }

    fn enabled(&self, v: usize, m: &[u32], t: TransitionId) -> bool {
        is_enabled_with(&self.vehs[v].net, t, |p| m[p.index()])
    }

    /// `Live::start`: the messages that arrived before the start fire on
    /// the initial marking (receive transitions on supervisor copies only,
    /// none that sends), then the player starts.
    fn start(&self, v: usize, mut vs: VState) -> Option<Vec<Run>> {
        let veh = &self.vehs[v];
        let mut kept = Vec::new();
        for m in std::mem::take(&mut vs.inbox) {
            let ev = &self.msgs[m as usize].event;
            let t = veh.net.event_transitions(ev).iter().copied().find(|&t| {
                veh.sends[t.index()].is_empty() && veh.coord_only[t.index()] && self.enabled(v, &vs.marking, t)
            });
            match t {
                Some(t) => fire(&veh.net, &mut vs.marking, t),
                None => kept.push(m),
            }
        }
        vs.inbox = kept;
        vs.phase = RUNNING;
        let mut runs = Vec::new();
        for (m2, fired) in self.stabilize(v, vs.marking.clone(), Vec::new())? {
            let st = self.ended(v, VState { marking: m2, ..vs.clone() });
            runs.extend(self.react(v, (st, Vec::new(), Vec::new()), &fired)?);
        }
        Some(runs)
    }

    /// Every stable marking that the engine's stabilization reaches from
    /// `m` (immediate transitions, then zero-delay ones, the ready ones by
    /// priority, each choice), with the transitions fired (`fired` first).
    /// Orders that fire the same messages and mutex transitions to the same
    /// marking are one.
    fn stabilize(&self, v: usize, m: Vec<u32>, fired: Vec<TransitionId>) -> Option<Vec<(Vec<u32>, Vec<TransitionId>)>> {
        let veh = &self.vehs[v];
        let matters = |t: &TransitionId| {
            !veh.sends[t.index()].is_empty()
                || veh.tokens.iter().any(|k| k.grant == *t || veh.net.transitions()[t.index()].id == k.request)
        };
        // The marking, the order of the firings that send or count, and
        // which transitions fired ([`follows`] matches a step by them).
        let key = |m: &Vec<u32>, f: &[TransitionId]| {
            let mut all = f.to_vec();
            all.sort_unstable();
            (m.clone(), f.iter().copied().filter(matters).collect::<Vec<_>>(), all)
        };
        type Key = (Vec<u32>, Vec<TransitionId>, Vec<TransitionId>);
        let mut seen: FxHashSet<Key> = FxHashSet::default();
        let mut out = Vec::new();
        seen.insert(key(&m, &fired));
        let mut stack = vec![(m, fired)];
        let mut steps = 0usize;
        let mut ready = Vec::new();
        while let Some((m, fired)) = stack.pop() {
            ready.clear();
            ready.extend(veh.net.transition_ids().filter(|&t| self.enabled(v, &m, t)));
            select_ready(&veh.net, &mut ready);
            let settles = |t: &TransitionId| {
                let k = &veh.net.transitions()[t.index()].kind;
                k.is_immediate() || k.is_deferred()
            };
            if !ready.iter().any(settles) {
                out.push((m, fired));
                continue;
            }
            for &t in ready.iter().filter(|t| settles(t)) {
                steps += 1;
                if steps > SETTLE_STEPS {
                    return None;
                }
                let mut m2 = m.clone();
                fire(&veh.net, &mut m2, t);
                let mut f2 = fired.clone();
                f2.push(t);
                if seen.insert(key(&m2, &f2)) {
                    stack.push((m2, f2));
                }
            }
        }
        Some(out)
    }

    /// The player's end (`Layer::check_end`) in a stable marking: a final
    /// place marked, or nothing non-immediate enabled.
    fn ended(&self, v: usize, mut vs: VState) -> VState {
        let veh = &self.vehs[v];
        if vs.phase != RUNNING {
            return vs;
        }
        if veh.finals.iter().any(|p| vs.marking[p.index()] > 0) {
            vs.phase = ENDED;
        } else if !veh.net.transition_ids().any(|t| self.enabled(v, &vs.marking, t)) {
            vs.phase = STOPPED;
        }
        vs
    }

    /// The runtime's reaction to the firings `fired` of an input
    /// (`run_real_time_with_peers`' loop): `Live::after`, then the inbox
    /// delivered (`Live::deliver`) and its reaction, while it takes some.
    fn react(&self, v: usize, run: Run, fired: &[TransitionId]) -> Option<Vec<Run>> {
        let mut out = Vec::new();
        let mut work = vec![(run, fired.to_vec())];
        let mut guard = 0usize;
        while let Some((run, fired)) = work.pop() {
            guard += 1;
            if guard > SETTLE_STEPS {
                return None;
            }
            for run in self.after(v, run, &fired)? {
                let delivered = self.deliver(v, &run.0)?;
                for (st, f) in delivered.iter().cloned() {
                    work.push(((st, run.1.clone(), run.2.clone()), f));
                }
                if delivered.is_empty() {
                    out.push(run);
                }
            }
        }
        Some(out)
    }

    /// `Live::after`: the messages of `fired` (and the mutex requests and
    /// grants counted), then the requests and returns of borrowed tokens
    /// raised as events, each with its own consequences.
    fn after(&self, v: usize, (mut vs, mut sent, mut log): Run, fired: &[TransitionId]) -> Option<Vec<Run>> {
        self.messages_for(v, &mut vs, &mut sent, fired);
        log.extend_from_slice(fired);
        let events = self.arbitrate(v, &mut vs, &mut sent);
        let mut runs = vec![(vs, sent, log)];
        for e in events {
            let mut next = Vec::new();
            for (vs, sent, log) in runs {
                for (st, f) in self.event(v, &vs, &e)? {
                    let mut run = (st, sent.clone(), log.clone());
                    self.messages_for(v, &mut run.0, &mut run.1, &f);
                    run.2.extend(f);
                    next.push(run);
                }
            }
            runs = next;
        }
        Some(runs)
    }

    fn messages_for(&self, v: usize, vs: &mut VState, sent: &mut Vec<u32>, fired: &[TransitionId]) {
        let veh = &self.vehs[v];
        for &t in fired {
            let id = &veh.net.transitions()[t.index()].id;
            for (k, asked) in veh.tokens.iter().zip(vs.asked.iter_mut()) {
                if k.grant == t {
                    *asked = asked.saturating_sub(1);
                } else if k.request == id.as_str() {
                    *asked += 1;
                }
            }
            sent.extend_from_slice(&veh.sends[t.index()]);
        }
    }

    /// `Live::arbitrate`: the request and return events to raise; once the
    /// mission has ended, each unused borrowed token goes back by a message.
    fn arbitrate(&self, v: usize, vs: &mut VState, sent: &mut Vec<u32>) -> Vec<String> {
        let veh = &self.vehs[v];
        let mut events = Vec::new();
        if veh.tokens.is_empty() || vs.phase == NOT_STARTED {
            return events;
        }
        if vs.phase != RUNNING {
            for (k, ret) in veh.tokens.iter().zip(&veh.ret) {
                let n = std::mem::take(&mut vs.marking[k.place.index()]);
                for _ in 0..n {
                    sent.extend(*ret);
                }
            }
            return events;
        }
        let places: Vec<PlaceId> = veh.tokens.iter().map(|k| k.place).collect();
        for (i, k) in veh.tokens.iter().enumerate() {
            let mut need = 0u32;
            for &(t, w) in &k.starts {
                let ready = is_enabled_with(&veh.net, t, |p| match places.iter().position(|&q| q == p) {
                    Some(j) if j >= i => u32::MAX,
                    _ => vs.marking[p.index()],
                });
                if ready {
                    need += w;
                }
            }
            let have = vs.marking[k.place.index()];
            let asked = vs.asked[i];
            if have + asked < need {
                events.extend(std::iter::repeat_n(k.request.clone(), (need - have - asked) as usize));
            } else if have > need {
                events.extend(std::iter::repeat_n(k.ret.clone(), (have - need) as usize));
            }
        }
        events
    }

    /// One event raised by the runtime (`Input::Event`): one enabled
    /// transition bound to it fires, then the net stabilizes; nothing when
    /// none is enabled or the mission has ended.
    fn event(&self, v: usize, vs: &VState, e: &str) -> Option<Vec<(VState, Vec<TransitionId>)>> {
        let veh = &self.vehs[v];
        if vs.phase != RUNNING {
            return Some(vec![(vs.clone(), Vec::new())]);
        }
        let ts: Vec<TransitionId> =
            veh.net.event_transitions(e).iter().copied().filter(|&t| self.enabled(v, &vs.marking, t)).collect();
        if ts.is_empty() {
            return Some(vec![(vs.clone(), Vec::new())]);
        }
        let mut out = Vec::new();
        for t in ts {
            let mut m = vs.marking.clone();
            fire(&veh.net, &mut m, t);
            for (m2, f) in self.stabilize(v, m, vec![t])? {
                out.push((self.ended(v, VState { marking: m2, ..vs.clone() }), f));
            }
        }
        Some(out)
    }

    /// `Live::deliver`: the inbox taken as one batch (each message fires
    /// one enabled transition bound to its event, in passes), when one of
    /// them can fire, then the net stabilizes; once the mission has ended,
    /// the messages whose receive transitions touch supervisor copies only
    /// (`Live::serve_ended`). Empty when nothing fires.
    fn deliver(&self, v: usize, vs: &VState) -> Option<Vec<(VState, Vec<TransitionId>)>> {
        let veh = &self.vehs[v];
        if vs.inbox.is_empty() || vs.phase == NOT_STARTED {
            return Some(Vec::new());
        }
        let bound = |m: &[u32], ev: &str, ended: bool| -> Vec<TransitionId> {
            veh.net
                .event_transitions(ev)
                .iter()
                .copied()
                .filter(|&t| self.enabled(v, m, t) && (!ended || veh.coord_only[t.index()]))
                .collect()
        };
        if vs.phase != RUNNING {
            // `serve_ended`: the first such transition, in passes.
            let mut st = vs.clone();
            let mut fired = Vec::new();
            loop {
                let before = fired.len();
                let mut kept = Vec::new();
                for m in std::mem::take(&mut st.inbox) {
                    match bound(&st.marking, &self.msgs[m as usize].event, true).first() {
                        Some(&t) => {
                            fire(&veh.net, &mut st.marking, t);
                            fired.push(t);
                        }
                        None => kept.push(m),
                    }
                }
                st.inbox = kept;
                if fired.len() == before || st.inbox.is_empty() {
                    break;
                }
            }
            return Some(if fired.is_empty() { Vec::new() } else { vec![(st, fired)] });
        }
        if !vs.inbox.iter().any(|&m| !bound(&vs.marking, &self.msgs[m as usize].event, false).is_empty()) {
            return Some(Vec::new());
        }
        // The batch, each choice of transition for each message.
        let mut partial: Vec<(VState, Vec<TransitionId>)> = vec![(vs.clone(), Vec::new())];
        let mut done = Vec::new();
        while let Some((st, fired)) = partial.pop() {
            // One pass over the messages still waiting, branching per choice.
            let mut pass: Vec<(VState, Vec<TransitionId>, Vec<u32>)> =
                vec![(VState { inbox: Vec::new(), ..st.clone() }, fired.clone(), Vec::new())];
            for &m in &st.inbox {
                let mut next = Vec::new();
                for (s2, f2, kept) in pass {
                    let ts = bound(&s2.marking, &self.msgs[m as usize].event, false);
                    if ts.is_empty() {
                        let mut kept = kept;
                        kept.push(m);
                        next.push((s2, f2, kept));
                        continue;
                    }
                    for t in ts {
                        let mut s3 = s2.clone();
                        fire(&veh.net, &mut s3.marking, t);
                        let mut f3 = f2.clone();
                        f3.push(t);
                        next.push((s3, f3, kept.clone()));
                    }
                }
                pass = next;
            }
            for (mut s2, f2, kept) in pass {
                let progressed = kept.len() < st.inbox.len();
                s2.inbox = kept;
                if progressed && !s2.inbox.is_empty() {
                    partial.push((s2, f2));
                } else {
                    done.push((s2, f2));
                }
            }
        }
        let mut out = Vec::new();
        for (st, fired) in done {
            for (m2, f) in self.stabilize(v, st.marking.clone(), fired)? {
                out.push((self.ended(v, VState { marking: m2, ..st.clone() }), f));
            }
        }
        Some(out)
    }
}

/// Fires `t` on `m` (enabled).
fn fire(net: &Net, m: &mut [u32], t: TransitionId) {
    for &(p, d) in net.delta(t) {
        let x = &mut m[p.index()];
        *x = (i64::from(*x) + d).max(0) as u32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::verify::{verify, Outcome, VerifyOptions};
    use mcl_compiler::{Database, Db};

    /// The missions, constraints and vehicle nets of `text` (with
    /// `examples/vehicle.mcl` imported), and the interleaving product's
    /// verdict alone (the exact product never consulted).
    fn setup(name: &str, text: &str) -> (Vec<Mission>, Vec<VehicleNet>, bool) {
        let dir = std::env::temp_dir().join(format!("mcl-coord-flight-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let vehicle = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/vehicle.mcl");
        std::fs::copy(vehicle, dir.join("vehicle.mcl")).unwrap();
        let path = dir.join("m.mcl");
        std::fs::write(&path, format!("import \"vehicle.mcl\";\n{text}")).unwrap();
        let db = Database::new();
        let (missions, constraints) = crate::source::load(&db, db.file(&path)).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        let plant = crate::centralize(&missions).unwrap();
        let sups = crate::supervisor::synthesize(&plant, &constraints).unwrap();
        let net = crate::analysis::supervised_net(&plant, &sups).unwrap();
        let opts = VerifyOptions { max_flight_states: 0, ..VerifyOptions::default() };
        let interleaving_dead = matches!(verify(&missions, &plant, &sups, &net, &opts), Outcome::Problems(..));
        let nets = crate::decentralize(&missions, &sups).unwrap();
        (missions, nets, interleaving_dead)
    }

    fn flown(missions: &[Mission], nets: &[VehicleNet]) -> Flown {
        fly(missions, nets, &[0, 1], &[true, true], false, 200_000)
    }

    /// `mcl-coord/tests/property.rs` READY_START: the interleaving product
    /// lets `b` leave an allowed start unfired while `a` withdraws what
    /// allowed it; a player fires it at once, and the exact product is free.
    #[test]
    fn a_deadlock_of_the_interleaving_product_that_no_player_reaches() {
        let text = "mission : a { parallel { parallel { Void() : l1 } and { Deploy() : l2 } } or { Deploy() : l3 } }\n\
                    mission : b { try { parallel { Surface() : l1 } and { Surface() : l2 } } catch { \
                    parallel { GotoTarget() : l3 } and { Surface() : l4 } } }\n\
                    constraints {\n sync { a:l2, b:l2 }\n sync { a:l2, b:l1 }\n order { b:l1, a:l3 }\n}\n";
        let (missions, nets, interleaving_dead) = setup("free", text);
        assert!(interleaving_dead, "the interleaving product finds no deadlock");
        assert_eq!(flown(&missions, &nets), Flown::Free);
        assert!(stuck_run(&missions, &nets, false, 200_000).is_none());
    }

    /// Figure 6.9a of the seed (`tests/ui/e0406_order_cycle.mcl`): each
    /// call waits for the other's end; both products find the deadlock,
    /// and the exact product's run ends with neither mission ended.
    #[test]
    fn an_order_cycle_is_stuck_in_both_products() {
        let text = "mission : v1 { GotoTarget() : p2 ; Surface() }\nmission : v2 { Deploy() : p5 ; Surface() }\n\
                    constraints {\n order { v1:p2, v2:p5 }\n order { v2:p5, v1:p2 }\n}\n";
        let (missions, nets, interleaving_dead) = setup("cycle", text);
        assert!(interleaving_dead);
        assert_eq!(flown(&missions, &nets), Flown::Stuck);
        let run = stuck_run(&missions, &nets, false, 200_000).expect("a stuck run");
        assert_eq!(run.markings.len(), 2);
        for (vn, m) in nets.iter().zip(&run.markings) {
            let marked = |prefix: &str| vn.net.places().iter().zip(m).any(|(p, &k)| k > 0 && p.id.starts_with(prefix));
            assert!(!marked("mission."), "`{}` ended", vn.mission);
        }
        // The run is a path of the exact product.
        assert!(follows(&missions, &nets, &run_firings(&run), 200_000).is_ok());
    }

    /// The firings of a stuck run, in order, as [`follows`] takes them.
    fn run_firings(run: &StuckRun) -> Vec<(usize, TransitionId)> {
        run.steps.iter().flat_map(|(v, f)| f.iter().map(move |&t| (*v, t))).collect()
    }
}
