//! How many coordination messages a run sends, and how many bytes each
//! takes (`mcl compile --link-report`, the language server's hover on a
//! constraint; `docs/acoustic.md` §2 says what the bounds mean).
//!
//! The messages are those of the vehicle nets ([`crate::decentralize`]):
//! each entry of a net's `coord.send` is one message per firing of its
//! transition. Every run of a vehicle is a path of its *vehicle graph*
//! (the markings of its mission under the per-vehicle firing rule, every
//! start a supervisor controls free to be held or to fire: step 1 of the
//! verification, `verify/lts.rs`, which over-approximates and never
//! under-approximates what the vehicle does, whatever the others send). The
//! most messages of a kind a run sends is the longest path of that graph
//! counted in those messages: a proven upper bound; *unbounded* when a
//! cycle of the graph (a loop) sends some, with a bound per iteration of
//! the loop (the most sent on a path of the loop's markings between two
//! returns to a loop head).
//!
//! The single-holder mutex protocol's messages (request, grant, unused
//! return) are counted per *readiness episode* of a borrowing start (it
//! becomes enabled in its mission's net): each episode asks for at most the
//! start's weight in tokens, each request is granted once, and a token is
//! returned at most once per grant.
//!
//! Every message takes [`Codebook::frame_bytes`] in the compact encoding
//! ([`mcl_net::wire`]); its JSON size is that of the TCP link's body with
//! `seq` 1 and `t` 0 (a lower bound: larger numbers take more digits).

use std::collections::{BTreeMap, HashMap};

use mcl_compiler::codes;
use mcl_net::wire::{Body, Codebook, DEFAULT_SEQ_BITS};
use mcl_net::TransitionId;
use mcl_syntax::{Diagnostic, Span};
use serde::Serialize;

use crate::analysis::{AnalyzeOptions, Verdict};
use crate::decentral::VehicleNet;
use crate::model::{Constraint, Mission};
use crate::verify::VehicleGraph;
use mcl_compiler::{Db, SourceFile};

/// States of a mission's state space explored at most for the counts.
pub const MAX_STATES: usize = 200_000;

/// The most messages of some kind a run sends.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "bound")]
pub enum Count {
    /// At most `max`.
    Bounded {
        /// The bound.
        max: u64,
    },
    /// As many as the mission loops.
    Unbounded {
        /// Why.
        reason: String,
        /// At most this many per iteration of a loop: between two returns
        /// of the sender's mission to a loop head (summed over the
        /// senders); none when not known.
        per_iteration: Option<u64>,
    },
    /// Not known (the mission's state space is too large, or the message
    /// is not one this report knows how to count).
    Unknown {
        /// Why.
        reason: String,
    },
}

impl Count {
    fn add(&self, other: &Count, times: u64) -> Count {
        match (self, other) {
            (Count::Bounded { max: a }, Count::Bounded { max: b }) => Count::Bounded { max: a + b * times },
            (Count::Unknown { .. }, _) => self.clone(),
            (_, Count::Unknown { .. }) => other.clone(),
            (Count::Unbounded { reason, per_iteration: a }, Count::Unbounded { per_iteration: b, .. }) => {
                let per_iteration = a.zip(*b).map(|(a, b)| a + b * times);
                Count::Unbounded { reason: reason.clone(), per_iteration }
            }
            (Count::Unbounded { reason, per_iteration }, Count::Bounded { .. }) => {
                Count::Unbounded { reason: reason.clone(), per_iteration: *per_iteration }
            }
            (Count::Bounded { .. }, Count::Unbounded { reason, per_iteration }) => {
                Count::Unbounded { reason: reason.clone(), per_iteration: per_iteration.map(|p| p * times) }
            }
        }
    }

    /// `3`, `unbounded, at most 2 per iteration (reason)`, `unknown (reason)`.
    pub fn describe(&self) -> String {
        match self {
            Count::Bounded { max } => max.to_string(),
            Count::Unbounded { reason, per_iteration: Some(n) } => {
                format!("unbounded, at most {n} per iteration ({reason})")
            }
            Count::Unbounded { reason, per_iteration: None } => format!("unbounded ({reason})"),
            Count::Unknown { reason } => format!("unknown ({reason})"),
        }
    }

    /// A count of bytes for the text report: `140`, `4 per iteration`, `-`.
    fn bytes(&self) -> String {
        match self {
            Count::Bounded { max } => max.to_string(),
            Count::Unbounded { per_iteration: Some(p), .. } => format!("{p} per iteration"),
            _ => "-".into(),
        }
    }

    /// The bound, if there is one.
    pub fn max(&self) -> Option<u64> {
        match self {
            Count::Bounded { max } => Some(*max),
            _ => None,
        }
    }
}

/// One kind of message: `from` tells `to` that it fired `transition`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct MessageLink {
    /// The sending mission.
    pub from: String,
    /// The receiving mission.
    pub to: String,
    /// The sender's transition.
    pub transition: String,
    /// `firing`, `request` or `return` (its kind in the compact encoding).
    pub kind: &'static str,
    /// The constraints it serves (numbers from 1, in the order of the
    /// file); empty for a supervisor added by deadlock avoidance.
    pub constraints: Vec<usize>,
    /// The most a run sends.
    pub count: Count,
    /// Bytes in the compact encoding.
    pub compact_bytes: u64,
    /// Bytes as JSON (at least).
    pub json_bytes: u64,
}

/// The messages of one constraint.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct ConstraintLink {
    /// Its number (from 1).
    pub number: usize,
    /// As written.
    pub text: String,
    /// Where (byte range), when it comes from MCL.
    pub span: Option<(u32, u32)>,
    /// The most messages a run sends for it.
    pub messages: Count,
    /// Their bytes in the compact encoding, at most.
    pub compact_bytes: Count,
    /// Their bytes as JSON, at most.
    pub json_bytes: Count,
}

/// The messages one mission sends.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct MissionLink {
    /// The mission.
    pub mission: String,
    /// The most messages a run sends.
    pub messages: Count,
    /// Their bytes in the compact encoding, at most.
    pub compact_bytes: Count,
    /// Their bytes as JSON, at most.
    pub json_bytes: Count,
}

/// The link report of a program.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct LinkReport {
    /// Bits of a frame of the compact encoding.
    pub frame_bits: u32,
    /// Bytes of a frame (every message and acknowledgement).
    pub frame_bytes: u64,
    /// Width of the sequence number.
    pub seq_bits: u32,
    /// Per constraint, in the order of the file.
    pub constraints: Vec<ConstraintLink>,
    /// Per mission, in the order of the file.
    pub missions: Vec<MissionLink>,
    /// Every kind of message.
    pub messages: Vec<MessageLink>,
}

/// The runs of one vehicle: its vehicle graph and its strongly connected
/// components (see the [module documentation](self)).
struct Runs<'a> {
    mission: &'a Mission,
    g: VehicleGraph,
    /// The component of each marking.
    comp: Vec<u32>,
    /// The components, sinks first.
    order: Vec<Vec<u32>>,
}

/// The longest path of a vehicle graph in some weight.
enum Longest {
    Bounded(u64),
    /// A cycle has weight: `t` is a transition on one; at most
    /// `per_iteration` between two returns to a loop head.
    Unbounded {
        t: u32,
        per_iteration: u64,
    },
}

impl<'a> Runs<'a> {
    /// The graph of `mission`, the transitions `held` free to wait.
    fn new(mission: &'a Mission, held: &[String]) -> Result<Runs<'a>, String> {
        let gated: Vec<bool> =
            mission.net.transitions().iter().map(|t| held.iter().any(|h| h.as_str() == t.id.as_str())).collect();
        let g = crate::verify::vehicle_graph(mission, &gated, MAX_STATES)?;
        let n = g.moves.len();
        let mut comp = vec![u32::MAX; n];
        let mut order: Vec<Vec<u32>> = Vec::new();
        mcl_net::graph::tarjan(
            n,
            |s, out| out.extend(g.moves[s as usize].iter().map(|&(_, v)| v)),
            |c| {
                for &s in c {
                    comp[s as usize] = order.len() as u32;
                }
                order.push(c.to_vec());
            },
        );
        Ok(Runs { mission, g, comp, order })
    }

    /// The longest path from the initial marking in `w(from, t, to)`.
    fn longest(&self, w: &dyn Fn(u32, u32, u32) -> u64) -> Longest {
        let mut val: Vec<Option<u64>> = vec![Some(0); self.order.len()];
        let mut on_cycle = None;
        // Components come sinks first: each one's successors are done.
        for (c, states) in self.order.iter().enumerate() {
            let mut best = Some(0u64);
            for &u in states {
                for &(t, v) in &self.g.moves[u as usize] {
                    let wt = w(u, t, v);
                    let cv = self.comp[v as usize] as usize;
                    let through = if cv == c {
                        if wt > 0 {
                            on_cycle.get_or_insert(t);
                            None
                        } else {
                            Some(0)
                        }
                    } else {
                        val[cv].map(|x| x + wt)
                    };
                    best = best.zip(through).map(|(a, b)| a.max(b));
                }
            }
            val[c] = best;
        }
        match (val[self.comp[0] as usize], on_cycle) {
            (Some(max), _) => Longest::Bounded(max),
            (None, t) => Longest::Unbounded { t: t.unwrap_or(0), per_iteration: self.per_iteration(w) },
        }
    }

    /// The most weight on a path inside one loop (a cyclic component)
    /// between two returns to a loop head: a depth-first search of the
    /// component from its first marking splits its moves into back moves
    /// (to a marking on the search's stack: the loop heads) and the others,
    /// which form an acyclic graph; an iteration is a path of those,
    /// possibly ended by one back move.
    fn per_iteration(&self, w: &dyn Fn(u32, u32, u32) -> u64) -> u64 {
        let mut best = 0u64;
        let mut state = vec![0u8; self.g.moves.len()]; // 0 unseen, 1 on the stack, 2 done
        let mut dp = vec![0u64; self.g.moves.len()];
        for (c, states) in self.order.iter().enumerate() {
            let inside = |v: u32| self.comp[v as usize] as usize == c;
            let cyclic = states.len() > 1 || self.g.moves[states[0] as usize].iter().any(|&(_, v)| v == states[0]);
            if !cyclic {
                continue;
            }
            let root = states.iter().copied().min().unwrap_or(0);
            // (marking, next move) frames.
            let mut stack: Vec<(u32, usize)> = vec![(root, 0)];
            state[root as usize] = 1;
            while let Some(&mut (u, ref mut i)) = stack.last_mut() {
                let moves = &self.g.moves[u as usize];
                if let Some(&(_, v)) = moves.get(*i) {
                    *i += 1;
                    if inside(v) && state[v as usize] == 0 {
                        state[v as usize] = 1;
                        stack.push((v, 0));
                    }
                    continue;
                }
                // Every successor inside is done or on the stack (a back move).
                let mut d = 0u64;
                for &(t, v) in moves.iter().filter(|&&(_, v)| inside(v)) {
                    let wt = w(u, t, v);
                    d = d.max(if state[v as usize] == 1 { wt } else { wt + dp[v as usize] });
                }
                dp[u as usize] = d;
                best = best.max(d);
                state[u as usize] = 2;
                stack.pop();
            }
        }
        best
    }

    /// A count from a longest path; `what` names the messages.
    fn count(&self, l: Longest, extra: u64) -> Count {
        match l {
            Longest::Bounded(max) => Count::Bounded { max: max + extra },
            Longest::Unbounded { t, per_iteration } => {
                let id = self.mission.net.transitions().get(t as usize).map_or("?", |t| t.id.as_str());
                let tid = TransitionId(t);
                let call = self
                    .mission
                    .activities
                    .iter()
                    .find(|a| [&a.arrived, &a.withdrawn, &a.started, &a.ended].iter().any(|ts| ts.contains(&tid)));
                let of = call.map_or(String::new(), |a| format!(" (call `{}:{}`)", self.mission.name, a.label));
                Count::Unbounded {
                    reason: format!(
                        "`{id}`{of} of `{}` is in a loop: it can fire again after it fired",
                        self.mission.name
                    ),
                    per_iteration: Some(per_iteration),
                }
            }
        }
    }

    /// Local index of transition `id`.
    fn index(&self, id: &str) -> Option<u32> {
        self.mission.net.transition_by_id(id).map(|t| t.0)
    }

    /// The most readiness episodes of the starts `starts` (index, weight),
    /// weighted: how many tokens the calls ask for in a run, at most.
    fn asked(&self, starts: &[(u32, u64)]) -> Count {
        let waits = |s: u32, t: u32| self.g.waiting[s as usize].contains(&t);
        let first: u64 = starts.iter().filter(|&&(t, _)| waits(0, t)).map(|&(_, w)| w).sum();
        let l = self
            .longest(&|u, _, v| starts.iter().filter(|&&(t, _)| waits(v, t) && !waits(u, t)).map(|&(_, w)| w).sum());
        self.count(l, first)
    }
}

/// The constraint number of a supervisor place id (`coord.mutex2.lent.b`
/// is constraint 2), none for a siphon supervisor.
fn constraint_of(place: &str) -> Option<usize> {
    let rest = place.strip_prefix("coord.")?;
    for kind in ["mutex", "order", "sync"] {
        if let Some(r) = rest.strip_prefix(kind) {
            let digits: String = r.chars().take_while(|c| c.is_ascii_digit()).collect();
            return digits.parse().ok();
        }
    }
    None
}

/// The link report of the vehicle nets `vehicles` of `missions` under
/// `constraints` (see the [module documentation](self)).
pub fn link_report(missions: &[Mission], constraints: &[Constraint], vehicles: &[VehicleNet]) -> LinkReport {
    let book = Codebook::of_nets(vehicles.iter().map(|v| (v.mission.as_str(), &v.net)), DEFAULT_SEQ_BITS)
        .unwrap_or_else(|_| Codebook::of_nets(std::iter::empty(), DEFAULT_SEQ_BITS).expect("an empty codebook"));
    let frame = book.frame_bytes() as u64;
    let props: HashMap<&str, mcl_net::coord_props::CoordProps> = vehicles
        .iter()
        .map(|v| (v.mission.as_str(), mcl_net::coord_props::CoordProps::read(&v.net).unwrap_or_default()))
        .collect();
    // Every vehicle's runs.
    let mut runs: HashMap<&str, Result<Runs<'_>, String>> = HashMap::new();
    for v in vehicles {
        let Some(m) = missions.iter().find(|m| m.name == v.mission) else { continue };
        // Its transitions that a supervisor copy may hold.
        let held: Vec<String> = v
            .net
            .transition_ids()
            .filter(|&t| v.net.pre(t).iter().any(|&(p, _)| v.net.place(p).is_some_and(|p| p.id.starts_with("coord."))))
            .map(|t| v.net.transitions()[t.index()].id.to_string())
            .collect();
        runs.insert(v.mission.as_str(), Runs::new(m, &held));
    }
    let runs_of = |mission: &str| -> Result<&Runs<'_>, Count> {
        match runs.get(mission) {
            Some(Ok(r)) => Ok(r),
            Some(Err(e)) => Err(Count::Unknown { reason: e.clone() }),
            None => Err(Count::Unknown { reason: format!("`{mission}` is not a mission of the file") }),
        }
    };
    // The most firings of `t` in a run of `mission`.
    let firings = |mission: &str, t: &str| -> Count {
        let r = match runs_of(mission) {
            Ok(r) => r,
            Err(c) => return c,
        };
        match r.index(t) {
            Some(i) => r.count(r.longest(&|_, x, _| u64::from(x == i)), 0),
            None => Count::Unknown { reason: format!("`{t}` is not a transition of `{mission}`") },
        }
    };
    // The most tokens of mutex `supervisor` that `borrower`'s calls ask for.
    let asked = |borrower: &str, supervisor: &str| -> Count {
        let Some(b) = props.get(borrower).and_then(|p| p.tokens.iter().find(|b| b.supervisor == supervisor)) else {
            return Count::Unknown { reason: format!("`{borrower}` borrows no `{supervisor}`") };
        };
        let r = match runs_of(borrower) {
            Ok(r) => r,
            Err(c) => return c,
        };
        let mut starts = Vec::new();
        for s in &b.starts {
            match r.index(&s.transition) {
                Some(i) => starts.push((i, u64::from(s.weight))),
                None => {
                    return Count::Unknown { reason: format!("`{}` is not a transition of `{borrower}`", s.transition) }
                }
            }
        }
        r.asked(&starts)
    };
    let mut messages = Vec::new();
    for v in vehicles {
        for (t, to) in &v.send {
            let body = book.body_of(t);
            let count = match &body {
                Body::Request(s) | Body::Return(s) => asked(&v.mission, s),
                _ => match t.strip_prefix("coord.lend.").and_then(|r| r.rsplit_once('.')) {
                    Some((mutex, borrower)) => asked(borrower, &format!("coord.{mutex}")),
                    None => firings(&v.mission, t),
                },
            };
            let mut served: Vec<usize> = Vec::new();
            if let Some(r) = vehicles.iter().find(|r| r.mission == *to) {
                for &tr in r.net.event_transitions(&crate::decentral::message_event(&v.mission, t)) {
                    for &(p, _) in r.net.pre(tr).iter().chain(r.net.post(tr)) {
                        served.extend(r.net.place(p).and_then(|p| constraint_of(&p.id)));
                    }
                }
            }
            served.sort();
            served.dedup();
            let json = mcl_runtime::coord::CoordMessage {
                from: v.mission.clone(),
                to: to.clone(),
                transition: t.clone(),
                seq: 1,
                t: 0.0,
            };
            let json_bytes = serde_json::to_string(&json).map(|s| s.len() as u64).unwrap_or(0);
            let kind = match body {
                Body::Request(_) => "request",
                Body::Return(_) => "return",
                _ => "firing",
            };
            messages.push(MessageLink {
                from: v.mission.clone(),
                to: to.clone(),
                transition: t.clone(),
                kind,
                constraints: served,
                count,
                compact_bytes: frame,
                json_bytes,
            });
        }
    }
    let totals = |of: &mut dyn Iterator<Item = &MessageLink>| {
        let zero = Count::Bounded { max: 0 };
        let (mut n, mut c, mut j) = (zero.clone(), zero.clone(), zero);
        for m in of {
            n = n.add(&m.count, 1);
            c = c.add(&m.count, m.compact_bytes);
            j = j.add(&m.count, m.json_bytes);
        }
        (n, c, j)
    };
    let constraints = constraints
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let (messages, compact_bytes, json_bytes) =
                totals(&mut messages.iter().filter(|m| m.constraints.contains(&(i + 1))));
            ConstraintLink { number: i + 1, text: c.to_string(), span: c.span, messages, compact_bytes, json_bytes }
        })
        .collect();
    // A mission's firing messages along one path of its graph (tighter
    // than the sum of each one's most), plus its token messages.
    let mission_total = |v: &VehicleNet| -> (Count, Count, Count) {
        let is_firing =
            |m: &&MessageLink| m.from == v.mission && m.kind == "firing" && !m.transition.starts_with("coord.lend.");
        let r = match runs_of(&v.mission) {
            Ok(r) => r,
            Err(c) => return (c.clone(), c.clone(), c),
        };
        // Per transition: (messages, their JSON bytes).
        let mut per_t: HashMap<u32, (u64, u64)> = HashMap::new();
        for m in messages.iter().filter(is_firing) {
            let Some(i) = r.index(&m.transition) else {
                let c = Count::Unknown { reason: format!("`{}` is not a transition of `{}`", m.transition, v.mission) };
                return (c.clone(), c.clone(), c);
            };
            let e = per_t.entry(i).or_default();
            e.0 += 1;
            e.1 += m.json_bytes;
        }
        let own = r.count(r.longest(&|_, t, _| per_t.get(&t).map_or(0, |e| e.0)), 0);
        let own_json = r.count(r.longest(&|_, t, _| per_t.get(&t).map_or(0, |e| e.1)), 0);
        let (n, c, j) = totals(&mut messages.iter().filter(|m| m.from == v.mission && !is_firing(m)));
        let own_compact = Count::Bounded { max: 0 }.add(&own, frame);
        (own.add(&n, 1), own_compact.add(&c, 1), own_json.add(&j, 1))
    };
    let missions = vehicles
        .iter()
        .map(|v| {
            let (messages, compact_bytes, json_bytes) = mission_total(v);
            MissionLink { mission: v.mission.clone(), messages, compact_bytes, json_bytes }
        })
        .collect();
    LinkReport {
        frame_bits: book.frame_bits(),
        frame_bytes: frame,
        seq_bits: book.seq_bits(),
        constraints,
        missions,
        messages,
    }
}

/// The link report of `file` for the editor's hover (a salsa query: kept
/// while the file and its imports are unchanged); none while the program
/// has errors or no constraints, or its constraints deadlock.
#[salsa::tracked(returns(ref))]
pub fn link_report_of(db: &dyn Db, file: SourceFile) -> Option<LinkReport> {
    let (missions, constraints) = crate::source::load(db, file).ok()?;
    if constraints.is_empty() {
        return None;
    }
    let opts = AnalyzeOptions { structure: false, ..AnalyzeOptions::default() };
    let report = crate::analyze_with(&missions, &constraints, &opts).ok()?;
    if report.verdict == Verdict::Deadlock {
        return None;
    }
    let vehicles = crate::decentralize(&missions, &report.supervisors).ok()?;
    Some(link_report(&missions, &constraints, &vehicles))
}

impl LinkReport {
    /// Markdown for the hover on constraint `number` (from 1).
    pub fn hover_text(&self, number: usize) -> Option<String> {
        let c = self.constraints.iter().find(|c| c.number == number)?;
        let how_many = match &c.messages {
            Count::Bounded { max } => format!("at most {max}"),
            Count::Unbounded { per_iteration: Some(n), reason } => {
                format!("any number of (at most {n} per iteration of a loop: {reason})")
            }
            other => other.describe(),
        };
        Some(format!(
            "**Link**: a run sends {how_many} coordination messages for it, {} bytes each in the compact encoding ({} bytes in all; {} as JSON). `mcl compile --link-report` details every message and what its bound means.",
            self.frame_bytes,
            c.compact_bytes.bytes(),
            c.json_bytes.bytes(),
        ))
    }

    /// E0410 at every constraint with messages when a frame does not fit
    /// `frame_bytes` bytes.
    pub fn frame_diagnostics(&self, frame_bytes: u64) -> Vec<Diagnostic> {
        if self.frame_bytes <= frame_bytes {
            return Vec::new();
        }
        self.constraints
            .iter()
            .filter(|c| c.messages != Count::Bounded { max: 0 })
            .map(|c| {
                let span = c.span.map_or(Span::new(0, 0), |(s, e)| Span::new(s as usize, e as usize));
                Diagnostic::error(
                    codes::FRAME_TOO_SMALL,
                    format!(
                        "constraint {}'s coordination messages take {} bytes ({} bits) in the compact encoding: they do not fit a {frame_bytes}-byte frame",
                        c.number, self.frame_bytes, self.frame_bits
                    ),
                    span,
                )
                .with_label(span, format!("{} messages of {} bytes", c.messages.describe(), self.frame_bytes))
                .with_note(
                    "a frame holds 2 bits of kind, 2 mission indices, an index among the sender's communicated transitions and a 3-bit sequence number (docs/acoustic.md)",
                )
                .with_help("use a larger frame (--frame-bytes), or coordinate fewer missions or fewer calls in this file")
            })
            .collect()
    }

    /// The report as text.
    pub fn to_text(&self) -> String {
        let mut s = format!(
            "compact encoding: {} bits per frame, {} bytes (sequence numbers modulo {})\n",
            self.frame_bits,
            self.frame_bytes,
            1u32 << self.seq_bits
        );
        s.push_str("\nper constraint (the most messages a run sends; their bytes compact / JSON):\n");
        for c in &self.constraints {
            s.push_str(&format!(
                "  {}. {}: messages {}, bytes {} / {}\n",
                c.number,
                c.text,
                c.messages.describe(),
                c.compact_bytes.bytes(),
                c.json_bytes.bytes(),
            ));
        }
        s.push_str("\nper mission (the most messages it sends; their bytes compact / JSON):\n");
        for m in &self.missions {
            s.push_str(&format!(
                "  {}: messages {}, bytes {} / {}\n",
                m.mission,
                m.messages.describe(),
                m.compact_bytes.bytes(),
                m.json_bytes.bytes(),
            ));
        }
        s.push_str("\nmessages (from -> to: transition, kind, constraints, at most, bytes compact / JSON):\n");
        let mut by: BTreeMap<(&str, &str), Vec<&MessageLink>> = BTreeMap::new();
        for m in &self.messages {
            by.entry((&m.from, &m.to)).or_default().push(m);
        }
        for ((from, to), ms) in by {
            for m in ms {
                let cs: Vec<String> = m.constraints.iter().map(|c| c.to_string()).collect();
                s.push_str(&format!(
                    "  {from} -> {to}: {}, {}, constraint {}, {}, {} / {} bytes\n",
                    m.transition,
                    m.kind,
                    if cs.is_empty() { "none (deadlock avoidance)".into() } else { cs.join(", ") },
                    m.count.describe(),
                    m.compact_bytes,
                    m.json_bytes
                ));
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn supervisor_places_name_their_constraint() {
        assert_eq!(constraint_of("coord.mutex2"), Some(2));
        assert_eq!(constraint_of("coord.mutex12.lent.b"), Some(12));
        assert_eq!(constraint_of("coord.sync3.1-2.withdrawn"), Some(3));
        assert_eq!(constraint_of("coord.order1"), Some(1));
        assert_eq!(constraint_of("coord.siphon1"), None);
        assert_eq!(constraint_of("task.x"), None);
    }

    #[test]
    fn counts_add_up_and_describe_themselves() {
        let b = |max| Count::Bounded { max };
        assert_eq!(b(2).add(&b(3), 2), b(8));
        let u = |n| Count::Unbounded { reason: "loop".into(), per_iteration: Some(n) };
        assert_eq!(b(2).add(&u(1), 1), u(1));
        assert_eq!(u(1).add(&u(2), 3), u(7));
        assert_eq!(u(2).describe(), "unbounded, at most 2 per iteration (loop)");
        assert_eq!(b(4).max(), Some(4));
        assert_eq!(u(1).max(), None);
    }

    /// `p` —a→ `q` —b→ `p` (a loop), `p` —c→ `r` (the end).
    fn looping() -> Mission {
        use mcl_net::{NetBuilder, Place, Transition, TransitionKind};
        let mut bld = NetBuilder::new("m");
        let p = bld.add_place(Place::new("p").with_tokens(1));
        let q = bld.add_place(Place::new("q"));
        let r = bld.add_place(Place::new("r"));
        let ev = |id: &str| Transition::new(id).with_kind(TransitionKind::Event(id.into()));
        let (a, b, c) = (bld.add_transition(ev("a")), bld.add_transition(ev("b")), bld.add_transition(ev("c")));
        bld.add_input(p, a, 1).add_output(a, q, 1).add_input(q, b, 1).add_output(b, p, 1);
        bld.add_input(p, c, 1).add_output(c, r, 1);
        let net = bld.build().unwrap();
        Mission {
            name: "m".into(),
            controllable: vec![true; net.transition_count()],
            net,
            initial_places: vec![p],
            final_places: vec![r],
            activities: Vec::new(),
            off_nominal: Vec::new(),
        }
    }

    #[test]
    fn a_loop_is_unbounded_with_a_bound_per_iteration() {
        let m = looping();
        let runs = Runs::new(&m, &[]).unwrap();
        let (a, c) = (runs.index("a").unwrap(), runs.index("c").unwrap());
        let count = |t: u32| runs.count(runs.longest(&|_, x, _| u64::from(x == t)), 0);
        assert_eq!(count(c), Count::Bounded { max: 1 });
        let Count::Unbounded { reason, per_iteration } = count(a) else { panic!("a loops") };
        assert_eq!(per_iteration, Some(1));
        assert!(reason.contains("`a`"), "{reason}");
        // Both a and b: two per iteration.
        let b = runs.index("b").unwrap();
        let both = runs.count(runs.longest(&|_, x, _| u64::from(x == a || x == b)), 0);
        assert!(matches!(both, Count::Unbounded { per_iteration: Some(2), .. }), "{both:?}");
    }
}
