//! The trajectory picture (`mcl run --sim --trajectory OUT.svg`): a plan
//! view (north up, equal scales) with the seabed's cable (buried sections
//! dashed), the objects, the wall and the way-points given to the
//! behaviours (numbered in order), and a depth profile over time with the
//! seabed under the vehicle; the path is coloured by the task that moved
//! the vehicle (legend).

use std::fmt::Write;

use mcl_runtime::vehicle::Pose;

use crate::sim::Track;
use crate::world::World;

const PALETTE: [&str; 10] =
    ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf", "#8c564b", "#e377c2", "#bcbd22", "#7f7f7f"];

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// A round step for about `n` ticks over `span`.
fn tick_step(span: f64, n: f64) -> f64 {
    let raw = (span / n).max(1e-9);
    let p = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * p).find(|s| *s >= raw).unwrap_or(10.0 * p)
}

/// The ticks every `step` in [lo, hi] (at most 50: far from the origin a
/// step may be lost in rounding).
fn ticks(lo: f64, hi: f64, step: f64) -> impl Iterator<Item = f64> {
    let first = (lo / step).ceil() * step;
    (0..50).map(move |k| first + k as f64 * step).take_while(move |g| *g <= hi)
}

/// A tick value without float noise nor "-0".
fn tick(v: f64) -> String {
    let r = (v * 1000.0).round() / 1000.0;
    format!("{}", if r == 0.0 { 0.0 } else { r })
}

fn colour(label: usize) -> &'static str {
    if label == 0 {
        "#444444"
    } else {
        PALETTE[(label - 1) % PALETTE.len()]
    }
}

/// The SVG document of `track` in `world`, titled `title`: the path
/// coloured by the task that moved the vehicle.
pub fn svg(track: &Track, world: &World, title: &str) -> String {
    let paths = [track.points.clone()];
    draw(&paths, &[&track.waypoints], &track.labels, "task moving the vehicle", world, title)
}

/// The SVG document of several vehicles in one `world` (`(name, track)`,
/// in order), titled `title`: each path coloured by its vehicle.
pub fn svg_fleet(tracks: &[(&str, &Track)], world: &World, title: &str) -> String {
    let paths: Vec<Vec<(Pose, usize)>> =
        tracks.iter().enumerate().map(|(k, (_, t))| t.points.iter().map(|(p, _)| (*p, k + 1)).collect()).collect();
    let waypoints: Vec<&[(f64, f64)]> = tracks.iter().map(|(_, t)| t.waypoints.as_slice()).collect();
    let mut labels = vec!["-".to_string()];
    labels.extend(tracks.iter().map(|(n, _)| n.to_string()));
    draw(&paths, &waypoints, &labels, "vehicle", world, title)
}

/// Draws `paths` (poses, each with an index in `labels` for its colour)
/// and each path's way-points, numbered in order.
fn draw(
    paths: &[Vec<(Pose, usize)>],
    waypoints: &[&[(f64, f64)]],
    labels: &[String],
    legend: &str,
    world: &World,
    title: &str,
) -> String {
    let (w, h) = (980.0, 900.0);
    // Plan view box.
    let (px, py, ps) = (60.0, 60.0, 560.0);
    // Profile box.
    let (qx, qy, qw, qh) = (60.0, 680.0, 880.0, 170.0);
    let mut xs: Vec<f64> = Vec::new();
    let mut ys: Vec<f64> = Vec::new();
    for (p, _) in paths.iter().flatten() {
        xs.push(p.x);
        ys.push(p.y);
    }
    for &(x, y) in waypoints.iter().copied().flatten() {
        xs.push(x);
        ys.push(y);
    }
    if let Some(c) = &world.cable {
        for &(x, y) in &c.points {
            xs.push(x);
            ys.push(y);
        }
    }
    for o in &world.objects {
        xs.push(o.x);
        ys.push(o.y);
    }
    if xs.is_empty() {
        xs.push(0.0);
        ys.push(0.0);
    }
    let (x0, x1) = xs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, &v| (a.0.min(v), a.1.max(v)));
    let (y0, y1) = ys.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, &v| (a.0.min(v), a.1.max(v)));
    let span = (x1 - x0).max(y1 - y0).max(10.0) * 1.1;
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let (bx0, by0) = (cx - span / 2.0, cy - span / 2.0);
    let sx = |x: f64| px + (x - bx0) / span * ps;
    let sy = |y: f64| py + ps - (y - by0) / span * ps;

    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    let _ = writeln!(s, r#"<text x="{px}" y="30" font-size="16" font-weight="bold">{}</text>"#, esc(title));
    // Plan view: frame, grid, labels.
    let _ = writeln!(
        s,
        r##"<g id="plan"><rect x="{px}" y="{py}" width="{ps}" height="{ps}" fill="#f4f8fb" stroke="#888"/>"##
    );
    let st = tick_step(span, 8.0);
    for g in ticks(bx0, bx0 + span, st) {
        let _ = writeln!(
            s,
            r##"<line x1="{0:.1}" y1="{py}" x2="{0:.1}" y2="{1}" stroke="#dde3ea"/><text x="{0:.1}" y="{2}" text-anchor="middle" fill="#555">{3}</text>"##,
            sx(g),
            py + ps,
            py + ps + 16.0,
            tick(g)
        );
    }
    for g in ticks(by0, by0 + span, st) {
        let _ = writeln!(
            s,
            r##"<line x1="{px}" y1="{0:.1}" x2="{1}" y2="{0:.1}" stroke="#dde3ea"/><text x="{2}" y="{3:.1}" text-anchor="end" fill="#555">{4}</text>"##,
            sy(g),
            px + ps,
            px - 6.0,
            sy(g) + 4.0,
            tick(g)
        );
    }
    let _ = writeln!(
        s,
        r##"<text x="{}" y="{}" text-anchor="middle" fill="#333">east (m)</text><text x="{}" y="{}" fill="#333" transform="rotate(-90 {} {})" text-anchor="middle">north (m)</text>"##,
        px + ps / 2.0,
        py + ps + 34.0,
        px - 40.0,
        py + ps / 2.0,
        px - 40.0,
        py + ps / 2.0
    );
    // The wall.
    if let Some(wall) = &world.wall {
        let (a, b) = (wall.point(-span, 0.0), wall.point(span, 0.0));
        let _ = writeln!(
            s,
            r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#555" stroke-width="4"><title>wall</title></line>"##,
            sx(a.0),
            sy(a.1),
            sx(b.0),
            sy(b.1)
        );
    }
    // The cable: visible parts solid, buried parts dashed.
    if let Some(c) = &world.cable {
        let len = c.length();
        let mut cuts: Vec<f64> = vec![0.0, len];
        for &(a, b) in &c.buried {
            cuts.push(a);
            cuts.push(b);
        }
        cuts.extend(c.cum.iter().copied());
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
        for w in cuts.windows(2) {
            let (a, b) = (w[0], w[1]);
            if b - a < 1e-9 {
                continue;
            }
            let buried = c.is_buried((a + b) / 2.0);
            let (p, q) = (c.point_at(a), c.point_at(b));
            let style = if buried {
                r##"stroke="#b08a5a" stroke-width="2" stroke-dasharray="4 4""##
            } else {
                r##"stroke="#8b5a2b" stroke-width="4""##
            };
            let _ = writeln!(
                s,
                r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" {style} stroke-linecap="round"/>"#,
                sx(p.0),
                sy(p.1),
                sx(q.0),
                sy(q.1)
            );
        }
    }
    for o in &world.objects {
        let _ = writeln!(
            s,
            r##"<rect x="{:.1}" y="{:.1}" width="10" height="10" fill="#e6a700" stroke="#7a5a00"><title>{}</title></rect>"##,
            sx(o.x) - 5.0,
            sy(o.y) - 5.0,
            esc(&o.name)
        );
    }
    // Each path, one polyline per stretch of one label.
    for points in paths {
        for (label, stretch) in stretches(points) {
            let pts: Vec<String> = stretch.iter().map(|(p, _)| format!("{:.2},{:.2}", sx(p.x), sy(p.y))).collect();
            let _ = writeln!(
                s,
                r#"<polyline points="{}" fill="none" stroke="{}" stroke-width="2" stroke-linejoin="round"/>"#,
                pts.join(" "),
                colour(label)
            );
        }
    }
    for (k, &(x, y)) in waypoints.iter().flat_map(|w| w.iter().enumerate()) {
        let _ = writeln!(
            s,
            r##"<circle cx="{:.1}" cy="{:.1}" r="4" fill="none" stroke="#000"/><text x="{:.1}" y="{:.1}" font-size="10" fill="#000">{}</text>"##,
            sx(x),
            sy(y),
            sx(x) + 5.0,
            sy(y) - 5.0,
            k + 1
        );
    }
    for (first, last) in paths.iter().filter_map(|p| Some((p.first()?, p.last()?))) {
        let _ = writeln!(
            s,
            r##"<circle cx="{:.1}" cy="{:.1}" r="6" fill="#2ca02c"><title>start</title></circle><rect x="{:.1}" y="{:.1}" width="10" height="10" fill="#d62728"><title>end</title></rect>"##,
            sx(first.0.x),
            sy(first.0.y),
            sx(last.0.x) - 5.0,
            sy(last.0.y) - 5.0
        );
    }
    let _ = writeln!(s, "</g>");
    // Legend.
    let lx = px + ps + 30.0;
    let _ = writeln!(s, r#"<g id="legend"><text x="{lx}" y="{}" font-weight="bold">{}</text>"#, py + 10.0, esc(legend));
    let mut ly = py + 32.0;
    let used: Vec<usize> = {
        let mut u: Vec<usize> = paths.iter().flatten().map(|p| p.1).collect();
        u.sort_unstable();
        u.dedup();
        u
    };
    for &k in &used {
        let name = if k == 0 { "(none)" } else { labels.get(k).map_or("?", String::as_str) };
        let _ = writeln!(
            s,
            r#"<rect x="{lx}" y="{:.1}" width="24" height="6" fill="{}"/><text x="{}" y="{:.1}">{}</text>"#,
            ly - 6.0,
            colour(k),
            lx + 32.0,
            ly,
            esc(name)
        );
        ly += 20.0;
    }
    let mut extra: Vec<(&str, &str)> = vec![("○ n", "way-point n, in order"), ("●", "start"), ("■", "end")];
    if world.cable.is_some() {
        extra.push(("━", "cable (dashed: buried)"));
    }
    if !world.objects.is_empty() {
        extra.push(("■", "object of interest"));
    }
    for (sym, what) in extra {
        let _ = writeln!(s, r#"<text x="{lx}" y="{ly:.1}">{} {}</text>"#, esc(sym), esc(what));
        ly += 20.0;
    }
    let _ = writeln!(s, "</g>");
    // Depth profile.
    let tmax = paths.iter().filter_map(|p| p.last()).map(|p| p.0.t).fold(1.0f64, f64::max);
    let zmax =
        paths.iter().flatten().map(|(p, _)| p.z.max(world.seabed.depth_at(p.x, p.y))).fold(1.0f64, f64::max) * 1.1;
    let tx = |t: f64| qx + t / tmax * qw;
    let tz = |z: f64| qy + z / zmax * qh;
    let _ = writeln!(
        s,
        r##"<g id="profile"><text x="{qx}" y="{}" font-weight="bold">depth (m) over time</text><rect x="{qx}" y="{qy}" width="{qw}" height="{qh}" fill="#f4f8fb" stroke="#888"/>"##,
        qy - 10.0
    );
    let stt = tick_step(tmax, 10.0);
    for g in ticks(0.0, tmax, stt) {
        let _ = writeln!(
            s,
            r##"<line x1="{0:.1}" y1="{qy}" x2="{0:.1}" y2="{1}" stroke="#dde3ea"/><text x="{0:.1}" y="{2}" text-anchor="middle" fill="#555">{3}</text>"##,
            tx(g),
            qy + qh,
            qy + qh + 14.0,
            tick(g)
        );
    }
    let stz = tick_step(zmax, 4.0);
    for g in ticks(0.0, zmax, stz) {
        let _ = writeln!(
            s,
            r##"<text x="{}" y="{:.1}" text-anchor="end" fill="#555">{}</text>"##,
            qx - 6.0,
            tz(g) + 4.0,
            tick(g)
        );
    }
    let _ = writeln!(
        s,
        r##"<text x="{}" y="{}" text-anchor="middle" fill="#333">time (s)</text>"##,
        qx + qw / 2.0,
        qy + qh + 30.0
    );
    for points in paths.iter().filter(|p| !p.is_empty()) {
        let bed: Vec<String> =
            points.iter().map(|(p, _)| format!("{:.2},{:.2}", tx(p.t), tz(world.seabed.depth_at(p.x, p.y)))).collect();
        let _ =
            writeln!(s, r##"<polyline points="{}" fill="none" stroke="#8b7355" stroke-width="1.5"/>"##, bed.join(" "));
    }
    for points in paths {
        for (label, stretch) in stretches(points) {
            let pts: Vec<String> = stretch.iter().map(|(p, _)| format!("{:.2},{:.2}", tx(p.t), tz(p.z))).collect();
            let _ = writeln!(
                s,
                r#"<polyline points="{}" fill="none" stroke="{}" stroke-width="2"/>"#,
                pts.join(" "),
                colour(label)
            );
        }
    }
    let _ = writeln!(s, "</g>\n</svg>");
    s
}

/// The stretches of one label of a path, each with the next stretch's
/// first point so that the path is drawn continuous.
fn stretches(points: &[(Pose, usize)]) -> Vec<(usize, &[(Pose, usize)])> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < points.len() {
        let label = points[i].1;
        let mut j = i;
        while j + 1 < points.len() && points[j + 1].1 == label {
            j += 1;
        }
        out.push((label, &points[i..=(j + 1).min(points.len() - 1)]));
        i = j + 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_path_waypoints_cable_and_legend() {
        let world = World::from_toml("[cable]\npoints = [[0, 0], [30, 0]]\nburied = [[10, 20]]\n", "w").unwrap();
        let p = |t: f64, x: f64| Pose { t, x, y: 1.0, z: 5.0, yaw: 0.0 };
        let track = Track {
            points: vec![(p(0.0, 0.0), 0), (p(1.0, 1.0), 1), (p(2.0, 2.0), 1), (p(3.0, 3.0), 2)],
            labels: vec!["-".into(), "Goto".into(), "Cable<Tracking>".into()],
            waypoints: vec![(3.0, 1.0)],
        };
        let s = svg(&track, &world, "a & b");
        assert!(s.starts_with("<svg") && s.trim_end().ends_with("</svg>"));
        assert!(s.contains("a &amp; b") && s.contains("Cable&lt;Tracking&gt;") && s.contains(">Goto<"));
        assert_eq!(s.matches("stroke-dasharray").count(), 1, "one buried section");
        assert_eq!(s.matches("<polyline").count(), 1 + 3 + 3, "seabed + 3 stretches in each view");
    }

    #[test]
    fn a_fleet_is_one_path_per_vehicle_in_its_colour() {
        let world = World::default();
        let p = |t: f64, x: f64, y: f64| Pose { t, x, y, z: 1.0, yaw: 0.0 };
        let track = |y: f64| Track {
            points: vec![(p(0.0, 0.0, y), 0), (p(1.0, 1.0, y), 1), (p(2.0, 2.0, y), 2)],
            labels: vec!["-".into(), "Goto".into(), "Surface".into()],
            waypoints: vec![(2.0, y)],
        };
        let (a, b) = (track(0.0), track(10.0));
        let s = svg_fleet(&[("auv", &a), ("asc", &b)], &world, "fleet");
        assert!(s.contains(">vehicle<") && s.contains(">auv<") && s.contains(">asc<") && !s.contains(">Goto<"));
        assert_eq!(s.matches("<polyline").count(), 2 + 2 + 2, "per vehicle: a seabed line and one stretch per view");
        assert_eq!(s.matches("<title>start</title>").count(), 2);
        assert!(
            s.contains(&format!(r#"stroke="{}""#, PALETTE[0])) && s.contains(&format!(r#"stroke="{}""#, PALETTE[1]))
        );
    }

    #[test]
    fn far_from_the_origin_the_axes_stay_bounded() {
        let world = World::from_toml("[start]\nposition = [1e17, 1e17]\n", "w").unwrap();
        let p = Pose { t: 0.0, x: 1e17, y: 1e17, z: 0.0, yaw: 0.0 };
        let track = Track { points: vec![(p, 0)], labels: vec!["-".into()], waypoints: vec![] };
        assert!(svg(&track, &world, "far").len() < 100_000);
    }
}
