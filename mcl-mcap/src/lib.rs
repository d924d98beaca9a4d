//! # mcl-mcap
//!
//! A run's trace as an MCAP file (<https://mcap.dev>), so that Foxglove and
//! the `mcap` tools open it next to the vehicle's own recordings: one
//! channel per kind of record ([`TOPICS`]: actions, events, firings,
//! poses, outcomes, coordination messages...), each message the trace
//! record itself as JSON (`message_encoding` `json`) described by a JSON
//! Schema (`schema_encoding` `jsonschema`), logged at its mission time
//! (`log_time` = `t` in nanoseconds). docs/mcap.md lists the channels.
//!
//! [`McapTrace`] writes records as a run produces them (`mcl run
//! --mcap`) or lines of a trace file (`mcl trace-to-mcap`); the same
//! record gives the same message either way.

mod schema;

use std::collections::BTreeMap;
use std::io::{Seek, Write};

use mcl_runtime::trace::{Record, RecordKind};

pub use schema::schema_of;

/// A channel of the MCAP file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Topic {
    /// The channel's topic, e.g. `/mcl/actions`.
    pub topic: &'static str,
    /// The name of its JSON schema, e.g. `mcl.Action`.
    pub schema: &'static str,
    /// The record kinds (the trace's `kind`) it carries.
    pub kinds: &'static [&'static str],
}

/// Every channel, in the order they are written; a record of a kind none
/// of them names goes to the last one, `/mcl/other`.
pub const TOPICS: [Topic; 9] = [
    Topic { topic: "/mcl/actions", schema: "mcl.Action", kinds: &["action"] },
    Topic { topic: "/mcl/events", schema: "mcl.Event", kinds: &["event", "unexpected_event", "stale_event"] },
    Topic { topic: "/mcl/firings", schema: "mcl.Firing", kinds: &["fire", "timer"] },
    Topic { topic: "/mcl/perceptions", schema: "mcl.Perception", kinds: &["perception"] },
    Topic { topic: "/mcl/poses", schema: "mcl.Pose", kinds: &["pose"] },
    Topic { topic: "/mcl/outcomes", schema: "mcl.Outcome", kinds: &["outcome", "coord_summary"] },
    Topic {
        topic: "/mcl/coordination",
        schema: "mcl.Coordination",
        kinds: &["coord_send", "coord_receive", "coord_reject", "link_send", "link_lost", "link_deliver"],
    },
    Topic { topic: "/mcl/log", schema: "mcl.Log", kinds: &["warning", "link"] },
    Topic { topic: "/mcl/other", schema: "mcl.Record", kinds: &[] },
];

/// The index in [`TOPICS`] of the channel of records of `kind`.
pub fn topic_index(kind: &str) -> usize {
    TOPICS.iter().position(|t| t.kinds.contains(&kind)).unwrap_or(TOPICS.len() - 1)
}

/// The trace's `kind` of a record (`other` for a kind this version does
/// not know).
pub fn kind_name(kind: &RecordKind) -> &'static str {
    match kind {
        RecordKind::Action { .. } => "action",
        RecordKind::Event { .. } => "event",
        RecordKind::Fire { .. } => "fire",
        RecordKind::UnexpectedEvent { .. } => "unexpected_event",
        RecordKind::StaleEvent { .. } => "stale_event",
        RecordKind::Timer { .. } => "timer",
        RecordKind::Perception { .. } => "perception",
        RecordKind::Warning { .. } => "warning",
        RecordKind::Link { .. } => "link",
        RecordKind::Outcome { .. } => "outcome",
        RecordKind::CoordSend { .. } => "coord_send",
        RecordKind::CoordReceive { .. } => "coord_receive",
        RecordKind::CoordReject { .. } => "coord_reject",
        RecordKind::CoordSummary { .. } => "coord_summary",
        RecordKind::Pose { .. } => "pose",
        RecordKind::LinkSend { .. } => "link_send",
        RecordKind::LinkLost { .. } => "link_lost",
        RecordKind::LinkDeliver { .. } => "link_deliver",
        RecordKind::Operator { .. } => "operator",
        RecordKind::Other => "other",
    }
}

/// Why an MCAP file could not be written, or a trace line not read.
#[derive(Debug)]
pub enum Error {
    /// The MCAP writer failed (its I/O included).
    Mcap(mcap::McapError),
    /// Line `line` of a trace is not a JSON object with a number `t` and a
    /// string `kind`.
    BadLine { line: usize, message: String },
}

impl std::fmt::Display for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Error::Mcap(e) => write!(f, "cannot write the MCAP file: {e}"),
            Error::BadLine { line, message } => write!(f, "line {line}: {message}"),
        }
    }
}

impl std::error::Error for Error {}

impl From<mcap::McapError> for Error {
    fn from(e: mcap::McapError) -> Self {
        Error::Mcap(e)
    }
}

/// How many messages each channel got, by topic.
pub type Counts = BTreeMap<&'static str, u64>;

/// Writes trace records as MCAP messages. Call [`McapTrace::finish`] to
/// write the summary (an unfinished file is still readable record by
/// record, but has no index).
pub struct McapTrace<W: Write + Seek> {
    writer: mcap::Writer<W>,
    /// Channel id of each of [`TOPICS`].
    channels: Vec<u16>,
    /// Messages written per channel (the next sequence number).
    counts: Vec<u64>,
}

impl<W: Write + Seek> McapTrace<W> {
    /// A file with every channel of [`TOPICS`] and its schema, no message yet.
    pub fn new(w: W) -> Result<Self, Error> {
        let opts = mcap::WriteOptions::new().compression(None).profile("").library("mcl");
        let mut writer = opts.create(w)?;
        let mut channels = Vec::with_capacity(TOPICS.len());
        for t in &TOPICS {
            let schema = writer.add_schema(t.schema, "jsonschema", schema_of(t).to_string().as_bytes())?;
            channels.push(writer.add_channel(schema, t.topic, "json", &BTreeMap::new())?);
        }
        Ok(McapTrace { writer, channels, counts: vec![0; TOPICS.len()] })
    }

    /// Writes one record as it appears on a trace line.
    pub fn record(&mut self, r: &Record) -> Result<(), Error> {
        // A record always serializes (string keys, finite numbers).
        let data = serde_json::to_vec(r).unwrap_or_default();
        self.message(topic_index(kind_name(&r.kind)), r.t, &data)
    }

    /// Writes one line of a trace file (`line`: 1-based, for errors);
    /// blank lines are skipped. The line is the message, as written.
    pub fn line(&mut self, line: usize, text: &str) -> Result<(), Error> {
        let text = text.trim();
        if text.is_empty() {
            return Ok(());
        }
        let bad = |message: String| Error::BadLine { line, message };
        let v: serde_json::Value = serde_json::from_str(text).map_err(|e| bad(e.to_string()))?;
        let t = v.get("t").and_then(serde_json::Value::as_f64).ok_or_else(|| bad("no number `t`".into()))?;
        let kind = v.get("kind").and_then(serde_json::Value::as_str).ok_or_else(|| bad("no string `kind`".into()))?;
        self.message(topic_index(kind), t, text.as_bytes())
    }

    fn message(&mut self, topic: usize, t: f64, data: &[u8]) -> Result<(), Error> {
        let time = log_time(t);
        let header = mcap::records::MessageHeader {
            channel_id: self.channels[topic],
            sequence: self.counts[topic] as u32,
            log_time: time,
            publish_time: time,
        };
        self.writer.write_to_known_channel(&header, data)?;
        self.counts[topic] += 1;
        Ok(())
    }

    /// Writes the summary and index; the messages written per topic.
    pub fn finish(mut self) -> Result<Counts, Error> {
        self.writer.finish()?;
        Ok(TOPICS.iter().zip(&self.counts).map(|(t, n)| (t.topic, *n)).collect())
    }
}

/// Mission seconds as MCAP nanoseconds (negative or not a number: 0).
pub fn log_time(t: f64) -> u64 {
    if t.is_finite() && t > 0.0 {
        (t * 1e9).round() as u64
    } else {
        0
    }
}

/// Converts the text of a JSONL trace to an MCAP file. A last line without
/// its newline that does not parse (a run killed while writing it) is
/// skipped, as `mcl chronogram` does.
pub fn convert<W: Write + Seek>(text: &str, w: W) -> Result<Counts, Error> {
    let mut out = McapTrace::new(w)?;
    let complete = text.ends_with('\n');
    let lines: Vec<&str> = text.lines().collect();
    for (i, l) in lines.iter().enumerate() {
        match out.line(i + 1, l) {
            Err(Error::BadLine { .. }) if !complete && i + 1 == lines.len() => {}
            r => r?,
        }
    }
    out.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    #[test]
    fn every_kind_has_its_channel_and_unknown_ones_go_to_other() {
        for (kind, topic) in [
            ("action", "/mcl/actions"),
            ("stale_event", "/mcl/events"),
            ("fire", "/mcl/firings"),
            ("pose", "/mcl/poses"),
            ("outcome", "/mcl/outcomes"),
            ("coord_receive", "/mcl/coordination"),
            ("link", "/mcl/log"),
            ("plan", "/mcl/other"),
        ] {
            assert_eq!(TOPICS[topic_index(kind)].topic, topic, "{kind}");
        }
        assert_eq!((log_time(1.5), log_time(-1.0), log_time(f64::NAN)), (1_500_000_000, 0, 0));
    }

    #[test]
    fn a_trace_converts_and_reads_back() {
        let text = concat!(
            r#"{"t":0.0,"kind":"action","seq":1,"action":"enableGoto","primitive":"GotoPrimitive","command":"enable","params":{"y":1,"x":2}}"#,
            "\n",
            r#"{"t":2.5,"kind":"event","event":"eventGotoOk","transition":"T2"}"#,
            "\n",
            r#"{"t":2.5,"kind":"outcome","result":"ok"}"#,
            "\n",
            r#"{"t":3.0,"kind":"plan","steps":[]}"#,
            "\n",
        );
        let mut buf = Cursor::new(Vec::new());
        let counts = convert(text, &mut buf).unwrap();
        assert_eq!(counts["/mcl/actions"], 1);
        assert_eq!(counts["/mcl/events"], 1);
        assert_eq!(counts["/mcl/outcomes"], 1);
        assert_eq!(counts["/mcl/other"], 1);
        assert_eq!(counts["/mcl/poses"], 0);
        let bytes = buf.into_inner();
        let mut seen = Vec::new();
        for m in mcap::MessageStream::new(&bytes).unwrap() {
            let m = m.unwrap();
            assert_eq!(m.channel.message_encoding, "json");
            let schema = m.channel.schema.as_ref().unwrap();
            assert_eq!(schema.encoding, "jsonschema");
            seen.push((m.channel.topic.clone(), m.log_time, String::from_utf8(m.data.to_vec()).unwrap()));
        }
        assert_eq!(seen.len(), 4);
        assert_eq!((seen[1].0.as_str(), seen[1].1), ("/mcl/events", 2_500_000_000));
        // The message is the line as written: parameters keep their order.
        assert!(seen[0].2.contains(r#""params":{"y":1,"x":2}"#), "{}", seen[0].2);
        assert!(matches!(convert("{\"t\":1}\n", Cursor::new(Vec::new())), Err(Error::BadLine { line: 1, .. })));
        // A torn last line (a killed run) is skipped.
        let torn = format!("{text}{{\"t\":4,\"ki");
        assert_eq!(convert(&torn, Cursor::new(Vec::new())).unwrap()["/mcl/other"], 1);
    }

    #[test]
    fn typed_records_and_lines_give_the_same_messages() {
        let line = r#"{"t":1.0,"kind":"pose","x":1.0,"y":2.0,"z":3.0,"yaw":0.5}"#;
        let r: Record = serde_json::from_str(line).unwrap();
        let mut a = McapTrace::new(Cursor::new(Vec::new())).unwrap();
        a.record(&r).unwrap();
        assert_eq!(a.finish().unwrap()["/mcl/poses"], 1);
        assert_eq!(serde_json::to_string(&r).unwrap(), line);
    }
}
