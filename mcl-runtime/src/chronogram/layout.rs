//! The chronogram's coordinates: the time axis, the height of each row
//! (its lines of mark names above its bars), the size of the page.

use super::collect::Chart;
use super::Options;

/// Height of one line of mark names.
pub(super) const LANE_H: f64 = 12.0;
/// Lines of mark names per row at most; names that would need more are
/// left out (their marks keep their tooltips) and counted under the row.
pub const MAX_LANES: usize = 8;
/// Font size of mark names, and the width allowed per character (generous,
/// so that names never touch in a browser).
pub(super) const NAME_FONT: f64 = 10.0;
const NAME_CHAR_W: f64 = 6.4;

/// Width of a mark name on the page.
pub(super) fn name_width(name: &str) -> f64 {
    name.chars().count() as f64 * NAME_CHAR_W + 4.0
}

/// Assigns each mark name (at its x, in time order) the first line where it
/// does not overlap the previous name of that line. Returns the line of
/// each (None: left out) and the number of lines used.
pub(super) fn lanes(xs: &[(f64, f64)]) -> (Vec<Option<usize>>, usize) {
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

/// A "nice" tick step for a span of `span` seconds and about `n` ticks.
pub(super) fn tick_step(span: f64, n: f64) -> f64 {
    let raw = (span / n).max(1e-6);
    let mag = 10f64.powf(raw.log10().floor());
    for m in [1.0, 2.0, 5.0, 10.0] {
        if m * mag >= raw {
            return m * mag;
        }
    }
    10.0 * mag
}

/// Where a row goes.
#[derive(Debug)]
pub(super) struct RowLayout {
    /// The line of each mark's name (None: left out).
    pub lane_of: Vec<Option<usize>>,
    /// Lines of names above the bars.
    pub lanes: usize,
    /// Top of the row.
    pub top: f64,
    /// Height of the row.
    pub height: f64,
}

impl RowLayout {
    /// Top of the bars' part of the row, under the lines of names.
    pub fn bars_top(&self) -> f64 {
        self.top + 4.0 + self.lanes as f64 * LANE_H
    }
}

/// Every coordinate of the page.
#[derive(Debug)]
pub(super) struct Layout {
    /// Left edge of the plot (after the row labels).
    pub left: f64,
    /// Top edge of the plot (under the title, legend and outcome names).
    pub top: f64,
    /// Height of a row's bars.
    pub row_height: f64,
    /// Width of the time axis.
    pub plot_width: f64,
    /// Seconds from 0 at the left edge to the right edge.
    pub span: f64,
    pub rows: Vec<RowLayout>,
    /// Height of all rows.
    pub plot_h: f64,
    pub width: f64,
    pub height: f64,
}

impl Layout {
    /// The x of time `t`.
    pub fn x(&self, t: f64) -> f64 {
        self.left + t / self.span * self.plot_width
    }
}

/// The coordinates of `chart`.
pub(super) fn layout(chart: &Chart, opts: &Options) -> Layout {
    let label_w =
        chart.rows.iter().map(|r| r.label.chars().count()).max().unwrap_or(10).clamp(10, 48) as f64 * 7.4 + 24.0;
    let left = label_w;
    // Room above the plot for the outcomes' names.
    let top = 64.0 + 14.0 * chart.outcomes.len() as f64;
    let rh = opts.row_height;
    let pw = opts.plot_width;
    let span = if chart.end_time > 0.0 { chart.end_time } else { 1.0 };
    let mut l = Layout {
        left,
        top,
        row_height: rh,
        plot_width: pw,
        span,
        rows: Vec::new(),
        plot_h: 0.0,
        width: 0.0,
        height: 0.0,
    };
    // Names of the marks, in lines above each row's bars.
    let mut y = top;
    for row in &chart.rows {
        let xs: Vec<(f64, f64)> = row.marks.iter().map(|m| (l.x(m.t) + 2.0, name_width(&m.name))).collect();
        let (lane_of, lanes) = lanes(&xs);
        let height = 4.0 + lanes as f64 * LANE_H + rh;
        l.rows.push(RowLayout { lane_of, lanes, top: y, height });
        y += height;
    }
    l.plot_h = l.rows.iter().map(|r| r.height).sum::<f64>().max(rh);
    // Room after the end for the names of the last marks.
    l.width = left + pw + 230.0;
    l.height = top + l.plot_h + 80.0;
    l
}
