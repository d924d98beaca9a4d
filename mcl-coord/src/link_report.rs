//! How many coordination messages a run sends, and how many bytes each
//! takes (`mcl compile --link-report`, the language server's hover on a
//! constraint; `docs/acoustic.md`).
//!
//! The messages are those of the vehicle nets ([`crate::decentralize`]):
//! each entry of a net's `coord.send` is one message per firing of its
//! transition. The most firings of a transition in a run come from the
//! state space of its mission alone (every event and timer free to fire,
//! so an upper bound): the longest path counted in firings of it, or
//! *unbounded* when it lies on a cycle (a loop). The messages of the
//! single-holder mutex protocol (request, grant, unused return) are at
//! most one each per arrival of a borrowing call (its starts and
//! withdrawals). A message belongs to the constraints whose supervisor
//! copies its receive transitions touch.
//!
//! Every message takes [`Codebook::frame_bytes`] in the compact encoding
//! ([`mcl_net::wire`]); its JSON size is that of the TCP link's body with
//! `seq` 1 and `t` 0 (a lower bound: larger numbers take more digits).

use std::collections::{BTreeMap, HashMap};

use mcl_compiler::codes;
use mcl_net::explore::{explore, Options, Semantics, StateId};
use mcl_net::wire::{Body, Codebook, DEFAULT_SEQ_BITS};
use mcl_net::TransitionKind;
use mcl_syntax::{Diagnostic, Span};
use serde::Serialize;

use crate::analysis::{AnalyzeOptions, Verdict};
use crate::decentral::VehicleNet;
use crate::model::{Constraint, Mission};
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
            (Count::Unbounded { .. } | Count::Unknown { .. }, _) => self.clone(),
            (_, o) => o.clone(),
        }
    }

    /// `3`, `unbounded (reason)`, `unknown (reason)`.
    pub fn describe(&self) -> String {
        match self {
            Count::Bounded { max } => max.to_string(),
            Count::Unbounded { reason } => format!("unbounded ({reason})"),
            Count::Unknown { reason } => format!("unknown ({reason})"),
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

/// The most firings of each of `ids` in a run of `mission`'s net, its
/// supervised transitions `held` free to wait (each fires as an event, in
/// a tangible marking, or never).
fn max_firings(mission: &Mission, held: &[String], ids: &[String]) -> HashMap<String, Count> {
    let mut b = mission.net.to_builder();
    for id in held {
        if let Some(t) = mission.net.transition_by_id(id).and_then(|t| b.transition_mut(t)) {
            t.kind = TransitionKind::Event(format!("coord.held/{id}"));
        }
    }
    let net = match b.build() {
        Ok(n) => n,
        Err(e) => {
            let reason = format!("mission `{}`: {e}", mission.name);
            return ids.iter().map(|id| (id.clone(), Count::Unknown { reason: reason.clone() })).collect();
        }
    };
    let labelled = mission;
    let (net, mission) = (&net, mission.name.as_str());
    let opts = Options { semantics: Semantics::Mcl, max_states: MAX_STATES, record_edges: true, ..Options::default() };
    let ss = explore(net, &opts);
    if !ss.complete() {
        let reason = format!("mission `{mission}` has more than {MAX_STATES} states");
        return ids.iter().map(|id| (id.clone(), Count::Unknown { reason: reason.clone() })).collect();
    }
    let n = ss.len();
    let mut comp = vec![u32::MAX; n];
    let mut order: Vec<Vec<u32>> = Vec::new();
    mcl_net::graph::tarjan(
        n,
        |s, out| out.extend(ss.successors(StateId(s)).iter().map(|(_, v)| v.0)),
        |c| {
            for &s in c {
                comp[s as usize] = order.len() as u32;
            }
            order.push(c.to_vec());
        },
    );
    let mut out = HashMap::new();
    for id in ids {
        let Some(t) = net.transition_by_id(id) else {
            out.insert(id.clone(), Count::Unknown { reason: format!("`{id}` is not a transition of `{mission}`") });
            continue;
        };
        // Components come sinks first: each one's successors are done.
        let mut val: Vec<Option<u64>> = vec![Some(0); order.len()];
        for (c, states) in order.iter().enumerate() {
            let mut best = Some(0u64);
            for &u in states {
                for &(tr, v) in ss.successors(StateId(u)) {
                    let w = u64::from(tr == t);
                    let cv = comp[v.0 as usize] as usize;
                    let through = if cv == c {
                        if w > 0 {
                            None
                        } else {
                            Some(0)
                        }
                    } else {
                        val[cv].map(|x| x + w)
                    };
                    best = match (best, through) {
                        (Some(a), Some(b)) => Some(a.max(b)),
                        _ => None,
                    };
                }
            }
            val[c] = best;
        }
        let count = match val[comp[0] as usize] {
            Some(max) => Count::Bounded { max },
            None => {
                // The labelled call it belongs to, when it is one's.
                let call = labelled
                    .activities
                    .iter()
                    .find(|a| [&a.arrived, &a.withdrawn, &a.started, &a.ended].iter().any(|ts| ts.contains(&t)));
                let of = call.map_or(String::new(), |a| format!(" (call `{mission}:{}`)", a.label));
                Count::Unbounded {
                    reason: format!("`{id}`{of} of `{mission}` is in a loop: it can fire again after it fired"),
                }
            }
        };
        out.insert(id.clone(), count);
    }
    out
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
    // The most firings of every own transition counted.
    let mut firings: HashMap<&str, HashMap<String, Count>> = HashMap::new();
    for v in vehicles {
        let Some(m) = missions.iter().find(|m| m.name == v.mission) else { continue };
        let mut ids: Vec<String> = v.send.iter().map(|(t, _)| t.clone()).collect();
        for b in &props[v.mission.as_str()].tokens {
            for s in &b.starts {
                ids.push(s.transition.clone());
                if let Some(call) = s.transition.strip_suffix(".start") {
                    if m.net.transition_by_id(&format!("{call}.cancel")).is_some() {
                        ids.push(format!("{call}.cancel"));
                    }
                }
            }
        }
        ids.sort();
        ids.dedup();
        ids.retain(|id| m.net.transition_by_id(id).is_some());
        // Its starts that a supervisor copy may hold.
        let held: Vec<String> = v
            .net
            .transition_ids()
            .filter(|&t| v.net.pre(t).iter().any(|&(p, _)| v.net.place(p).is_some_and(|p| p.id.starts_with("coord."))))
            .map(|t| v.net.transitions()[t.index()].id.to_string())
            .collect();
        firings.insert(v.mission.as_str(), max_firings(m, &held, &ids));
    }
    // Arrivals of `borrower`'s calls under mutex `supervisor`.
    let arrivals = |borrower: &str, supervisor: &str| -> Count {
        let Some(b) = props.get(borrower).and_then(|p| p.tokens.iter().find(|b| b.supervisor == supervisor)) else {
            return Count::Unknown { reason: format!("`{borrower}` borrows no `{supervisor}`") };
        };
        let counts = &firings[borrower];
        let mut total = Count::Bounded { max: 0 };
        for s in &b.starts {
            let call = s.transition.strip_suffix(".start").unwrap_or(&s.transition);
            for id in [s.transition.clone(), format!("{call}.cancel")] {
                if let Some(c) = counts.get(&id) {
                    total = total.add(c, 1);
                }
            }
        }
        total
    };
    let mut messages = Vec::new();
    for v in vehicles {
        for (t, to) in &v.send {
            let body = book.body_of(t);
            let count = match &body {
                Body::Request(s) | Body::Return(s) => arrivals(&v.mission, s),
                _ => match t.strip_prefix("coord.lend.").and_then(|r| r.rsplit_once('.')) {
                    Some((mutex, borrower)) => arrivals(borrower, &format!("coord.{mutex}")),
                    None => firings.get(v.mission.as_str()).and_then(|f| f.get(t)).cloned().unwrap_or_else(|| {
                        Count::Unknown { reason: format!("`{t}` is not a transition of a mission") }
                    }),
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
    let missions = vehicles
        .iter()
        .map(|v| {
            let (messages, compact_bytes, json_bytes) = totals(&mut messages.iter().filter(|m| m.from == v.mission));
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
        let bytes = |b: &Count| b.max().map_or("-".to_string(), |b| b.to_string());
        Some(format!(
            "**Link**: a run sends {} coordination messages for it, {} bytes each in the compact encoding ({} bytes in all; {} as JSON). `mcl compile --link-report` details every message.",
            match &c.messages {
                Count::Bounded { max } => format!("at most {max}"),
                other => other.describe(),
            },
            self.frame_bytes,
            bytes(&c.compact_bytes),
            bytes(&c.json_bytes),
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
                c.compact_bytes.max().map_or("-".into(), |b| b.to_string()),
                c.json_bytes.max().map_or("-".into(), |b| b.to_string()),
            ));
        }
        s.push_str("\nper mission (the most messages it sends; their bytes compact / JSON):\n");
        for m in &self.missions {
            s.push_str(&format!(
                "  {}: messages {}, bytes {} / {}\n",
                m.mission,
                m.messages.describe(),
                m.compact_bytes.max().map_or("-".into(), |b| b.to_string()),
                m.json_bytes.max().map_or("-".into(), |b| b.to_string()),
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
        let u = Count::Unbounded { reason: "loop".into() };
        assert_eq!(b(2).add(&u, 1), u);
        assert_eq!(u.describe(), "unbounded (loop)");
        assert_eq!(b(4).max(), Some(4));
    }
}
