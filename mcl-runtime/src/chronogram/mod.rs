//! Chronograms: an SVG timeline of a trace, in the style of the seed's
//! figures 8.5, 8.6 and 8.10.
//!
//! One row per primitive (per mission, when the trace holds several), in
//! the order the primitives were first used. A bar spans each interval in
//! which the primitive was enabled (from the action that activated it to its
//! `disable`); a bar still open at the end is drawn to the end with a dashed
//! edge. Every action is a mark (a blue tick) and every event a mark (green:
//! an ok event, red: a fail event, grey: any other) on the row of its
//! primitive, a time-out (a timed transition that fired) is an orange mark,
//! an event of a disabled run (`stale_event`) a hollow grey one; each mark
//! carries its name (the action's, the event's) above the bar, in as many
//! lines as needed so that no two names overlap. Unexpected events have a
//! row of their own, and a vertical line gives the mission's outcome.
//! Hovering a mark shows its details with the source line of its call
//! (`<title>`). Hand-written SVG, no dependencies.
//!
//! Three steps, one file each: `collect.rs` turns records into rows of bars
//! and marks, `layout.rs` gives them coordinates, `draw.rs` writes the SVG.

mod collect;
mod draw;
mod layout;

pub use layout::MAX_LANES;

use crate::trace::Record;

/// Layout options.
#[derive(Clone, Debug)]
pub struct Options {
    /// Width of the time axis, in pixels.
    pub plot_width: f64,
    /// Height of a row.
    pub row_height: f64,
    /// Title (default: the mission name and its outcome).
    pub title: Option<String>,
}

impl Default for Options {
    fn default() -> Self {
        Options { plot_width: 1100.0, row_height: 30.0, title: None }
    }
}

/// Times on the page: whole seconds without decimals, others to 0.1 s.
fn fmt_time(t: f64) -> String {
    if (t - t.round()).abs() < 1e-9 {
        format!("{}", t.round() as i64)
    } else {
        format!("{t:.1}")
    }
}

/// Renders the records of a trace as an SVG document.
pub fn render(records: &[Record], opts: &Options) -> String {
    let chart = collect::collect(records);
    let l = layout::layout(&chart, opts);
    draw::draw(&chart, &l, opts)
}

#[cfg(test)]
mod tests {
    use super::layout::{lanes, name_width, tick_step, LANE_H};
    use super::*;

    use crate::trace::{Call, RecordKind};

    fn action(t: f64, seq: u64, prim: &str, task: &str, command: &str) -> Record {
        Record::new(
            t,
            RecordKind::Action {
                seq,
                action: format!("{command}{task}"),
                primitive: prim.into(),
                command: command.into(),
                params: Default::default(),
                call: Call { task: Some(task.into()), src: Some(format!("m.mcl:{}", 10 + seq)), ..Call::default() },
                queued: false,
            },
        )
    }

    fn event(t: f64, ev: &str, task: Option<&str>) -> Record {
        Record::new(
            t,
            RecordKind::Event {
                event: ev.into(),
                transition: format!("{ev}.T"),
                call: Call { task: task.map(str::to_string), src: Some("m.mcl:3".into()), ..Call::default() },
                activation: None,
                ends: None,
            },
        )
    }

    #[test]
    fn bars_marks_and_outcome() {
        let a = action(0.0, 1, "GotoPrimitive", "Goto", "enable");
        let e = event(5.0, "eventGotoOk", Some("Goto"));
        let d = action(5.0, 2, "GotoPrimitive", "Goto", "disable");
        let u = Record::new(6.0, RecordKind::UnexpectedEvent { event: "eventX".into(), reason: "no".into() });
        let o = Record::outcome(7.0, "ok", None);
        let svg = render(&[a, e, d, u, o], &Options::default());
        assert!(svg.starts_with("<svg"));
        assert!(svg.contains(">GotoPrimitive</text>"));
        assert!(svg.contains("enabled from 0 s to 5 s (ended ok)"));
        assert!(svg.contains("#1f9d3a"));
        assert!(svg.contains("unexpected events"));
        assert!(svg.contains("mission OK"));
        assert!(svg.trim_end().ends_with("</svg>"));
    }

    /// The names of the marks: (x, y, text) of every `mark-name` element.
    fn names(svg: &str) -> Vec<(f64, f64, String)> {
        svg.lines()
            .filter(|l| l.contains(r#"class="mark-name""#))
            .map(|l| {
                let attr = |k: &str| -> f64 {
                    let i = l.find(&format!(" {k}=\"")).unwrap() + k.len() + 3;
                    l[i..i + l[i..].find('"').unwrap()].parse().unwrap()
                };
                let i = l.find('>').unwrap() + 1;
                let text = l[i..i + l[i..].find('<').unwrap()].to_string();
                (attr("x"), attr("y"), text)
            })
            .collect()
    }

    /// Every action and event is a mark with its name; at one instant the
    /// names go on separate lines; names never overlap; tooltips give the
    /// source line of the call.
    #[test]
    fn actions_and_events_are_named_without_overlap() {
        let mut recs = vec![
            action(0.0, 1, "GotoPrimitive", "Goto", "enable"),
            action(0.0, 2, "DepthPrimitive", "Depth", "enable"),
            event(5.0, "eventGotoOk", Some("Goto")),
            action(5.0, 3, "GotoPrimitive", "Goto", "disable"),
            action(5.0, 4, "GotoPrimitive", "Goto", "enable"),
            event(5.5, "eventGotoFail", Some("Goto")),
            action(5.5, 5, "GotoPrimitive", "Goto", "disable"),
            action(6.0, 6, "DepthPrimitive", "Depth", "disable"),
        ];
        recs.push(Record::new(
            6.0,
            RecordKind::StaleEvent {
                event: "eventDepthOk".into(),
                reason: "its activation, action #2, is over".into(),
                activation: 2,
            },
        ));
        recs.push(Record::outcome(100.0, "ok", None));
        let svg = render(&recs, &Options::default());
        let got = names(&svg);
        let texts: Vec<&str> = got.iter().map(|(_, _, t)| t.as_str()).collect();
        for want in [
            "enableGoto",
            "eventGotoOk",
            "disableGoto",
            "eventGotoFail",
            "enableDepth",
            "disableDepth",
            "eventDepthOk (stale)",
        ] {
            assert!(texts.contains(&want), "{want} in {texts:?}");
        }
        assert_eq!(texts.iter().filter(|t| **t == "enableGoto").count(), 2);
        assert_eq!(got.len(), 9, "{texts:?}");
        // No two names overlap (same line, intersecting extents).
        for (i, a) in got.iter().enumerate() {
            for b in &got[i + 1..] {
                if (a.1 - b.1).abs() < LANE_H - 0.5 {
                    let (a0, a1) = (a.0, a.0 + name_width(&a.2));
                    let (b0, b1) = (b.0, b.0 + name_width(&b.2));
                    assert!(a1 <= b0 || b1 <= a0, "{a:?} overlaps {b:?}");
                }
            }
        }
        // The four names of Goto at t = 5 and 5.5 stand on four lines.
        let goto_ys: std::collections::BTreeSet<i64> =
            got.iter().filter(|(_, _, t)| t.contains("Goto")).map(|(_, y, _)| *y as i64).collect();
        assert!(goto_ys.len() >= 4, "{got:?}");
        // Tooltips name the call's source line.
        assert!(svg.contains("action #1 enableGoto = GotoPrimitive enable() (task Goto) at m.mcl:11"), "{svg}");
        assert!(svg.contains("event eventGotoOk (task Goto) at m.mcl:3"));
        // The stale event is drawn on the row of its activation's primitive, hollow.
        assert!(svg.contains(r##"fill="#fff" stroke="#999999""##));
    }

    #[test]
    fn lanes_are_bounded() {
        // 30 names at one instant: MAX_LANES lines, the others counted.
        let mut recs = Vec::new();
        for k in 0..30 {
            recs.push(event(1.0, &format!("ev{k}"), None));
        }
        let svg = render(&recs, &Options::default());
        assert_eq!(names(&svg).len(), MAX_LANES);
        assert!(svg.contains(&format!("+{} names not shown", 30 - MAX_LANES)));
        let (l, n) = lanes(&[(0.0, 50.0), (10.0, 50.0), (60.0, 10.0), (53.0, 5.0)]);
        assert_eq!((l, n), (vec![Some(0), Some(1), Some(0), Some(2)], 3));
    }

    #[test]
    fn ticks_are_nice() {
        assert_eq!(tick_step(100.0, 10.0), 10.0);
        assert_eq!(tick_step(130.0, 12.0), 20.0);
        assert_eq!(tick_step(7.0, 12.0), 1.0);
    }
}
