//! The compact binary encoding of coordination messages, for links that
//! carry a few bytes at a time (acoustic modems; `docs/acoustic.md` gives
//! the bit layout for anyone writing a decoder).
//!
//! Every vehicle of a fleet computes the same vehicle nets, so every
//! vehicle can number the same things: the missions, each mission's
//! communicated transitions, the mutexes whose tokens travel. A
//! [`Codebook`] holds those numberings (read from the nets' coordination
//! properties, [`crate::coord_props`]) and turns a [`Frame`] into a few
//! bits and back. All frames of a program have the same length,
//! [`Codebook::frame_bytes`].
//!
//! Layout (most significant bit first, fields in this order, zero padding
//! up to the next byte):
//!
//! | field | bits | value |
//! |---|---|---|
//! | kind | 2 | 0 firing, 1 token request, 2 token return, 3 acknowledgement |
//! | from | V | index of the sending mission |
//! | to | V | index of the receiving mission |
//! | index | I | firing: index in the sender's firing table (its last entry is "mission ended"); request, return: index of the mutex; acknowledgement: 0 |
//! | seq | S | the sequence number modulo 2^S |
//!
//! with `V = ⌈log2 missions⌉`, `I = ⌈log2 max(firing table, mutexes)⌉`,
//! `S` = [`Codebook::seq_bits`].

use std::fmt;

use crate::coord_props::{CoordProps, CoordPropsError};
use crate::model::Net;

/// Default width of the sequence number: modulo 8, for at most
/// [`Codebook::window`] = 4 unacknowledged frames per link.
pub const DEFAULT_SEQ_BITS: u32 = 3;

/// The transition of the message that says a mission has ended (sent to
/// the vehicles of other processes; not a firing of the net).
pub const ENDED: &str = "coord.ended";

/// What a frame says.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Body {
    /// The sender fired this transition of its vehicle net.
    Firing(String),
    /// The sender asks the holder of this mutex (supervisor id) for a token.
    Request(String),
    /// The sender gives an unused token of this mutex back.
    Return(String),
    /// The sender's mission has ended ([`ENDED`]).
    Ended,
    /// Every frame of the link `to` → `from` up to `seq` has arrived.
    Ack,
}

/// One coordination message (or acknowledgement) with its names.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Frame {
    /// The sending mission.
    pub from: String,
    /// The receiving mission.
    pub to: String,
    /// What it says.
    pub body: Body,
    /// Its sequence number on the link (encoded modulo 2^S).
    pub seq: u64,
}

/// A mutex whose tokens travel between vehicles.
#[derive(Clone, Debug, PartialEq, Eq)]
struct MutexCode {
    supervisor: String,
    request: String,
    ret: String,
}

/// Why a frame cannot be encoded or decoded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum WireError {
    /// A name the codebook does not have (mission, transition, mutex).
    Unknown {
        /// `mission`, `transition` or `mutex`.
        what: &'static str,
        /// The name.
        name: String,
    },
    /// The bytes are not one frame of this codebook: wrong length, an index
    /// out of range, a reserved value, padding that is not zero.
    Malformed(String),
}

impl fmt::Display for WireError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            WireError::Unknown { what, name } => write!(f, "no {what} `{name}` in the codebook"),
            WireError::Malformed(m) => write!(f, "malformed frame: {m}"),
        }
    }
}

impl std::error::Error for WireError {}

/// The numberings of one program's coordination (see the [module
/// documentation](self)).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Codebook {
    missions: Vec<String>,
    /// Per mission (same order): its communicated transitions, sorted.
    firings: Vec<Vec<String>>,
    /// Sorted by supervisor id.
    mutexes: Vec<MutexCode>,
    seq_bits: u32,
}

/// ⌈log2 n⌉ (0 for n ≤ 1).
fn width(n: usize) -> u32 {
    if n <= 1 {
        0
    } else {
        usize::BITS - (n - 1).leading_zeros()
    }
}

impl Codebook {
    /// The codebook of the vehicle nets `nets` (mission name, net; missions
    /// numbered in this order), with sequence numbers of `seq_bits` bits
    /// (1 to 16). Errors on a malformed coordination property.
    pub fn of_nets<'a>(
        nets: impl IntoIterator<Item = (&'a str, &'a Net)>,
        seq_bits: u32,
    ) -> Result<Codebook, CoordPropsError> {
        let mut missions = Vec::new();
        let mut props = Vec::new();
        for (name, net) in nets {
            missions.push(name.to_string());
            props.push(CoordProps::read(net)?);
        }
        let mut mutexes: Vec<MutexCode> = props
            .iter()
            .flat_map(|p| &p.tokens)
            .map(|m| MutexCode { supervisor: m.supervisor.clone(), request: m.request.clone(), ret: m.ret.clone() })
            .collect();
        mutexes.sort_by(|a, b| a.supervisor.cmp(&b.supervisor));
        mutexes.dedup_by(|a, b| a.supervisor == b.supervisor);
        let firings = props
            .iter()
            .map(|p| {
                let mut t: Vec<String> = p
                    .send
                    .iter()
                    .map(|s| s.transition.clone())
                    .filter(|t| !mutexes.iter().any(|m| m.request == *t || m.ret == *t))
                    .collect();
                t.sort();
                t.dedup();
                t
            })
            .collect();
        Ok(Codebook { missions, firings, mutexes, seq_bits: seq_bits.clamp(1, 16) })
    }

    /// The missions, numbered in this order.
    pub fn missions(&self) -> &[String] {
        &self.missions
    }

    /// Width of the sequence number (S).
    pub fn seq_bits(&self) -> u32 {
        self.seq_bits
    }

    /// The most frames a sender may have unacknowledged on one link, so
    /// that a receiver tells a new frame from a repeated one by its number
    /// modulo 2^S: half the modulus.
    pub fn window(&self) -> u64 {
        1 << (self.seq_bits - 1)
    }

    /// Width of the mission fields (V).
    pub fn mission_bits(&self) -> u32 {
        width(self.missions.len())
    }

    /// Width of the index field (I).
    pub fn index_bits(&self) -> u32 {
        let table = self.firings.iter().map(|f| f.len() + 1).max().unwrap_or(1);
        width(table.max(self.mutexes.len()))
    }

    /// Bits of a frame: 2 + 2V + I + S.
    pub fn frame_bits(&self) -> u32 {
        2 + 2 * self.mission_bits() + self.index_bits() + self.seq_bits
    }

    /// Bytes of a frame (every frame of the codebook has this length).
    pub fn frame_bytes(&self) -> usize {
        self.frame_bits().div_ceil(8) as usize
    }

    /// The communicated transitions of `mission`, in the order of their
    /// indices (the entry after the last is [`ENDED`]).
    pub fn firings_of(&self, mission: &str) -> &[String] {
        self.missions.iter().position(|m| m == mission).map_or(&[], |i| &self.firings[i])
    }

    /// The body of the message "`from` fired `transition`": a token request
    /// or return when it is one of a mutex's, [`Body::Ended`] for
    /// [`ENDED`], else a firing.
    pub fn body_of(&self, transition: &str) -> Body {
        if transition == ENDED {
            return Body::Ended;
        }
        for m in &self.mutexes {
            if m.request == transition {
                return Body::Request(m.supervisor.clone());
            }
            if m.ret == transition {
                return Body::Return(m.supervisor.clone());
            }
        }
        Body::Firing(transition.to_string())
    }

    /// The transition of a message body (the inverse of
    /// [`Codebook::body_of`]); none for [`Body::Ack`] or an unknown mutex.
    pub fn transition_of(&self, body: &Body) -> Option<String> {
        let mutex = |s: &str| self.mutexes.iter().find(|m| m.supervisor == s);
        match body {
            Body::Firing(t) => Some(t.clone()),
            Body::Request(s) => mutex(s).map(|m| m.request.clone()),
            Body::Return(s) => mutex(s).map(|m| m.ret.clone()),
            Body::Ended => Some(ENDED.to_string()),
            Body::Ack => None,
        }
    }

    fn mission_index(&self, name: &str) -> Result<usize, WireError> {
        self.missions
            .iter()
            .position(|m| m == name)
            .ok_or_else(|| WireError::Unknown { what: "mission", name: name.to_string() })
    }

    fn mutex_index(&self, s: &str) -> Result<usize, WireError> {
        self.mutexes
            .iter()
            .position(|m| m.supervisor == s)
            .ok_or_else(|| WireError::Unknown { what: "mutex", name: s.to_string() })
    }

    /// The bytes of `f` ([`Codebook::frame_bytes`] of them).
    pub fn encode(&self, f: &Frame) -> Result<Vec<u8>, WireError> {
        let from = self.mission_index(&f.from)?;
        let to = self.mission_index(&f.to)?;
        let (kind, index) = match &f.body {
            Body::Firing(t) => {
                let table = &self.firings[from];
                let i = table
                    .iter()
                    .position(|x| x == t)
                    .ok_or_else(|| WireError::Unknown { what: "transition", name: format!("{}/{t}", f.from) })?;
                (0, i)
            }
            Body::Ended => (0, self.firings[from].len()),
            Body::Request(s) => (1, self.mutex_index(s)?),
            Body::Return(s) => (2, self.mutex_index(s)?),
            Body::Ack => (3, 0),
        };
        let mut w = BitWriter::default();
        w.put(kind, 2);
        w.put(from as u64, self.mission_bits());
        w.put(to as u64, self.mission_bits());
        w.put(index as u64, self.index_bits());
        w.put(f.seq & ((1 << self.seq_bits) - 1), self.seq_bits);
        Ok(w.bytes)
    }

    /// The frame of `bytes`, its `seq` modulo 2^S (the receiver restores
    /// the full number: [`restore_seq`]). Never panics: any bytes that are
    /// not exactly one frame of this codebook are [`WireError::Malformed`].
    pub fn decode(&self, bytes: &[u8]) -> Result<Frame, WireError> {
        let bad = |m: String| Err(WireError::Malformed(m));
        if bytes.len() != self.frame_bytes() {
            return bad(format!("{} bytes, a frame has {}", bytes.len(), self.frame_bytes()));
        }
        let mut r = BitReader { bytes, pos: 0 };
        let kind = r.get(2);
        let from = r.get(self.mission_bits()) as usize;
        let to = r.get(self.mission_bits()) as usize;
        let index = r.get(self.index_bits()) as usize;
        let seq = r.get(self.seq_bits);
        if r.get(self.frame_bytes() as u32 * 8 - self.frame_bits()) != 0 {
            return bad("padding bits are not zero".into());
        }
        if from >= self.missions.len() || to >= self.missions.len() {
            return bad(format!("mission index out of range ({} missions)", self.missions.len()));
        }
        if from == to {
            return bad("a mission sends to itself".into());
        }
        let mutex = |i: usize| match self.mutexes.get(i) {
            Some(m) => Ok(m.supervisor.clone()),
            None => Err(WireError::Malformed(format!("mutex index {i} out of range"))),
        };
        let body = match kind {
            0 => match self.firings[from].get(index) {
                Some(t) => Body::Firing(t.clone()),
                None if index == self.firings[from].len() => Body::Ended,
                None => return bad(format!("firing index {index} out of range for `{}`", self.missions[from])),
            },
            1 => Body::Request(mutex(index)?),
            2 => Body::Return(mutex(index)?),
            _ if index == 0 => Body::Ack,
            _ => return bad(format!("acknowledgement with index {index}")),
        };
        Ok(Frame { from: self.missions[from].clone(), to: self.missions[to].clone(), body, seq })
    }
}

/// The full sequence number of a frame numbered `wire` (modulo 2^`bits`)
/// at a receiver that expects `next`: the number within half the modulus
/// of `next` (below it: a repeat to acknowledge again; from it on: new).
/// Senders keep at most half the modulus unacknowledged, so it is exact.
pub fn restore_seq(wire: u64, next: u64, bits: u32) -> u64 {
    let m = 1u64 << bits;
    let half = m / 2;
    let base = next.saturating_sub(half);
    // The number ≡ wire (mod m) in [base, base + m).
    base + (wire + m - base % m) % m
}

#[derive(Default)]
struct BitWriter {
    bytes: Vec<u8>,
    bits: u32,
}

impl BitWriter {
    fn put(&mut self, value: u64, n: u32) {
        for k in (0..n).rev() {
            if self.bits % 8 == 0 {
                self.bytes.push(0);
            }
            if value >> k & 1 == 1 {
                let last = self.bytes.len() - 1;
                self.bytes[last] |= 0x80 >> (self.bits % 8);
            }
            self.bits += 1;
        }
    }
}

struct BitReader<'a> {
    bytes: &'a [u8],
    pos: u32,
}

impl BitReader<'_> {
    /// The next `n` bits (zeros past the end).
    fn get(&mut self, n: u32) -> u64 {
        let mut v = 0u64;
        for _ in 0..n {
            let byte = self.bytes.get((self.pos / 8) as usize).copied().unwrap_or(0);
            v = v << 1 | u64::from(byte >> (7 - self.pos % 8) & 1);
            self.pos += 1;
        }
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coord_props::{BorrowedMutex, BorrowedStart, CoordSend};
    use crate::model::{NetBuilder, Place, Transition};
    use proptest::prelude::*;

    /// Three missions: `a` sends two firings, `b` borrows `coord.mutex1`
    /// from `a`, `c` sends one firing.
    fn book(seq_bits: u32) -> Codebook {
        let net = |props: CoordProps, ids: &[&str]| {
            let mut b = NetBuilder::new("v");
            b.add_place(Place::new("coord.mutex1"));
            for id in ids {
                b.add_transition(Transition::new(*id));
            }
            props.write(&mut b);
            b.build().unwrap()
        };
        let send = |pairs: &[(&str, &str)]| {
            pairs.iter().map(|(t, to)| CoordSend { transition: t.to_string(), to: to.to_string() }).collect()
        };
        let a = net(
            CoordProps { send: send(&[("call1.release", "c"), ("call2.start", "c")]), ..Default::default() },
            &["call1.release", "call2.start"],
        );
        let b = net(
            CoordProps {
                send: send(&[("coord.request.mutex1", "a"), ("coord.return.mutex1", "a"), ("call1.release", "a")]),
                tokens: vec![BorrowedMutex {
                    ends: vec!["call1.release".into()],
                    grant: "g".into(),
                    holder: "a".into(),
                    kind: Default::default(),
                    place: "coord.mutex1".into(),
                    request: "coord.request.mutex1".into(),
                    ret: "coord.return.mutex1".into(),
                    starts: vec![BorrowedStart { transition: "call1.start".into(), weight: 1 }],
                    supervisor: "coord.mutex1".into(),
                }],
                ..Default::default()
            },
            &["coord.request.mutex1", "coord.return.mutex1", "call1.release", "call1.start", "g"],
        );
        let c = net(CoordProps { send: send(&[("call4.ok", "a")]), ..Default::default() }, &["call4.ok"]);
        Codebook::of_nets([("a", &a), ("b", &b), ("c", &c)], seq_bits).unwrap()
    }

    #[test]
    fn widths_come_from_the_program() {
        let b = book(DEFAULT_SEQ_BITS);
        // V = 2 (3 missions), I = 2 (a's table: 2 firings + ended), S = 3.
        assert_eq!((b.mission_bits(), b.index_bits(), b.seq_bits()), (2, 2, 3));
        assert_eq!((b.frame_bits(), b.frame_bytes(), b.window()), (11, 2, 4));
        assert_eq!(b.firings_of("b"), ["call1.release"]);
        assert_eq!(b.body_of("coord.request.mutex1"), Body::Request("coord.mutex1".into()));
        assert_eq!(b.body_of(ENDED), Body::Ended);
        assert_eq!(b.transition_of(&Body::Return("coord.mutex1".into())).unwrap(), "coord.return.mutex1");
    }

    #[test]
    fn the_documented_layout_bit_by_bit() {
        let b = book(DEFAULT_SEQ_BITS);
        // a → c, firing index 1 (call2.start), seq 5: kind 00, from 00, to 10,
        // index 01, seq 101, padding 00000.
        let f = Frame { from: "a".into(), to: "c".into(), body: Body::Firing("call2.start".into()), seq: 13 };
        assert_eq!(b.encode(&f).unwrap(), [0b0000_1001, 0b1010_0000]);
        // b → a, ack of 2: kind 11, from 01, to 00, index 00, seq 010.
        let ack = Frame { from: "b".into(), to: "a".into(), body: Body::Ack, seq: 2 };
        assert_eq!(b.encode(&ack).unwrap(), [0b1101_0000, 0b0100_0000]);
        assert_eq!(b.decode(&[0b1101_0000, 0b0100_0000]).unwrap(), ack);
    }

    #[test]
    fn unknown_names_are_errors() {
        let b = book(DEFAULT_SEQ_BITS);
        let f = |from: &str, body: Body| Frame { from: from.into(), to: "a".into(), body, seq: 1 };
        assert!(matches!(b.encode(&f("zz", Body::Ack)), Err(WireError::Unknown { what: "mission", .. })));
        assert!(matches!(
            b.encode(&f("b", Body::Firing("nope".into()))),
            Err(WireError::Unknown { what: "transition", .. })
        ));
        assert!(matches!(b.encode(&f("b", Body::Request("x".into()))), Err(WireError::Unknown { what: "mutex", .. })));
    }

    #[test]
    fn hostile_bytes_are_refused() {
        let b = book(DEFAULT_SEQ_BITS);
        for bytes in
            [&[][..], &[0], &[0, 0, 0], &[0b0000_0000, 0b0000_0001], &[0b0011_0000, 0], &[0b1100_0101, 0], &[0, 0]]
        {
            assert!(matches!(b.decode(bytes), Err(WireError::Malformed(_))), "{bytes:?}");
        }
    }

    #[test]
    fn restore_seq_takes_the_number_near_the_expected_one() {
        // Modulo 8: expecting 9, wire 1 is 9, wire 0 is 8 (a repeat), wire 4 is 12.
        assert_eq!(restore_seq(1, 9, 3), 9);
        assert_eq!(restore_seq(0, 9, 3), 8);
        assert_eq!(restore_seq(5, 9, 3), 5);
        assert_eq!(restore_seq(4, 9, 3), 12);
        assert_eq!(restore_seq(3, 1, 3), 3);
        assert_eq!(restore_seq(0, 1, 3), 0);
    }

    fn frame() -> impl Strategy<Value = Frame> {
        let missions = ["a", "b", "c"];
        (0usize..3, 1usize..3, 0usize..6, 0u64..1000).prop_map(move |(from, d, k, seq)| {
            let to = (from + d) % 3;
            let (from, to) = (missions[from].to_string(), missions[to].to_string());
            let body = match (from.as_str(), k) {
                (_, 0) => Body::Ack,
                (_, 1) => Body::Ended,
                ("b", 2) => Body::Request("coord.mutex1".into()),
                ("b", 3) => Body::Return("coord.mutex1".into()),
                ("a", 4) => Body::Firing("call2.start".into()),
                ("a", _) => Body::Firing("call1.release".into()),
                ("b", _) => Body::Firing("call1.release".into()),
                _ => Body::Firing("call4.ok".into()),
            };
            Frame { from, to, body, seq }
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 512, rng_seed: proptest::test_runner::RngSeed::Fixed(16), ..ProptestConfig::default() })]

        #[test]
        fn round_trip(f in frame(), bits in 1u32..=16) {
            let b = book(bits);
            let bytes = b.encode(&f).unwrap();
            prop_assert_eq!(bytes.len(), b.frame_bytes());
            let back = b.decode(&bytes).unwrap();
            let m = 1u64 << bits;
            prop_assert_eq!(&back, &Frame { seq: f.seq % m, ..f.clone() });
            // The receiver expecting any number within the window of f.seq restores it.
            let next = f.seq.saturating_sub(m / 2 - 1).max(1);
            if f.seq + 1 >= next && f.seq < next + m / 2 {
                prop_assert_eq!(restore_seq(back.seq, next, bits), f.seq);
            }
        }

        #[test]
        fn decode_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..8), bits in 1u32..=16) {
            let b = book(bits);
            if let Ok(f) = b.decode(&bytes) {
                // What decodes encodes back to the same bytes.
                prop_assert_eq!(b.encode(&f).unwrap(), bytes);
            }
        }
    }
}
