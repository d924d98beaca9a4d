//! Chronograms: an SVG timeline of a trace, in the style of the seed's
//! figures 8.5, 8.6 and 8.10.
//!
//! One row per primitive (per mission, when the trace holds several), in
//! the order the primitives were first used. A bar spans each interval in
//! which the primitive was enabled (from the action that activated it to its
//! `disable`); a bar still open at the end is drawn to the end with a dashed
//! edge. Events are marks on the row of the primitive whose task they
//! concern (green: an ok event, red: a fail event, grey: any other), a
//! time-out (a timed transition that fired) is an orange mark, unexpected
//! events have a row of their own, and a vertical line gives the mission's
//! outcome. Hovering a mark shows its details (`<title>`). Hand-written SVG,
//! no dependencies.

use std::collections::HashMap;
use std::fmt::Write;

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

/// How an activation ended.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Ending {
    /// Disabled without an outcome of its own (aborted), or still running.
    Aborted,
    Ok,
    Fail,
    Timeout,
}

#[derive(Debug)]
struct Bar {
    start: f64,
    end: Option<f64>,
    ending: Ending,
    /// The parameters of the activating action.
    text: String,
}

#[derive(Debug, Default)]
struct Row {
    label: String,
    bars: Vec<Bar>,
    /// (time, kind, short label, details)
    marks: Vec<(f64, MarkKind, String, String)>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum MarkKind {
    Ok,
    Fail,
    Other,
    Timeout,
    Unexpected,
    Action,
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// A "nice" tick step for a span of `span` seconds and about `n` ticks.
fn tick_step(span: f64, n: f64) -> f64 {
    let raw = (span / n).max(1e-6);
    let mag = 10f64.powf(raw.log10().floor());
    for m in [1.0, 2.0, 5.0, 10.0] {
        if m * mag >= raw {
            return m * mag;
        }
    }
    10.0 * mag
}

fn fmt_time(t: f64) -> String {
    if (t - t.round()).abs() < 1e-9 {
        format!("{}", t.round() as i64)
    } else {
        format!("{t:.1}")
    }
}

/// Renders the records of a trace as an SVG document.
pub fn render(records: &[Record], opts: &Options) -> String {
    // Rows keyed by (mission, primitive), in order of first use.
    let mut rows: Vec<Row> = Vec::new();
    let mut row_of: HashMap<(Option<String>, String), usize> = HashMap::new();
    let mut task_primitive: HashMap<(Option<String>, String), String> = HashMap::new();
    let mut open: HashMap<usize, usize> = HashMap::new(); // row -> index of its open bar
    let mut timers: HashMap<(Option<String>, String), f64> = HashMap::new();
    let mut unexpected: Vec<(f64, String, String)> = Vec::new();
    let mut outcomes: Vec<(f64, Option<String>, String, Option<String>)> = Vec::new();
    let missions: Vec<Option<String>> = {
        let mut v: Vec<Option<String>> = Vec::new();
        for r in records {
            if !v.contains(&r.mission) {
                v.push(r.mission.clone());
            }
        }
        v
    };
    let several = missions.len() > 1;
    let mut end_time: f64 = 0.0;
    let row_for =
        |rows: &mut Vec<Row>, row_of: &mut HashMap<(Option<String>, String), usize>, m: &Option<String>, prim: &str| {
            *row_of.entry((m.clone(), prim.to_string())).or_insert_with(|| {
                let label = match (several, m) {
                    (true, Some(m)) => format!("{m}: {prim}"),
                    _ => prim.to_string(),
                };
                rows.push(Row { label, ..Default::default() });
                rows.len() - 1
            })
        };
    for r in records {
        end_time = end_time.max(r.t);
        match r.kind.as_str() {
            "action" => {
                let prim = r.primitive.clone().unwrap_or_else(|| "?".into());
                if let Some(task) = &r.task {
                    task_primitive.insert((r.mission.clone(), task.clone()), prim.clone());
                }
                let i = row_for(&mut rows, &mut row_of, &r.mission, &prim);
                let cmd = r.command.clone().unwrap_or_default();
                let details = format!(
                    "t={} {} {}({})",
                    fmt_time(r.t),
                    r.action.as_deref().unwrap_or(""),
                    cmd,
                    r.params.iter().flatten().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(", ")
                );
                if cmd == "disable" {
                    if let Some(b) = open.remove(&i) {
                        rows[i].bars[b].end = Some(r.t);
                    }
                } else if let std::collections::hash_map::Entry::Vacant(e) = open.entry(i) {
                    let text = r
                        .params
                        .iter()
                        .flatten()
                        .map(|(k, v)| match v {
                            serde_json::Value::String(s) => format!("{k}: {s}"),
                            v => format!("{k}: {v}"),
                        })
                        .collect::<Vec<_>>()
                        .join(", ");
                    rows[i].bars.push(Bar { start: r.t, end: None, ending: Ending::Aborted, text });
                    e.insert(rows[i].bars.len() - 1);
                } else {
                    rows[i].marks.push((r.t, MarkKind::Action, cmd.clone(), details.clone()));
                }
                let _ = details;
            }
            "event" => {
                let ev = r.event.clone().unwrap_or_default();
                let prim = r
                    .task
                    .as_ref()
                    .and_then(|t| task_primitive.get(&(r.mission.clone(), t.clone())).cloned())
                    .or_else(|| r.task.clone())
                    .unwrap_or_else(|| "events".into());
                let i = row_for(&mut rows, &mut row_of, &r.mission, &prim);
                let (kind, short) = if ev.ends_with("Ok") || ev.ends_with("_ok") {
                    (MarkKind::Ok, "ok".to_string())
                } else if ev.ends_with("Fail") || ev.ends_with("_fail") {
                    (MarkKind::Fail, "fail".to_string())
                } else {
                    (MarkKind::Other, ev.clone())
                };
                let details = format!(
                    "t={} event {ev}{}{}",
                    fmt_time(r.t),
                    r.task.as_ref().map(|t| format!(" (task {t})")).unwrap_or_default(),
                    r.src.as_ref().map(|s| format!(" at {s}")).unwrap_or_default()
                );
                if let Some(&b) = open.get(&i) {
                    if rows[i].bars[b].ending == Ending::Aborted {
                        rows[i].bars[b].ending = match kind {
                            MarkKind::Ok => Ending::Ok,
                            MarkKind::Fail => Ending::Fail,
                            _ => Ending::Aborted,
                        };
                    }
                }
                rows[i].marks.push((r.t, kind, short, details));
            }
            "timer" => {
                if let (Some(tr), Some(d)) = (&r.transition, r.deadline) {
                    timers.insert((r.mission.clone(), tr.clone()), d);
                }
            }
            "fire" => {
                if let Some(tr) = &r.transition {
                    if let Some(d) = timers.remove(&(r.mission.clone(), tr.clone())) {
                        if (d - r.t).abs() < 1e-6 {
                            let prim = r
                                .task
                                .as_ref()
                                .and_then(|t| task_primitive.get(&(r.mission.clone(), t.clone())).cloned())
                                .unwrap_or_else(|| "timers".into());
                            let i = row_for(&mut rows, &mut row_of, &r.mission, &prim);
                            let details = format!(
                                "t={} time-out: {tr} fired{}",
                                fmt_time(r.t),
                                r.task.as_ref().map(|t| format!(" (task {t})")).unwrap_or_default()
                            );
                            if let Some(&b) = open.get(&i) {
                                rows[i].bars[b].ending = Ending::Timeout;
                            }
                            rows[i].marks.push((r.t, MarkKind::Timeout, "time-out".into(), details));
                        }
                    }
                }
            }
            "unexpected_event" => {
                let ev = r.event.clone().unwrap_or_default();
                let details = format!(
                    "t={} unexpected event {ev}: {}",
                    fmt_time(r.t),
                    r.reason.as_deref().unwrap_or("no transition waits for it")
                );
                unexpected.push((r.t, ev, details));
            }
            "outcome" => {
                outcomes.push((r.t, r.mission.clone(), r.result.clone().unwrap_or_default(), r.reason.clone()));
            }
            _ => {}
        }
    }
    if !unexpected.is_empty() {
        let mut row = Row { label: "unexpected events".into(), ..Default::default() };
        for (t, ev, d) in unexpected {
            row.marks.push((t, MarkKind::Unexpected, ev, d));
        }
        rows.push(row);
    }

    // Geometry.
    let label_w = rows.iter().map(|r| r.label.chars().count()).max().unwrap_or(10).clamp(10, 48) as f64 * 7.4 + 24.0;
    let left = label_w;
    let top = 64.0;
    let rh = opts.row_height;
    let pw = opts.plot_width;
    let span = if end_time > 0.0 { end_time } else { 1.0 };
    // Leave room after the end for the outcome label.
    let x = |t: f64| left + t / span * pw;
    let plot_h = rows.len().max(1) as f64 * rh;
    let width = left + pw + 150.0;
    let height = top + plot_h + 80.0;

    let title = opts.title.clone().unwrap_or_else(|| {
        let name = missions.iter().flatten().cloned().collect::<Vec<_>>().join(", ");
        let name = if name.is_empty() { "mission".to_string() } else { name };
        let res: Vec<String> = outcomes
            .iter()
            .map(|(t, m, r, _)| match (several, m) {
                (true, Some(m)) => format!("{m}: {} at {} s", r.to_uppercase(), fmt_time(*t)),
                _ => format!("{} at {} s", r.to_uppercase(), fmt_time(*t)),
            })
            .collect();
        if res.is_empty() {
            format!("{name} (no outcome)")
        } else {
            format!("{name}: {}", res.join(", "))
        }
    });

    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="DejaVu Sans, Helvetica, Arial, sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r##"<rect x="0" y="0" width="{width:.0}" height="{height:.0}" fill="#ffffff"/>"##);
    let _ = writeln!(
        s,
        r##"<text x="{left:.1}" y="26" font-size="16" font-weight="bold" fill="#222">{}</text>"##,
        esc(&title)
    );
    legend(&mut s, left, 46.0);

    // Grid and axis.
    let step = tick_step(span, 12.0);
    let mut t = 0.0;
    while t <= span + 1e-9 {
        let xx = x(t);
        let _ = writeln!(
            s,
            r##"<line x1="{xx:.1}" y1="{top:.1}" x2="{xx:.1}" y2="{:.1}" stroke="#e4e4e4" stroke-width="1"/>"##,
            top + plot_h
        );
        let _ = writeln!(
            s,
            r##"<text x="{xx:.1}" y="{:.1}" text-anchor="middle" fill="#444">{}</text>"##,
            top + plot_h + 16.0,
            fmt_time(t)
        );
        t += step;
    }
    let _ = writeln!(
        s,
        r##"<line x1="{left:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#444" stroke-width="1"/>"##,
        top + plot_h,
        left + pw,
        top + plot_h
    );
    let _ = writeln!(
        s,
        r##"<text x="{:.1}" y="{:.1}" text-anchor="middle" fill="#444">time (s)</text>"##,
        left + pw / 2.0,
        top + plot_h + 34.0
    );

    // Rows.
    for (i, row) in rows.iter().enumerate() {
        let y0 = top + i as f64 * rh;
        let yc = y0 + rh / 2.0;
        if i % 2 == 1 {
            let _ =
                writeln!(s, r##"<rect x="0" y="{y0:.1}" width="{:.1}" height="{rh:.1}" fill="#f6f8fa"/>"##, left + pw);
        }
        let _ = writeln!(
            s,
            r##"<text x="{:.1}" y="{:.1}" text-anchor="end" fill="#222">{}</text>"##,
            left - 10.0,
            yc + 4.0,
            esc(&row.label)
        );
        for bar in &row.bars {
            let (a, b) = (bar.start, bar.end);
            let xa = x(a) + 1.0;
            let xb = x(b.unwrap_or(span)) - 1.0;
            let w = (xb - xa).max(2.0);
            let (fill, stroke) = ending_colors(bar.ending);
            let how = match (bar.ending, b) {
                (_, None) => "still enabled at the end",
                (Ending::Aborted, _) => "disabled without an outcome (aborted)",
                (Ending::Ok, _) => "ended ok",
                (Ending::Fail, _) => "ended in fail",
                (Ending::Timeout, _) => "timed out",
            };
            let _ = writeln!(
                s,
                r##"<rect x="{xa:.1}" y="{:.1}" width="{w:.1}" height="{:.1}" rx="3" fill="{fill}" stroke="{stroke}" stroke-width="1"{}><title>{}</title></rect>"##,
                y0 + 6.0,
                rh - 12.0,
                if b.is_none() { r#" stroke-dasharray="4 3""# } else { "" },
                esc(&format!(
                    "{}: enabled from {} s to {} ({how}){}",
                    row.label,
                    fmt_time(a),
                    b.map(|b| format!("{} s", fmt_time(b))).unwrap_or_else(|| "the end".into()),
                    if bar.text.is_empty() { String::new() } else { format!("\n{}", bar.text) }
                ))
            );
            // The parameters inside the bar, cut to fit.
            let room = ((w - 10.0) / 5.8).floor() as usize;
            if room >= 4 && !bar.text.is_empty() {
                let n = bar.text.chars().count();
                let text = if n <= room {
                    bar.text.clone()
                } else {
                    format!("{}…", bar.text.chars().take(room - 1).collect::<String>())
                };
                let _ = writeln!(
                    s,
                    r##"<text x="{:.1}" y="{:.1}" font-size="10" fill="#1d2b3a" pointer-events="none">{}</text>"##,
                    xa + 5.0,
                    yc + 3.5,
                    esc(&text)
                );
            }
        }
        // Marks, with labels that do not overlap the previous one.
        let mut last_label_end = f64::NEG_INFINITY;
        for (t, kind, short, details) in &row.marks {
            let xm = x(*t);
            let (color, shape) = match kind {
                MarkKind::Ok => ("#1f9d3a", "circle"),
                MarkKind::Fail => ("#d02a2a", "circle"),
                MarkKind::Other => ("#777777", "circle"),
                MarkKind::Timeout => ("#e08a00", "diamond"),
                MarkKind::Unexpected => ("#e08a00", "triangle"),
                MarkKind::Action => ("#3a6ea5", "tick"),
            };
            let tip = format!("<title>{}</title>", esc(details));
            match shape {
                "circle" => {
                    let _ = writeln!(
                        s,
                        r##"<circle cx="{xm:.1}" cy="{yc:.1}" r="5" fill="{color}" stroke="#fff" stroke-width="1.5">{tip}</circle>"##
                    );
                }
                "diamond" => {
                    let _ = writeln!(
                        s,
                        r##"<path d="M {xm:.1} {:.1} l 6 6 l -6 6 l -6 -6 z" fill="{color}" stroke="#fff" stroke-width="1">{tip}</path>"##,
                        yc - 6.0
                    );
                }
                "triangle" => {
                    let _ = writeln!(
                        s,
                        r##"<path d="M {xm:.1} {:.1} l 6 11 l -12 0 z" fill="{color}" stroke="#fff" stroke-width="1">{tip}</path>"##,
                        yc - 6.0
                    );
                }
                _ => {
                    let _ = writeln!(
                        s,
                        r##"<line x1="{xm:.1}" y1="{:.1}" x2="{xm:.1}" y2="{:.1}" stroke="{color}" stroke-width="2">{tip}</line>"##,
                        y0 + 4.0,
                        y0 + rh - 4.0
                    );
                }
            }
            let lx = xm + 8.0;
            if lx > last_label_end + 2.0 {
                let _ = writeln!(
                    s,
                    r##"<text x="{lx:.1}" y="{:.1}" font-size="10" fill="{color}">{}</text>"##,
                    yc - 6.0,
                    esc(short)
                );
                last_label_end = lx + short.chars().count() as f64 * 6.0;
            }
        }
    }

    // Outcomes.
    for (k, (t, m, result, reason)) in outcomes.iter().enumerate() {
        let xo = x(*t);
        let color = match result.as_str() {
            "ok" => "#1f9d3a",
            "fail" => "#d02a2a",
            _ => "#e08a00",
        };
        let label = match (several, m) {
            (true, Some(m)) => format!("{m}: {}", result.to_uppercase()),
            _ => format!("mission {}", result.to_uppercase()),
        };
        let _ = writeln!(
            s,
            r##"<line x1="{xo:.1}" y1="{:.1}" x2="{xo:.1}" y2="{:.1}" stroke="{color}" stroke-width="2" stroke-dasharray="6 3"><title>{}</title></line>"##,
            top - 6.0,
            top + plot_h,
            esc(&format!(
                "t={} {label}{}",
                fmt_time(*t),
                reason.as_ref().map(|r| format!(": {r}")).unwrap_or_default()
            ))
        );
        let _ = writeln!(
            s,
            r##"<text x="{:.1}" y="{:.1}" font-size="12" font-weight="bold" fill="{color}">{}</text>"##,
            xo + 5.0,
            top + 12.0 + k as f64 * 14.0,
            esc(&label)
        );
    }
    s.push_str("</svg>\n");
    s
}

fn ending_colors(e: Ending) -> (&'static str, &'static str) {
    match e {
        Ending::Aborted => ("#b9d2ee", "#3a6ea5"),
        Ending::Ok => ("#b7e2c0", "#1f9d3a"),
        Ending::Fail => ("#f3b8b8", "#d02a2a"),
        Ending::Timeout => ("#f7d49a", "#e08a00"),
    }
}

/// The legend, one line at height `y`.
fn legend(s: &mut String, x0: f64, y: f64) {
    let mut x = x0;
    let text = |s: &mut String, x: &mut f64, t: &str| {
        let _ = writeln!(s, r##"<text x="{:.1}" y="{:.1}" font-size="11" fill="#555">{}</text>"##, *x, y + 4.0, esc(t));
        *x += t.chars().count() as f64 * 6.3 + 16.0;
    };
    text(s, &mut x, "primitive enabled, then:");
    for (e, t) in [
        (Ending::Ok, "ended ok"),
        (Ending::Fail, "failed"),
        (Ending::Timeout, "timed out"),
        (Ending::Aborted, "aborted / running"),
    ] {
        let (fill, stroke) = ending_colors(e);
        let _ = writeln!(
            s,
            r##"<rect x="{x:.1}" y="{:.1}" width="22" height="10" rx="2" fill="{fill}" stroke="{stroke}"/>"##,
            y - 5.0
        );
        x += 27.0;
        text(s, &mut x, t);
    }
    for (shape, color, t) in [
        ("circle", "#1f9d3a", "ok event"),
        ("circle", "#d02a2a", "fail event"),
        ("diamond", "#e08a00", "time-out"),
        ("triangle", "#e08a00", "unexpected event"),
    ] {
        match shape {
            "circle" => {
                let _ = writeln!(s, r##"<circle cx="{:.1}" cy="{y:.1}" r="5" fill="{color}"/>"##, x + 5.0);
            }
            "diamond" => {
                let _ = writeln!(
                    s,
                    r##"<path d="M {:.1} {:.1} l 6 6 l -6 6 l -6 -6 z" fill="{color}"/>"##,
                    x + 5.0,
                    y - 6.0
                );
            }
            _ => {
                let _ = writeln!(s, r##"<path d="M {:.1} {:.1} l 6 11 l -12 0 z" fill="{color}"/>"##, x + 5.0, y - 6.0);
            }
        }
        x += 15.0;
        text(s, &mut x, t);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(t: f64, kind: &str) -> Record {
        Record::new(t, kind)
    }

    #[test]
    fn bars_marks_and_outcome() {
        let mut a = rec(0.0, "action");
        a.primitive = Some("GotoPrimitive".into());
        a.command = Some("enable".into());
        a.task = Some("Goto".into());
        let mut e = rec(5.0, "event");
        e.event = Some("eventGotoOk".into());
        e.task = Some("Goto".into());
        let mut d = rec(5.0, "action");
        d.primitive = Some("GotoPrimitive".into());
        d.command = Some("disable".into());
        let mut u = rec(6.0, "unexpected_event");
        u.event = Some("eventX".into());
        let mut o = rec(7.0, "outcome");
        o.result = Some("ok".into());
        let svg = render(&[a, e, d, u, o], &Options::default());
        assert!(svg.starts_with("<svg"));
        assert!(svg.contains(">GotoPrimitive</text>"));
        assert!(svg.contains("enabled from 0 s to 5 s (ended ok)"));
        assert!(svg.contains("#1f9d3a"));
        assert!(svg.contains("unexpected events"));
        assert!(svg.contains("mission OK"));
        assert!(svg.trim_end().ends_with("</svg>"));
    }

    #[test]
    fn ticks_are_nice() {
        assert_eq!(tick_step(100.0, 10.0), 10.0);
        assert_eq!(tick_step(130.0, 12.0), 20.0);
        assert_eq!(tick_step(7.0, 12.0), 1.0);
    }
}
