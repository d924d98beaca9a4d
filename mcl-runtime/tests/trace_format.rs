//! The trace format, byte for byte: records read back and written again are
//! the same lines (field order included), and the chronograms of two
//! recorded runs are the same SVG documents.
//!
//! The files under `tests/traces/` were written by `mcl run --mock
//! --virtual-time` (the dam inspection whose wall inspection fails, a
//! three-vehicle mutex), `mcl chronogram`, and, for `all-kinds.jsonl`, one
//! line of each kind and shape of record from several runs, with the kinds
//! that a mock run in virtual time does not write (`link`, `stale_event`,
//! `coord_reject`, `pose`, a queued action) written by hand.

use std::path::PathBuf;

use mcl_runtime::chronogram::{render, Options};
use mcl_runtime::trace::{parse_trace, read_trace};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/traces").join(name)
}

fn text(name: &str) -> String {
    std::fs::read_to_string(data(name)).unwrap()
}

#[test]
fn every_kind_of_record_is_written_back_as_it_was_read() {
    for name in ["all-kinds.jsonl", "dam-wall-failure.jsonl", "mutex.jsonl"] {
        let original = text(name);
        let records = parse_trace(&original).unwrap();
        assert_eq!(records.len(), original.lines().count(), "{name}");
        for (r, line) in records.iter().zip(original.lines()) {
            assert_eq!(serde_json::to_string(r).unwrap(), line, "{name}");
        }
    }
}

#[test]
fn chronograms_of_recorded_traces_are_unchanged() {
    for (trace, svg) in [("dam-wall-failure.jsonl", "dam-wall-failure.svg"), ("mutex.jsonl", "mutex.svg")] {
        let records = read_trace(&data(trace)).unwrap();
        let got = render(&records, &Options::default());
        assert!(got == text(svg), "{trace}: the chronogram differs from {svg}");
    }
}
