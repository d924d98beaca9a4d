//! The world file (TOML): where the vehicle starts, the seabed, the water
//! current, a cable, objects of interest, a dam wall, the battery and the
//! navigation drift. Shared by every vehicle simulated in it (read-only:
//! what changes during a run, such as the battery's charge, belongs to the
//! vehicle, [`crate::sim::SimVehicle`]). Format: `docs/simulator.md`.
//!
//! Frame: `x` east and `y` north in metres, depth positive down, angles in
//! the file in degrees (0 towards east, counter-clockwise), in memory in
//! radians.

use std::collections::BTreeMap;
use std::path::Path;

use serde::de::{self, Deserializer};
use serde::Deserialize;
use serde_json::Value;

use crate::error::toml_error;

/// Depth of the flat seabed of the default world, metres.
pub const DEFAULT_SEABED_DEPTH: f64 = 20.0;

/// Where the vehicle starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Start {
    pub x: f64,
    pub y: f64,
    /// Depth, metres.
    pub z: f64,
    /// Heading, radians.
    pub yaw: f64,
}

/// The seabed's depth below the surface.
#[derive(Clone, Debug, PartialEq)]
pub enum Seabed {
    /// `depth` at the origin, growing by `slope.0` per metre east and
    /// `slope.1` per metre north (flat when both are 0); never below 0.
    Plane { depth: f64, slope: (f64, f64) },
    /// Depths on a regular grid (rows south to north, columns west to
    /// east, the first sample at `origin`), bilinear between samples and
    /// constant beyond the edges.
    Grid { origin: (f64, f64), cell: f64, depths: Vec<Vec<f64>> },
}

impl Seabed {
    /// The seabed's depth at (x, y), metres (≥ 0).
    pub fn depth_at(&self, x: f64, y: f64) -> f64 {
        match self {
            Seabed::Plane { depth, slope } => (depth + slope.0 * x + slope.1 * y).max(0.0),
            Seabed::Grid { origin, cell, depths } => {
                let rows = depths.len();
                let cols = depths[0].len();
                let fx = ((x - origin.0) / cell).clamp(0.0, (cols - 1) as f64);
                let fy = ((y - origin.1) / cell).clamp(0.0, (rows - 1) as f64);
                let (c0, r0) = (fx.floor() as usize, fy.floor() as usize);
                let (c1, r1) = ((c0 + 1).min(cols - 1), (r0 + 1).min(rows - 1));
                let (u, v) = (fx - c0 as f64, fy - r0 as f64);
                let a = depths[r0][c0] * (1.0 - u) + depths[r0][c1] * u;
                let b = depths[r1][c0] * (1.0 - u) + depths[r1][c1] * u;
                (a * (1.0 - v) + b * v).max(0.0)
            }
        }
    }
}

/// A cable on the seabed: a polyline, parts of it buried (invisible).
#[derive(Clone, Debug, PartialEq)]
pub struct Cable {
    /// What a detector's `target` calls it (besides `cable`).
    pub name: String,
    /// Vertices, metres.
    pub points: Vec<(f64, f64)>,
    /// Arc length at each vertex (`cum[0] = 0`).
    pub cum: Vec<f64>,
    /// Buried sections as arc-length intervals [from, to], metres.
    pub buried: Vec<(f64, f64)>,
    /// How far (horizontally) the vehicle's sensors see the cable, metres.
    pub range: f64,
    /// The highest altitude over the seabed at which the cable is seen, metres.
    pub max_altitude: f64,
}

impl Cable {
    /// Its length, metres.
    pub fn length(&self) -> f64 {
        *self.cum.last().unwrap_or(&0.0)
    }

    /// The point at arc length `s` (clamped to the cable).
    pub fn point_at(&self, s: f64) -> (f64, f64) {
        let s = s.clamp(0.0, self.length());
        let i = self.cum.partition_point(|&c| c <= s).clamp(1, self.points.len() - 1);
        let (a, b) = (self.points[i - 1], self.points[i]);
        let seg = self.cum[i] - self.cum[i - 1];
        let u = if seg > 0.0 { (s - self.cum[i - 1]) / seg } else { 0.0 };
        (a.0 + (b.0 - a.0) * u, a.1 + (b.1 - a.1) * u)
    }

    /// Whether arc length `s` lies in a buried section.
    pub fn is_buried(&self, s: f64) -> bool {
        self.buried.iter().any(|&(a, b)| a <= s && s <= b)
    }

    /// The nearest point to (x, y) with arc length in [lo, hi]: its arc
    /// length and horizontal distance.
    pub fn project(&self, x: f64, y: f64, lo: f64, hi: f64) -> (f64, f64) {
        let mut best = (lo.clamp(0.0, self.length()), f64::INFINITY);
        for i in 1..self.points.len() {
            let (s0, s1) = (self.cum[i - 1], self.cum[i]);
            if s1 < lo || s0 > hi || s1 <= s0 {
                continue;
            }
            let (a, b) = (self.points[i - 1], self.points[i]);
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            let len = s1 - s0;
            let u = (((x - a.0) * dx + (y - a.1) * dy) / (len * len)).clamp(0.0, 1.0);
            let s = (s0 + u * len).clamp(lo.max(s0), hi.min(s1));
            let (px, py) = self.point_at(s);
            let d = (px - x).hypot(py - y);
            if d < best.1 {
                best = (s, d);
            }
        }
        best
    }

    /// The nearest visible (not buried) point beyond arc length `after`
    /// within `range` of (x, y): its arc length. Scans the cable every
    /// half metre (at most 20,000 points: coarser on a longer cable).
    pub fn visible_near(&self, x: f64, y: f64, after: f64) -> Option<f64> {
        let mut best: Option<(f64, f64)> = None;
        let mut s = after.max(0.0);
        let len = self.length();
        let ds = (len / 20_000.0).max(0.5);
        while s <= len {
            if !self.is_buried(s) {
                let (px, py) = self.point_at(s);
                let d = (px - x).hypot(py - y);
                if d <= self.range && best.is_none_or(|b| d < b.1) {
                    best = Some((s, d));
                }
            }
            s += ds;
        }
        best.map(|b| b.0)
    }
}

/// An object of interest on the seabed.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// What a detector's `target` names (an `object_description`).
    pub name: String,
    pub x: f64,
    pub y: f64,
    /// How far (horizontally) it is seen from, metres.
    pub range: f64,
}

/// A vertical wall (a dam): the line through `origin` along `direction`;
/// the water is on its left (`direction` + 90°).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wall {
    pub origin: (f64, f64),
    /// Radians.
    pub direction: f64,
}

impl Wall {
    /// Unit vectors along the wall and towards the water.
    pub fn axes(&self) -> ((f64, f64), (f64, f64)) {
        let (s, c) = self.direction.sin_cos();
        ((c, s), (-s, c))
    }

    /// The point `u` metres along the wall and `off` metres in front of it.
    pub fn point(&self, u: f64, off: f64) -> (f64, f64) {
        let (a, n) = self.axes();
        (self.origin.0 + a.0 * u + n.0 * off, self.origin.1 + a.1 * u + n.1 * off)
    }

    /// (along, in front) coordinates of (x, y).
    pub fn coords(&self, x: f64, y: f64) -> (f64, f64) {
        let (a, n) = self.axes();
        let (dx, dy) = (x - self.origin.0, y - self.origin.1);
        (dx * a.0 + dy * a.1, dx * n.0 + dy * n.1)
    }

    /// The heading that faces the wall, radians.
    pub fn facing(&self) -> f64 {
        self.direction - std::f64::consts::FRAC_PI_2
    }
}

/// The battery: energy drawn by the hotel load (time) and by motion (distance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Battery {
    /// Full charge, watt-hours.
    pub capacity_wh: f64,
    /// Charge at the start, fraction of the capacity.
    pub initial: f64,
    /// Constant draw, watts.
    pub hotel_w: f64,
    /// Energy per metre travelled through the water, joules.
    pub per_metre_j: f64,
    /// The alarm primitive fires at or below this fraction of the capacity.
    pub alarm_below: f64,
}

/// Navigation: the estimated position drifts while submerged; a position
/// fix at the surface resets it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Navigation {
    /// Drift of the estimate while submerged, metres per second.
    pub drift: f64,
    /// Direction of the drift, radians.
    pub direction: f64,
    /// Past this error (metres) the invalid-positioning primitive fires.
    pub bound: f64,
}

/// A world. See the [module documentation](self).
#[derive(Clone, Debug, PartialEq)]
pub struct World {
    pub start: Start,
    /// Where each named vehicle (mission) starts, when several run in this
    /// world (`[starts.NAME]`); the others start at [`World::start`].
    pub starts: BTreeMap<String, Start>,
    pub seabed: Seabed,
    /// Water current, m/s east and north.
    pub current: (f64, f64),
    pub cable: Option<Cable>,
    pub objects: Vec<Object>,
    pub wall: Option<Wall>,
    pub battery: Battery,
    pub navigation: Navigation,
    /// Values of symbolic call arguments for missions run in this world
    /// (`initial_pos`, `recovery_pos`...).
    pub symbols: BTreeMap<String, Value>,
}

impl Default for World {
    /// The default world: a flat seabed at [`DEFAULT_SEABED_DEPTH`] m, no
    /// current, cable, object or wall, a battery that lasts (1 kWh, 50 W,
    /// 100 J/m, alarm at 10 %), navigation without drift (bound 10 m).
    fn default() -> Self {
        World {
            start: Start { x: 0.0, y: 0.0, z: 0.0, yaw: 0.0 },
            starts: BTreeMap::new(),
            seabed: Seabed::Plane { depth: DEFAULT_SEABED_DEPTH, slope: (0.0, 0.0) },
            current: (0.0, 0.0),
            cable: None,
            objects: Vec::new(),
            wall: None,
            battery: Battery { capacity_wh: 1000.0, initial: 1.0, hotel_w: 50.0, per_metre_j: 100.0, alarm_below: 0.1 },
            navigation: Navigation { drift: 0.0, direction: 0.0, bound: 10.0 },
            symbols: BTreeMap::new(),
        }
    }
}

// --- The file ---------------------------------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct WorldFile {
    #[serde(default)]
    start: Option<StartFile>,
    #[serde(default)]
    starts: BTreeMap<String, StartFile>,
    #[serde(default)]
    seabed: Option<SeabedFile>,
    #[serde(default, deserialize_with = "opt_vec2")]
    current: Option<(f64, f64)>,
    #[serde(default)]
    cable: Option<CableFile>,
    #[serde(default)]
    objects: Vec<ObjectFile>,
    #[serde(default)]
    wall: Option<WallFile>,
    #[serde(default)]
    battery: Option<BatteryFile>,
    #[serde(default)]
    navigation: Option<NavFile>,
    #[serde(default)]
    symbols: BTreeMap<String, Value>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StartFile {
    #[serde(default, deserialize_with = "opt_vec2")]
    position: Option<(f64, f64)>,
    #[serde(default, deserialize_with = "opt_non_negative")]
    depth: Option<f64>,
    #[serde(default, deserialize_with = "opt_finite")]
    heading: Option<f64>,
}

impl StartFile {
    fn start(self) -> Start {
        let (x, y) = self.position.unwrap_or((0.0, 0.0));
        Start { x, y, z: self.depth.unwrap_or(0.0), yaw: self.heading.unwrap_or(0.0).to_radians() }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SeabedFile {
    #[serde(default, deserialize_with = "opt_non_negative")]
    depth: Option<f64>,
    #[serde(default, deserialize_with = "opt_vec2")]
    slope: Option<(f64, f64)>,
    #[serde(default)]
    grid: Option<GridFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GridFile {
    #[serde(default, deserialize_with = "opt_vec2")]
    origin: Option<(f64, f64)>,
    #[serde(deserialize_with = "positive")]
    cell: f64,
    #[serde(deserialize_with = "grid_depths")]
    depths: Vec<Vec<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CableFile {
    #[serde(default)]
    name: Option<String>,
    #[serde(deserialize_with = "polyline")]
    points: Vec<(f64, f64)>,
    #[serde(default)]
    buried: Vec<toml::Spanned<(f64, f64)>>,
    #[serde(default, deserialize_with = "opt_positive")]
    range: Option<f64>,
    #[serde(default, deserialize_with = "opt_positive")]
    max_altitude: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectFile {
    name: String,
    #[serde(deserialize_with = "vec2")]
    position: (f64, f64),
    #[serde(default, deserialize_with = "opt_positive")]
    range: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct WallFile {
    #[serde(deserialize_with = "vec2")]
    origin: (f64, f64),
    #[serde(default, deserialize_with = "opt_finite")]
    direction: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BatteryFile {
    #[serde(default, deserialize_with = "opt_positive")]
    capacity: Option<f64>,
    #[serde(default, deserialize_with = "opt_fraction")]
    initial: Option<f64>,
    #[serde(default, deserialize_with = "opt_non_negative")]
    hotel: Option<f64>,
    #[serde(default, deserialize_with = "opt_non_negative")]
    per_metre: Option<f64>,
    #[serde(default, deserialize_with = "opt_fraction")]
    alarm_below: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct NavFile {
    #[serde(default, deserialize_with = "opt_non_negative")]
    drift: Option<f64>,
    #[serde(default, deserialize_with = "opt_finite")]
    direction: Option<f64>,
    #[serde(default, deserialize_with = "opt_positive")]
    bound: Option<f64>,
}

fn check<E: de::Error>(v: f64, ok: bool, what: &str) -> Result<f64, E> {
    if v.is_finite() && ok {
        Ok(v)
    } else {
        Err(E::custom(format!("expected {what}, found {v}")))
    }
}

fn opt_finite<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    let v = f64::deserialize(d)?;
    check(v, true, "a number").map(Some)
}

fn opt_non_negative<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    let v = f64::deserialize(d)?;
    check(v, v >= 0.0, "a number ≥ 0").map(Some)
}

fn positive<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let v = f64::deserialize(d)?;
    check(v, v > 0.0, "a number > 0")
}

fn opt_positive<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    positive(d).map(Some)
}

fn opt_fraction<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    let v = f64::deserialize(d)?;
    check(v, (0.0..=1.0).contains(&v), "a fraction between 0 and 1").map(Some)
}

fn vec2<'de, D: Deserializer<'de>>(d: D) -> Result<(f64, f64), D::Error> {
    let v: Vec<f64> = Vec::deserialize(d)?;
    match v.as_slice() {
        [a, b] if a.is_finite() && b.is_finite() => Ok((*a, *b)),
        _ => Err(de::Error::custom(format!("expected two numbers [x, y], found {v:?}"))),
    }
}

fn opt_vec2<'de, D: Deserializer<'de>>(d: D) -> Result<Option<(f64, f64)>, D::Error> {
    vec2(d).map(Some)
}

fn polyline<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<(f64, f64)>, D::Error> {
    let v: Vec<Vec<f64>> = Vec::deserialize(d)?;
    let mut out = Vec::with_capacity(v.len());
    for p in &v {
        match p.as_slice() {
            [a, b] if a.is_finite() && b.is_finite() => out.push((*a, *b)),
            _ => return Err(de::Error::custom(format!("expected points [x, y], found {p:?}"))),
        }
    }
    if out.len() < 2 {
        return Err(de::Error::custom("a polyline needs at least two points"));
    }
    Ok(out)
}

fn grid_depths<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Vec<f64>>, D::Error> {
    let v: Vec<Vec<f64>> = Vec::deserialize(d)?;
    let cols = v.first().map_or(0, Vec::len);
    if cols == 0 {
        return Err(de::Error::custom("a grid needs at least one row of at least one depth"));
    }
    if let Some(r) = v.iter().position(|r| r.len() != cols) {
        return Err(de::Error::custom(format!(
            "every row of the grid has {cols} depths like the first; row {} has {}",
            r + 1,
            v[r].len()
        )));
    }
    if let Some(x) = v.iter().flatten().find(|x| !(x.is_finite() && **x >= 0.0)) {
        return Err(de::Error::custom(format!("depths are numbers ≥ 0, found {x}")));
    }
    Ok(v)
}

impl World {
    /// Parses a world file. Errors are `origin:line:col: message`.
    pub fn from_toml(text: &str, origin: &str) -> Result<World, String> {
        let f: WorldFile = toml::from_str(text).map_err(|e| toml_error(origin, text, &e))?;
        let d = World::default();
        let start = f.start.map_or(d.start, StartFile::start);
        let starts = f.starts.into_iter().map(|(k, s)| (k, s.start())).collect();
        let seabed = match f.seabed {
            None => d.seabed,
            Some(SeabedFile { grid: Some(g), .. }) => {
                Seabed::Grid { origin: g.origin.unwrap_or((0.0, 0.0)), cell: g.cell, depths: g.depths }
            }
            Some(s) => {
                Seabed::Plane { depth: s.depth.unwrap_or(DEFAULT_SEABED_DEPTH), slope: s.slope.unwrap_or((0.0, 0.0)) }
            }
        };
        let cable = match f.cable {
            None => None,
            Some(c) => {
                let mut cum = vec![0.0];
                for w in c.points.windows(2) {
                    let l = cum.last().copied().unwrap_or(0.0);
                    cum.push(l + (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1));
                }
                let len = *cum.last().unwrap_or(&0.0);
                let mut buried = Vec::new();
                for b in &c.buried {
                    let (a, z) = *b.get_ref();
                    if !(a.is_finite() && z.is_finite() && 0.0 <= a && a < z && z <= len) {
                        return Err(crate::error::located(
                            origin,
                            text,
                            b.span(),
                            &format!("a buried section is [from, to] in metres along the cable, 0 ≤ from < to ≤ {len:.1} (its length)"),
                        ));
                    }
                    buried.push((a, z));
                }
                Some(Cable {
                    name: c.name.unwrap_or_else(|| "cable".to_string()),
                    points: c.points,
                    cum,
                    buried,
                    range: c.range.unwrap_or(3.0),
                    max_altitude: c.max_altitude.unwrap_or(5.0),
                })
            }
        };
        let objects = f
            .objects
            .into_iter()
            .map(|o| Object { name: o.name, x: o.position.0, y: o.position.1, range: o.range.unwrap_or(3.0) })
            .collect();
        let wall = f.wall.map(|w| Wall { origin: w.origin, direction: w.direction.unwrap_or(0.0).to_radians() });
        let battery = match f.battery {
            None => d.battery,
            Some(b) => Battery {
                capacity_wh: b.capacity.unwrap_or(d.battery.capacity_wh),
                initial: b.initial.unwrap_or(d.battery.initial),
                hotel_w: b.hotel.unwrap_or(d.battery.hotel_w),
                per_metre_j: b.per_metre.unwrap_or(d.battery.per_metre_j),
                alarm_below: b.alarm_below.unwrap_or(d.battery.alarm_below),
            },
        };
        let navigation = match f.navigation {
            None => d.navigation,
            Some(n) => Navigation {
                drift: n.drift.unwrap_or(0.0),
                direction: n.direction.unwrap_or(0.0).to_radians(),
                bound: n.bound.unwrap_or(d.navigation.bound),
            },
        };
        Ok(World {
            start,
            starts,
            seabed,
            current: f.current.unwrap_or((0.0, 0.0)),
            cable,
            objects,
            wall,
            battery,
            navigation,
            symbols: f.symbols,
        })
    }

    /// Where the vehicle of `mission` starts: its `[starts.NAME]`, else
    /// `[start]`.
    pub fn start_of(&self, mission: &str) -> Start {
        self.starts.get(mission).copied().unwrap_or(self.start)
    }

    /// Reads and parses a world file.
    pub fn load(path: &Path) -> Result<World, String> {
        let text = mcl_net::input::read_source(path).map_err(|e| format!("world: {e}"))?;
        World::from_toml(&text, &path.display().to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn named_vehicles_start_where_the_world_says() {
        let w = World::from_toml("[start]\nposition = [1, 2]\n[starts.asc]\nposition = [5, 0]\nheading = 90\n", "w")
            .unwrap();
        assert_eq!((w.start_of("auv").x, w.start_of("auv").y), (1.0, 2.0));
        let asc = w.start_of("asc");
        assert_eq!((asc.x, asc.y, asc.z), (5.0, 0.0, 0.0));
        assert!((asc.yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let e = World::from_toml("[starts.asc]\npositon = [5, 0]\n", "w").unwrap_err();
        assert!(e.starts_with("w:2:1:"), "{e}");
    }

    #[test]
    fn seabed_plane_and_grid() {
        let w = World::from_toml("[seabed]\ndepth = 10\nslope = [0.1, 0]\n", "w").unwrap();
        assert_eq!(w.seabed.depth_at(10.0, 5.0), 11.0);
        assert_eq!(w.seabed.depth_at(-200.0, 0.0), 0.0);
        let w = World::from_toml("[seabed.grid]\ncell = 10\ndepths = [[10, 20], [30, 40]]\n", "w").unwrap();
        assert_eq!(w.seabed.depth_at(5.0, 0.0), 15.0);
        assert_eq!(w.seabed.depth_at(5.0, 5.0), 25.0);
        assert_eq!(w.seabed.depth_at(100.0, 100.0), 40.0);
    }

    #[test]
    fn cable_geometry() {
        let w = World::from_toml("[cable]\npoints = [[0, 0], [10, 0], [10, 10]]\nburied = [[5, 12]]\n", "w").unwrap();
        let c = w.cable.unwrap();
        assert_eq!(c.length(), 20.0);
        assert_eq!(c.point_at(15.0), (10.0, 5.0));
        assert!(c.is_buried(6.0) && !c.is_buried(13.0));
        let (s, d) = c.project(4.0, 1.0, 0.0, 20.0);
        assert!((s - 4.0).abs() < 1e-9 && (d - 1.0).abs() < 1e-9);
        // Seen beyond the buried part only.
        assert_eq!(c.visible_near(10.5, 8.0, 0.0), Some(18.0));
        assert_eq!(c.visible_near(7.5, -2.0, 0.0), None);
    }

    #[test]
    fn errors_are_located() {
        let e = World::from_toml("[seabed]\ndepth = -3\n", "w.toml").unwrap_err();
        assert!(e.starts_with("w.toml:2:9:"), "{e}");
        let e = World::from_toml("[cable]\npoints = [[0, 0], [10, 0]]\nburied = [[5, 30]]\n", "w.toml").unwrap_err();
        assert!(e.starts_with("w.toml:3:11:"), "{e}");
        let e = World::from_toml("[battery]\ncapacty = 3\n", "w.toml").unwrap_err();
        assert!(e.starts_with("w.toml:2:1:") && e.contains("capacty"), "{e}");
        let e = World::from_toml("[seabed.grid]\ncell = 1\ndepths = [[1, 2], [3]]\n", "w.toml").unwrap_err();
        assert!(e.starts_with("w.toml:3:10:"), "{e}");
    }
}
