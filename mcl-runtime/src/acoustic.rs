//! A modelled acoustic link for coordinated runs in virtual time (`mcl run
//! --link "acoustic:bitrate=80,loss=0.3,delay=2[,range=3000]"`;
//! `docs/acoustic.md`).
//!
//! Every coordination message travels as one frame of the compact encoding
//! ([`mcl_net::wire`]), acknowledged by a frame of the same length. Each
//! vehicle has one modem that sends one frame at a time: a frame of `b` bits
//! occupies it `b / bitrate` seconds, then reaches its receiver after the
//! propagation delay (`delay`, or with positions the distance at 1500 m/s),
//! unless it is lost (drawn with probability `loss` from a generator seeded
//! by the run's seed, or the vehicles are more than `range` metres apart).
//!
//! Retransmission: a sender keeps at most [`Codebook::window`] frames
//! unacknowledged per link (the others wait, in order) and sends a frame
//! again when no acknowledgement covered it by its timeout, one round trip
//! (two frame times and twice the propagation delay) plus one second after
//! its transmission started, doubled at each retransmission of the same
//! message (at most 32 times). The receiver hands messages to its vehicle
//! in order, once (an early frame waits for the ones before it; a repeat is
//! dropped) and acknowledges every data frame it receives with the number
//! of the last message it has in order (cumulative). So every message
//! arrives, once, in order, as long as some frames get through.

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::sync::Arc;

use mcl_net::wire::{restore_seq, Body, Codebook, Frame};
use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::coord::CoordMessage;
use crate::multi::SharedSink;
use crate::trace::{Record, RecordKind};

/// Speed of sound in sea water, m/s.
pub const SOUND_SPEED: f64 = 1500.0;

/// A seconds margin added to the first retransmission timeout.
pub const TIMEOUT_MARGIN: f64 = 1.0;

/// The largest factor of the backoff.
pub const MAX_BACKOFF: f64 = 32.0;

/// The link parameters of `--link acoustic:...`.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkSpec {
    /// Bits per second (> 0).
    pub bitrate: f64,
    /// Probability that a frame is lost, in [0, 1).
    pub loss: f64,
    /// Propagation delay, seconds (≥ 0), when the positions are unknown.
    pub delay: f64,
    /// Frames between vehicles farther apart (metres) are lost, when the
    /// positions are known.
    pub range: Option<f64>,
}

impl LinkSpec {
    /// Reads `acoustic:bitrate=80,loss=0.3,delay=2[,range=3000]` (every
    /// key but `range` required, each once).
    pub fn parse(text: &str) -> Result<LinkSpec, String> {
        let Some(params) = text.strip_prefix("acoustic:") else {
            return Err(format!("`{text}`: expected `acoustic:bitrate=BPS,loss=P,delay=S[,range=M]`"));
        };
        let mut values: HashMap<&str, f64> = HashMap::new();
        for kv in params.split(',').filter(|s| !s.trim().is_empty()) {
            let Some((k, v)) = kv.split_once('=') else {
                return Err(format!("`{kv}`: expected KEY=VALUE"));
            };
            let k = k.trim();
            if !["bitrate", "loss", "delay", "range"].contains(&k) {
                return Err(format!("unknown link parameter `{k}` (bitrate, loss, delay, range)"));
            }
            let v: f64 = v.trim().parse().map_err(|_| format!("`{k}`: `{v}` is not a number"))?;
            if !v.is_finite() {
                return Err(format!("`{k}` must be finite"));
            }
            if values.insert(k, v).is_some() {
                return Err(format!("`{k}` given twice"));
            }
        }
        let get = |k: &str| values.get(k).copied().ok_or_else(|| format!("missing `{k}=`"));
        let spec = LinkSpec {
            bitrate: get("bitrate")?,
            loss: get("loss")?,
            delay: get("delay")?,
            range: values.get("range").copied(),
        };
        if spec.bitrate <= 0.0 {
            return Err("`bitrate` must be positive".into());
        }
        if !(0.0..1.0).contains(&spec.loss) {
            return Err("`loss` must be at least 0 and less than 1".into());
        }
        if spec.delay < 0.0 || spec.range.is_some_and(|r| r <= 0.0) {
            return Err("`delay` must be at least 0 and `range` positive".into());
        }
        Ok(spec)
    }
}

/// Where each vehicle is (east, north, depth in metres), by mission name:
/// the hook through which a simulator gives positions.
pub type Positions = Arc<dyn Fn(&str) -> Option<[f64; 3]> + Send + Sync>;

/// A link model for a run: its parameters, the seed of its losses, and the
/// vehicles' positions when they are simulated.
#[derive(Clone)]
pub struct AcousticLink {
    /// Parameters.
    pub spec: LinkSpec,
    /// Seed of the losses.
    pub seed: u64,
    /// Positions, for `range` and the delay from the distance.
    pub positions: Option<Positions>,
}

/// What a link carried during a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// Coordination messages handed to the link.
    pub messages: u64,
    /// Frames transmitted (data and acknowledgements, retransmissions included).
    pub frames: u64,
    /// Of them, retransmissions.
    pub retransmissions: u64,
    /// Frames lost.
    pub lost: u64,
    /// Bytes transmitted (frames × frame length).
    pub bytes: u64,
    /// The JSON bytes of the messages (each once).
    pub json_bytes: u64,
}

enum Event {
    Arrive { from: usize, to: usize, bytes: Vec<u8>, lost: Option<&'static str>, what: String, seq: u64, t: f64 },
    Timeout { from: usize, to: usize, seq: u64 },
}

#[derive(Default)]
struct Sender {
    queue: VecDeque<CoordMessage>,
    /// seq → (message, attempts).
    outstanding: BTreeMap<u64, (CoordMessage, u32)>,
    /// seq → the key of its pending timeout (removed with its acknowledgement).
    timeouts: HashMap<u64, (u64, u64)>,
    /// Every message up to this one is acknowledged.
    acked: u64,
}

struct Receiver {
    next: u64,
    early: BTreeMap<u64, CoordMessage>,
}

/// The link during a run.
pub(crate) struct Channel {
    link: AcousticLink,
    book: Codebook,
    sink: SharedSink,
    rng: ChaCha8Rng,
    modem_free: Vec<f64>,
    events: BTreeMap<(u64, u64), Event>,
    counter: u64,
    senders: HashMap<(usize, usize), Sender>,
    receivers: HashMap<(usize, usize), Receiver>,
    stats: LinkStats,
}

impl Channel {
    pub(crate) fn new(link: AcousticLink, book: Codebook, sink: SharedSink) -> Channel {
        let n = book.missions().len();
        let rng = ChaCha8Rng::seed_from_u64(link.seed ^ 0x6c69_6e6b); // "link"
        Channel {
            link,
            book,
            sink,
            rng,
            modem_free: vec![0.0; n],
            events: BTreeMap::new(),
            counter: 0,
            senders: HashMap::new(),
            receivers: HashMap::new(),
            stats: LinkStats::default(),
        }
    }

    pub(crate) fn stats(&self) -> LinkStats {
        self.stats
    }

    fn index(&self, m: &str) -> Result<usize, String> {
        self.book.missions().iter().position(|x| x == m).ok_or_else(|| format!("the link knows no mission `{m}`"))
    }

    fn record(&self, t: f64, mission: &str, kind: RecordKind) {
        let r = Record { mission: Some(mission.to_string()), ..Record::new(t, kind) };
        if let Ok(mut s) = self.sink.lock() {
            s.record(&r);
        }
    }

    fn push(&mut self, t: f64, e: Event) -> (u64, u64) {
        self.counter += 1;
        let key = (t.max(0.0).to_bits(), self.counter);
        self.events.insert(key, e);
        key
    }

    /// The time of the next event.
    pub(crate) fn next_deadline(&self) -> Option<f64> {
        self.events.keys().next().map(|(t, _)| f64::from_bits(*t))
    }

    /// Propagation delay from `a` to `b`, and whether they are within range.
    fn propagation(&self, a: usize, b: usize) -> (f64, bool) {
        let Some(pos) = &self.link.positions else { return (self.link.spec.delay, true) };
        let names = self.book.missions();
        match (pos(&names[a]), pos(&names[b])) {
            (Some(p), Some(q)) => {
                let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
                (d / SOUND_SPEED, self.link.spec.range.is_none_or(|r| d <= r))
            }
            _ => (self.link.spec.delay, true),
        }
    }

    /// Puts one frame on the air at `now`; returns when its transmission starts.
    fn transmit(
        &mut self,
        now: f64,
        (from, to): (usize, usize),
        frame: &Frame,
        t_msg: f64,
        attempt: u32,
        json: u64,
    ) -> Result<(f64, f64), String> {
        let bytes = self.book.encode(frame).map_err(|e| e.to_string())?;
        let tx = (bytes.len() * 8) as f64 / self.link.spec.bitrate;
        let start = now.max(self.modem_free[from]);
        self.modem_free[from] = start + tx;
        let (prop, in_range) = self.propagation(from, to);
        let lost = if !in_range {
            Some("range")
        } else if ((self.rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64) < self.link.spec.loss {
            Some("loss")
        } else {
            None
        };
        let what = match &frame.body {
            Body::Ack => "ack".to_string(),
            b => self.book.transition_of(b).unwrap_or_default(),
        };
        self.stats.frames += 1;
        self.stats.bytes += bytes.len() as u64;
        if attempt > 1 {
            self.stats.retransmissions += 1;
        }
        let names = self.book.missions();
        let kind = RecordKind::LinkSend {
            to: names[to].clone(),
            seq: frame.seq,
            what: what.clone(),
            bytes: bytes.len() as u64,
            json_bytes: json,
            attempt,
        };
        self.record(now, &names[from].clone(), kind);
        let e = Event::Arrive { from, to, bytes, lost, what, seq: frame.seq, t: t_msg };
        self.push(start + tx + prop, e);
        Ok((start, 2.0 * (tx + prop) + TIMEOUT_MARGIN))
    }

    fn send_data(&mut self, now: f64, from: usize, to: usize, m: &CoordMessage, attempt: u32) -> Result<(), String> {
        let frame =
            Frame { from: m.from.clone(), to: m.to.clone(), body: self.book.body_of(&m.transition), seq: m.seq };
        let json = if attempt == 1 { serde_json::to_string(m).map(|s| s.len() as u64).unwrap_or(0) } else { 0 };
        self.stats.json_bytes += json;
        let (start, rto) = self.transmit(now, (from, to), &frame, m.t, attempt, json)?;
        let backoff = 2f64.powi(attempt.saturating_sub(1).min(5) as i32).min(MAX_BACKOFF);
        let key = self.push(start + rto * backoff, Event::Timeout { from, to, seq: m.seq });
        if let Some(s) = self.senders.get_mut(&(from, to)) {
            s.timeouts.insert(m.seq, key);
        }
        Ok(())
    }

    /// Takes a message that left its sender at `now`.
    pub(crate) fn offer(&mut self, now: f64, m: CoordMessage) -> Result<(), String> {
        let (from, to) = (self.index(&m.from)?, self.index(&m.to)?);
        self.stats.messages += 1;
        let window = self.book.window() as usize;
        let s = self.senders.entry((from, to)).or_default();
        if s.outstanding.len() >= window {
            s.queue.push_back(m);
            return Ok(());
        }
        s.outstanding.insert(m.seq, (m.clone(), 1));
        self.send_data(now, from, to, &m, 1)
    }

    /// Handles the events due at `t` (the earliest); returns the messages
    /// handed to their receivers, in order.
    pub(crate) fn step(&mut self, t: f64) -> Result<Vec<CoordMessage>, String> {
        let mut out = Vec::new();
        while let Some(entry) = self.events.first_entry() {
            if f64::from_bits(entry.key().0) > t {
                break;
            }
            let e = entry.remove();
            match e {
                Event::Timeout { from, to, seq } => {
                    let Some(s) = self.senders.get_mut(&(from, to)) else { continue };
                    let Some((m, attempts)) = s.outstanding.get_mut(&seq) else { continue };
                    *attempts += 1;
                    let (m, a) = (m.clone(), *attempts);
                    self.send_data(t, from, to, &m, a)?;
                }
                Event::Arrive { from, to, lost: Some(reason), what, seq, .. } => {
                    self.stats.lost += 1;
                    let names = self.book.missions();
                    let kind = RecordKind::LinkLost { to: names[to].clone(), seq, what, reason: reason.to_string() };
                    self.record(t, &names[from].clone(), kind);
                }
                Event::Arrive { from, to, bytes, lost: None, t: sent_t, .. } => {
                    let frame = self.book.decode(&bytes).map_err(|e| format!("the link garbled its own frame: {e}"))?;
                    if frame.body == Body::Ack {
                        self.on_ack(t, to, from, frame.seq)?;
                    } else {
                        out.extend(self.on_data(t, from, to, &frame, sent_t)?);
                    }
                }
            }
        }
        Ok(out)
    }

    /// `sender` receives the acknowledgement from `receiver` of the frames up to `wire` (mod 2^S).
    fn on_ack(&mut self, t: f64, sender: usize, receiver: usize, wire: u64) -> Result<(), String> {
        let bits = self.book.seq_bits();
        let names = self.book.missions().to_vec();
        let Some(s) = self.senders.get_mut(&(sender, receiver)) else { return Ok(()) };
        let base = s.outstanding.keys().next().copied().unwrap_or(s.acked + 1);
        let upto = restore_seq(wire, base, bits);
        s.acked = s.acked.max(upto);
        let acked = s.acked;
        s.outstanding.retain(|&k, _| k > acked);
        // Their timeouts are moot: once every message is acknowledged,
        // nothing is left on the link.
        let done: Vec<u64> = s.timeouts.keys().copied().filter(|&k| k <= acked).collect();
        let keys: Vec<(u64, u64)> = done.iter().filter_map(|k| s.timeouts.remove(k)).collect();
        let mut next = Vec::new();
        while s.outstanding.len() < self.book.window() as usize {
            let Some(m) = s.queue.pop_front() else { break };
            s.outstanding.insert(m.seq, (m.clone(), 1));
            next.push(m);
        }
        for k in keys {
            self.events.remove(&k);
        }
        let kind = RecordKind::LinkDeliver {
            from: names[receiver].clone(),
            seq: upto,
            what: "ack".into(),
            status: "ack".into(),
        };
        self.record(t, &names[sender], kind);
        for m in next {
            self.send_data(t, sender, receiver, &m, 1)?;
        }
        Ok(())
    }

    /// `to` receives a data frame from `from`: messages now in order.
    fn on_data(
        &mut self,
        t: f64,
        from: usize,
        to: usize,
        frame: &Frame,
        sent_t: f64,
    ) -> Result<Vec<CoordMessage>, String> {
        let bits = self.book.seq_bits();
        let transition = self.book.transition_of(&frame.body).ok_or("a data frame without a transition")?;
        let r = self.receivers.entry((from, to)).or_insert(Receiver { next: 1, early: BTreeMap::new() });
        let seq = restore_seq(frame.seq, r.next, bits);
        let m = CoordMessage {
            from: frame.from.clone(),
            to: frame.to.clone(),
            transition: transition.clone(),
            seq,
            t: sent_t,
        };
        let mut out = Vec::new();
        let status = if seq < r.next {
            "repeat"
        } else if seq > r.next {
            r.early.insert(seq, m);
            "early"
        } else {
            out.push(m);
            r.next += 1;
            while let Some(m) = r.early.remove(&r.next) {
                out.push(m);
                r.next += 1;
            }
            "new"
        };
        let acked = r.next - 1;
        let names = self.book.missions().to_vec();
        let kind = RecordKind::LinkDeliver { from: names[from].clone(), seq, what: transition, status: status.into() };
        self.record(t, &names[to], kind);
        let ack = Frame { from: names[to].clone(), to: names[from].clone(), body: Body::Ack, seq: acked };
        self.transmit(t, (to, from), &ack, t, 1, 0)?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A channel between `a` and `b` (`a` tells `b` its `t`), its records collected.
    fn channel(spec: LinkSpec, seed: u64) -> (Channel, Arc<std::sync::Mutex<crate::driver::Collect>>) {
        let net = |send: &str| {
            let mut b = mcl_net::NetBuilder::new("v");
            b.add_transition(mcl_net::Transition::new("t"));
            let props =
                mcl_net::coord_props::CoordProps { send: serde_json::from_str(send).unwrap(), ..Default::default() };
            props.write(&mut b);
            b.build().unwrap()
        };
        let (na, nb) = (net(r#"[{"to":"b","transition":"t"}]"#), net("[]"));
        let book = Codebook::of_nets([("a", &na), ("b", &nb)], mcl_net::wire::DEFAULT_SEQ_BITS).unwrap();
        let sink = Arc::new(std::sync::Mutex::new(crate::driver::Collect::default()));
        let link = AcousticLink { spec, seed, positions: None };
        (Channel::new(link, book, sink.clone()), sink)
    }

    fn message(seq: u64) -> CoordMessage {
        CoordMessage { from: "a".into(), to: "b".into(), transition: "t".into(), seq, t: 0.0 }
    }

    /// Offers `n` messages at 0 and runs the channel until it has nothing
    /// left to do; the messages handed over, with their times, and the
    /// time of its last event.
    fn drain(c: &mut Channel, n: u64) -> (Vec<(f64, u64)>, f64) {
        for seq in 1..=n {
            c.offer(0.0, message(seq)).unwrap();
        }
        let mut out = Vec::new();
        let mut steps = 0;
        let mut last = 0.0;
        while let Some(t) = c.next_deadline() {
            last = t;
            out.extend(c.step(t).unwrap().into_iter().map(|m| (t, m.seq)));
            steps += 1;
            assert!(steps < 100_000, "the channel never settles");
        }
        (out, last)
    }

    #[test]
    fn every_message_arrives_once_in_order_across_sequence_wraps_and_losses() {
        for (loss, seed) in [(0.0, 1), (0.5, 2), (0.5, 3), (0.8, 4)] {
            let spec = LinkSpec { bitrate: 80.0, loss, delay: 2.0, range: None };
            let (mut c, sink) = channel(spec, seed);
            // 30 messages: the 3-bit sequence number wraps three times.
            let (got, _) = drain(&mut c, 30);
            let seqs: Vec<u64> = got.iter().map(|(_, s)| *s).collect();
            assert_eq!(seqs, (1..=30).collect::<Vec<_>>(), "loss {loss}");
            let s = c.stats();
            assert_eq!((s.messages, s.json_bytes > 0), (30, true));
            // Each frame is 1 byte: 2 + 1 + 1 + 1 (index: `t` or ended) + 3 bits.
            assert_eq!(s.bytes, s.frames);
            if loss > 0.0 {
                assert!(s.lost > 0 && s.retransmissions > 0, "{s:?}");
            } else {
                // 30 data frames and 30 acknowledgements, nothing sent twice.
                assert_eq!((s.frames, s.lost, s.retransmissions), (60, 0, 0));
            }
            let records = sink.lock().unwrap().0.clone();
            let lost = records.iter().filter(|r| matches!(r.kind, RecordKind::LinkLost { .. })).count() as u64;
            assert_eq!(lost, s.lost);
        }
    }

    #[test]
    fn frames_take_modem_time_and_the_delay_and_wait_for_the_window() {
        // 8 bits at 80 bit/s: 0.1 s per frame, then 2 s of delay. Four
        // frames leave at once (the window), the fifth after the first ack.
        let spec = LinkSpec { bitrate: 80.0, loss: 0.0, delay: 2.0, range: None };
        let (mut c, _) = channel(spec, 0);
        let (got, last) = drain(&mut c, 5);
        let times: Vec<f64> = got.iter().map(|(t, _)| (t * 10.0).round() / 10.0).collect();
        // The last thing on the link is the acknowledgement of 5 (8.4 s),
        // not the timeouts of acknowledged frames (frame 5's: 9.4 s).
        assert_eq!((last * 10.0).round() / 10.0, 8.4);
        // b's acknowledgement of 1 leaves at 2.1 and arrives at 4.2; frame 5
        // leaves then (a's modem is free) and arrives at 4.2 + 0.1 + 2.
        assert_eq!(times, [2.1, 2.2, 2.3, 2.4, 6.3]);
        assert!(c.senders.values().all(|s| s.timeouts.is_empty() && s.outstanding.is_empty()));
    }

    #[test]
    fn the_link_option_is_read_strictly() {
        let s = LinkSpec::parse("acoustic:bitrate=80,loss=0.3,delay=2").unwrap();
        assert_eq!(s, LinkSpec { bitrate: 80.0, loss: 0.3, delay: 2.0, range: None });
        assert_eq!(LinkSpec::parse("acoustic:bitrate=80,loss=0,delay=2,range=3000").unwrap().range, Some(3000.0));
        for (bad, says) in [
            ("radio:bitrate=1", "expected `acoustic:"),
            ("acoustic:bitrate=80,loss=0.3", "missing `delay=`"),
            ("acoustic:bitrate=0,loss=0.3,delay=1", "positive"),
            ("acoustic:bitrate=80,loss=1,delay=1", "less than 1"),
            ("acoustic:bitrate=80,loss=0.1,delay=1,speed=3", "unknown link parameter `speed`"),
            ("acoustic:bitrate=80,loss=0.1,delay=x", "not a number"),
            ("acoustic:bitrate=80,bitrate=8,loss=0.1,delay=1", "twice"),
            ("acoustic:bitrate=NaN,loss=0.1,delay=1", "finite"),
        ] {
            let e = LinkSpec::parse(bad).unwrap_err();
            assert!(e.contains(says), "{bad}: {e}");
        }
    }
}
