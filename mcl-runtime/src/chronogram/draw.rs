//! The chronogram as SVG text: title, legend, time axis, rows (bars, marks
//! and their names), outcomes. Hand-written SVG, no dependencies.

use std::fmt::Write;

use super::collect::{Chart, Ending, Mark, MarkKind, Outcome, Row};
use super::layout::{tick_step, Layout, RowLayout, LANE_H, NAME_FONT};
use super::{fmt_time, Options};

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// The SVG document of `chart` laid out by `l`.
pub(super) fn draw(chart: &Chart, l: &Layout, opts: &Options) -> String {
    let mut s = String::new();
    header(&mut s, l, &title(chart, opts));
    grid(&mut s, l);
    for (i, (row, rl)) in chart.rows.iter().zip(&l.rows).enumerate() {
        self::row(&mut s, l, i, row, rl);
    }
    outcomes(&mut s, chart, l);
    s.push_str("</svg>\n");
    s
}

/// The title: `opts.title`, else the missions and how each ended.
fn title(chart: &Chart, opts: &Options) -> String {
    let several = chart.several;
    opts.title.clone().unwrap_or_else(|| {
        let name = chart.missions.iter().flatten().cloned().collect::<Vec<_>>().join(", ");
        let name = if name.is_empty() { "mission".to_string() } else { name };
        let res: Vec<String> = chart
            .outcomes
            .iter()
            .map(|o| {
                let via = o.via.as_ref().map(|v| format!(" through {v}")).unwrap_or_default();
                match (several, &o.mission) {
                    (true, Some(m)) => format!("{m}: {}{via} at {} s", o.result.to_uppercase(), fmt_time(o.t)),
                    _ => format!("{}{via} at {} s", o.result.to_uppercase(), fmt_time(o.t)),
                }
            })
            .collect();
        if res.is_empty() {
            format!("{name} (no outcome)")
        } else {
            format!("{name}: {}", res.join(", "))
        }
    })
}

/// The page, the title and the legend.
fn header(s: &mut String, l: &Layout, title: &str) {
    let (left, width, height) = (l.left, l.width, l.height);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="DejaVu Sans, Helvetica, Arial, sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r##"<rect x="0" y="0" width="{width:.0}" height="{height:.0}" fill="#ffffff"/>"##);
    let _ = writeln!(
        s,
        r##"<text x="{left:.1}" y="26" font-size="16" font-weight="bold" fill="#222">{}</text>"##,
        esc(title)
    );
    legend(s, left, 46.0);
}

/// The time axis: a vertical line and a label per tick.
fn grid(s: &mut String, l: &Layout) {
    let (left, top, pw, span, plot_h) = (l.left, l.top, l.plot_width, l.span, l.plot_h);
    let x = |t: f64| l.x(t);
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
}

/// One row: its band, its label, its bars and its marks.
fn row(s: &mut String, l: &Layout, i: usize, row: &Row, rl: &RowLayout) {
    let (left, rh, pw) = (l.left, l.row_height, l.plot_width);
    let (y0, h) = (rl.top, rl.height);
    // The bars' part of the row, under the lines of names.
    let yb = rl.bars_top();
    let yc = yb + rh / 2.0;
    if i % 2 == 1 {
        let _ = writeln!(s, r##"<rect x="0" y="{y0:.1}" width="{:.1}" height="{h:.1}" fill="#f6f8fa"/>"##, left + pw);
    }
    let _ = writeln!(
        s,
        r##"<text x="{:.1}" y="{:.1}" text-anchor="end" fill="#222">{}</text>"##,
        left - 10.0,
        yc + 4.0,
        esc(&row.label)
    );
    bars(s, l, row, yb, yc);
    marks(s, l, row, rl, yb, yc);
}

/// The bars of a row (tops of the bars' part at `yb`, middle at `yc`).
fn bars(s: &mut String, l: &Layout, row: &Row, yb: f64, yc: f64) {
    let (rh, span) = (l.row_height, l.span);
    let x = |t: f64| l.x(t);
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
}

/// The marks of a row, each with its name in the line the layout gave it.
fn marks(s: &mut String, l: &Layout, row: &Row, rl: &RowLayout, yb: f64, yc: f64) {
    let (left, rh, pw) = (l.left, l.row_height, l.plot_width);
    let x = |t: f64| l.x(t);
    let mut hidden = 0;
    for (Mark { t, kind, name, details }, lane) in row.marks.iter().zip(&rl.lane_of) {
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

/// A dashed vertical line and a name per outcome.
fn outcomes(s: &mut String, chart: &Chart, l: &Layout) {
    let (top, plot_h, several) = (l.top, l.plot_h, chart.several);
    let x = |t: f64| l.x(t);
    let outcomes = &chart.outcomes;
    for (k, Outcome { t, mission: m, result, reason, .. }) in outcomes.iter().enumerate() {
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
