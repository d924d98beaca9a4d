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
    /// (time, kind, name, details)
    marks: Vec<(f64, MarkKind, String, String)>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum MarkKind {
    Ok,
    Fail,
    Other,
    Timeout,
    Unexpected,
    Stale,
    Action,
}

/// Height of one line of mark names.
const LANE_H: f64 = 12.0;
/// Lines of mark names per row at most; names that would need more are
/// left out (their marks keep their tooltips) and counted under the row.
pub const MAX_LANES: usize = 8;
/// Font size of mark names, and the width allowed per character (generous,
/// so that names never touch in a browser).
const NAME_FONT: f64 = 10.0;
const NAME_CHAR_W: f64 = 6.4;

/// Width of a mark name on the page.
fn name_width(name: &str) -> f64 {
    name.chars().count() as f64 * NAME_CHAR_W + 4.0
}

/// Assigns each mark name (at its x, in time order) the first line where it
/// does not overlap the previous name of that line. Returns the line of
/// each (None: left out) and the number of lines used.
fn lanes(xs: &[(f64, f64)]) -> (Vec<Option<usize>>, usize) {
    let mut ends: Vec<f64> = Vec::new();
    let mut out = Vec::with_capacity(xs.len());
    for &(x, w) in xs {
        match ends.iter().position(|&e| e + 3.0 <= x) {
            Some(k) => {
                ends[k] = x + w;
                out.push(Some(k));
            }
            None if ends.len() < MAX_LANES => {
                ends.push(x + w);
                out.push(Some(ends.len() - 1));
            }
            None => out.push(None),
        }
    }
    (out, ends.len())
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
    // (time, mission, result, reason, how it got there off its nominal path)
    #[allow(clippy::type_complexity)]
    let mut outcomes: Vec<(f64, Option<String>, String, Option<String>, Option<String>)> = Vec::new();
    // The row of each action, by (mission, seq).
    let mut seq_row: HashMap<(Option<String>, u64), usize> = HashMap::new();
    let missions: Vec<Option<String>> = {
        let mut v: Vec<Option<String>> = Vec::new();
        // `"*"`: a record about every mission (coord_summary).
        for r in records.iter().filter(|r| r.mission.as_deref() != Some("*")) {
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
                    "t={} action #{} {} = {prim} {}({}){}{}",
                    fmt_time(r.t),
                    r.seq.unwrap_or_default(),
                    r.action.as_deref().unwrap_or(""),
                    cmd,
                    r.params.iter().flatten().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(", "),
                    r.task
                        .as_ref()
                        .map(|t| format!(
                            " (task {t}{})",
                            r.label.as_ref().map(|l| format!(":{l}")).unwrap_or_default()
                        ))
                        .unwrap_or_default(),
                    r.src.as_ref().map(|s| format!(" at {s}")).unwrap_or_default()
                );
                if let Some(seq) = r.seq {
                    seq_row.insert((r.mission.clone(), seq), i);
                }
                let name = r.action.clone().unwrap_or_else(|| cmd.clone());
                rows[i].marks.push((r.t, MarkKind::Action, name, details));
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
                }
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
                // What the event ends comes from the net (`ends`); traces
                // written before it existed fall back to the event's name.
                let kind = match r.ends.as_deref() {
                    Some("ok") => MarkKind::Ok,
                    Some("fail") => MarkKind::Fail,
                    Some(_) => MarkKind::Other,
                    None if ev.ends_with("Ok") || ev.ends_with("_ok") => MarkKind::Ok,
                    None if ev.ends_with("Fail") || ev.ends_with("_fail") => MarkKind::Fail,
                    None => MarkKind::Other,
                };
                let details = format!(
                    "t={} event {ev}{}{}",
                    fmt_time(r.t),
                    r.task
                        .as_ref()
                        .map(|t| format!(
                            " (task {t}{})",
                            r.label.as_ref().map(|l| format!(":{l}")).unwrap_or_default()
                        ))
                        .unwrap_or_default(),
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
                rows[i].marks.push((r.t, kind, ev, details));
            }
            "stale_event" => {
                let ev = r.event.clone().unwrap_or_default();
                let details = format!(
                    "t={} event {ev} of a disabled run, ignored: {}",
                    fmt_time(r.t),
                    r.reason.as_deref().unwrap_or("stale")
                );
                let row = r.activation.and_then(|a| seq_row.get(&(r.mission.clone(), a)).copied());
                let i = match row {
                    Some(i) => i,
                    None => row_for(&mut rows, &mut row_of, &r.mission, "events"),
                };
                rows[i].marks.push((r.t, MarkKind::Stale, format!("{ev} (stale)"), details));
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
                outcomes.push((
                    r.t,
                    r.mission.clone(),
                    r.result.clone().unwrap_or_default(),
                    r.reason.clone(),
                    r.via.clone(),
                ));
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
    // Room above the plot for the outcomes' names.
    let top = 64.0 + 14.0 * outcomes.len() as f64;
    let rh = opts.row_height;
    let pw = opts.plot_width;
    let span = if end_time > 0.0 { end_time } else { 1.0 };
    let x = |t: f64| left + t / span * pw;
    // Names of the marks, in lines above each row's bars.
    for row in rows.iter_mut() {
        row.marks.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    let layouts: Vec<(Vec<Option<usize>>, usize)> = rows
        .iter()
        .map(|row| lanes(&row.marks.iter().map(|(t, _, name, _)| (x(*t) + 2.0, name_width(name))).collect::<Vec<_>>()))
        .collect();
    let heights: Vec<f64> = layouts.iter().map(|(_, n)| 4.0 + *n as f64 * LANE_H + rh).collect();
    let tops: Vec<f64> = heights
        .iter()
        .scan(top, |y, h| {
            let y0 = *y;
            *y += h;
            Some(y0)
        })
        .collect();
    let plot_h = heights.iter().sum::<f64>().max(rh);
    // Room after the end for the names of the last marks.
    let width = left + pw + 230.0;
    let height = top + plot_h + 80.0;

    let title = opts.title.clone().unwrap_or_else(|| {
        let name = missions.iter().flatten().cloned().collect::<Vec<_>>().join(", ");
        let name = if name.is_empty() { "mission".to_string() } else { name };
        let res: Vec<String> = outcomes
            .iter()
            .map(|(t, m, r, _, via)| {
                let via = via.as_ref().map(|v| format!(" through {v}")).unwrap_or_default();
                match (several, m) {
                    (true, Some(m)) => format!("{m}: {}{via} at {} s", r.to_uppercase(), fmt_time(*t)),
                    _ => format!("{}{via} at {} s", r.to_uppercase(), fmt_time(*t)),
                }
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
        let (lane_of, n_lanes) = &layouts[i];
        let y0 = tops[i];
        let h = heights[i];
        // The bars' part of the row, under the lines of names.
        let yb = y0 + 4.0 + *n_lanes as f64 * LANE_H;
        let yc = yb + rh / 2.0;
        if i % 2 == 1 {
            let _ =
                writeln!(s, r##"<rect x="0" y="{y0:.1}" width="{:.1}" height="{h:.1}" fill="#f6f8fa"/>"##, left + pw);
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
                yb + 6.0,
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
        // Marks, each with its name in the line the layout gave it.
        let mut hidden = 0;
        for ((t, kind, name, details), lane) in row.marks.iter().zip(lane_of) {
            let xm = x(*t);
            let (color, shape) = match kind {
                MarkKind::Ok => ("#1f9d3a", "circle"),
                MarkKind::Fail => ("#d02a2a", "circle"),
                MarkKind::Other => ("#777777", "circle"),
                MarkKind::Stale => ("#999999", "ring"),
                MarkKind::Timeout => ("#e08a00", "diamond"),
                MarkKind::Unexpected => ("#e08a00", "triangle"),
                MarkKind::Action => ("#3a6ea5", "tick"),
            };
            let tip = format!("<title>{}</title>", esc(details));
            match lane {
                Some(k) => {
                    // The name, and a faint line down to its mark.
                    let base = yb - 3.0 - *k as f64 * LANE_H;
                    let _ = writeln!(
                        s,
                        r##"<line x1="{xm:.1}" y1="{:.1}" x2="{xm:.1}" y2="{:.1}" stroke="{color}" stroke-opacity="0.35" stroke-width="0.8"/>"##,
                        base - 8.0,
                        yc - 6.0
                    );
                    let _ = writeln!(
                        s,
                        r##"<text class="mark-name" x="{:.1}" y="{base:.1}" font-size="{NAME_FONT}" fill="{color}">{}{tip}</text>"##,
                        xm + 2.0,
                        esc(name)
                    );
                }
                None => hidden += 1,
            }
            match shape {
                "circle" => {
                    let _ = writeln!(
                        s,
                        r##"<circle cx="{xm:.1}" cy="{yc:.1}" r="5" fill="{color}" stroke="#fff" stroke-width="1.5">{tip}</circle>"##
                    );
                }
                "ring" => {
                    let _ = writeln!(
                        s,
                        r##"<circle cx="{xm:.1}" cy="{yc:.1}" r="4" fill="#fff" stroke="{color}" stroke-width="1.5">{tip}</circle>"##
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
                        yb + 2.0,
                        yb + rh - 2.0
                    );
                }
            }
        }
        if hidden > 0 {
            let _ = writeln!(
                s,
                r##"<text x="{:.1}" y="{:.1}" font-size="10" fill="#777">+{hidden} names not shown (hover the marks)</text>"##,
                left + pw + 8.0,
                yc + 4.0
            );
        }
    }

    // Outcomes.
    for (k, (t, m, result, reason, _)) in outcomes.iter().enumerate() {
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
            top - 14.0 * (outcomes.len() - k) as f64 + 2.0,
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
            top - 14.0 * (outcomes.len() - k - 1) as f64 - 4.0,
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
        ("tick", "#3a6ea5", "action"),
        ("circle", "#1f9d3a", "ok event"),
        ("circle", "#d02a2a", "fail event"),
        ("diamond", "#e08a00", "time-out"),
        ("ring", "#999999", "event of a disabled run"),
        ("triangle", "#e08a00", "unexpected event"),
    ] {
        match shape {
            "tick" => {
                let _ = writeln!(
                    s,
                    r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{color}" stroke-width="2"/>"##,
                    x + 5.0,
                    y - 6.0,
                    x + 5.0,
                    y + 6.0
                );
            }
            "circle" => {
                let _ = writeln!(s, r##"<circle cx="{:.1}" cy="{y:.1}" r="5" fill="{color}"/>"##, x + 5.0);
            }
            "ring" => {
                let _ = writeln!(
                    s,
                    r##"<circle cx="{:.1}" cy="{y:.1}" r="4" fill="#fff" stroke="{color}" stroke-width="1.5"/>"##,
                    x + 5.0
                );
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

    fn action(t: f64, seq: u64, prim: &str, task: &str, command: &str) -> Record {
        let mut a = rec(t, "action");
        a.seq = Some(seq);
        a.action = Some(format!("{command}{task}"));
        a.primitive = Some(prim.into());
        a.command = Some(command.into());
        a.task = Some(task.into());
        a.src = Some(format!("m.mcl:{}", 10 + seq));
        a
    }

    fn event(t: f64, ev: &str, task: &str) -> Record {
        let mut e = rec(t, "event");
        e.event = Some(ev.into());
        e.task = Some(task.into());
        e.src = Some("m.mcl:3".into());
        e
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
            event(5.0, "eventGotoOk", "Goto"),
            action(5.0, 3, "GotoPrimitive", "Goto", "disable"),
            action(5.0, 4, "GotoPrimitive", "Goto", "enable"),
            event(5.5, "eventGotoFail", "Goto"),
            action(5.5, 5, "GotoPrimitive", "Goto", "disable"),
            action(6.0, 6, "DepthPrimitive", "Depth", "disable"),
        ];
        let mut st = rec(6.0, "stale_event");
        st.event = Some("eventDepthOk".into());
        st.activation = Some(2);
        st.reason = Some("its activation, action #2, is over".into());
        recs.push(st);
        let mut o = rec(100.0, "outcome");
        o.result = Some("ok".into());
        recs.push(o);
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
            let mut e = event(1.0, &format!("ev{k}"), "Goto");
            e.task = None;
            recs.push(e);
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
