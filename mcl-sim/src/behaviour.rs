//! Behaviours: what a primitive does to the simulated vehicle (seed 8.1,
//! 8.2, 8.4, 8.5), and when it ends. A behaviour is started with its
//! arguments ([`Behaviour::start`], which may fail at once: an unreachable
//! depth), asked at every step for the set-points of the degrees of freedom
//! it controls ([`Behaviour::command`]) and then whether it has ended
//! ([`Behaviour::check`]). Keep-mode behaviours never end on their own.

use std::collections::BTreeMap;
use std::f64::consts::{FRAC_PI_4, PI, TAU};

use serde::Deserialize;
use serde_json::Value;

use crate::model::Limits;
use crate::world::{Wall, World};

/// The behaviours a model can give a primitive.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// Line of sight to a way-point (surge, yaw); ok within `tolerance`.
    Goto,
    /// Line of sight through way-points in order; ok at the last one.
    Trajectory,
    /// Reach (and in `keep` mode hold) a depth (heave); fails at once if
    /// the seabed is shallower.
    Depth,
    /// Reach (and hold) an altitude over the seabed (heave); fails at once
    /// if the water is not that deep.
    Altitude,
    /// Turn to a heading (yaw) and hold it in `keep` mode.
    Heading,
    /// Rise to the surface (heave).
    Surface,
    /// Rise at the emergency ascent speed, thrusters stopped (every DOF).
    EmergencySurface,
    /// Hold the position and depth where it started; never ends.
    StationKeeping,
    /// A sinusoid of growing amplitude along a direction; ok once it has
    /// covered `length` metres along it.
    SearchPattern,
    /// Follow the cable; ok at its end, `lost` where it is buried or out of sight.
    CableTracking,
    /// Way-points (along the wall, depth) in front of the world's wall.
    WallInspection,
    /// Reach (and hold) a distance in front of the world's wall.
    Distance,
    /// Ok when its `target` is in sight: the cable (`"cable"` or the cable's
    /// `name`; a part not tracked yet) or an object (its `name`).
    Detector,
    /// Ok when the battery falls to its alarm level.
    Alarm,
    /// Ok when the navigation error passes the world's bound.
    InvalidPositioning,
    /// Ok after `duration` s at the surface; resets the navigation error.
    PositionFix,
    /// Ok after `duration` s (processing units: initialize, stop, send data).
    Timed,
    /// Never ends (take images).
    Forever,
    /// Line of sight to the nearest object of interest.
    GotoObject,
}

impl Kind {
    /// The name used in model files.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Goto => "goto",
            Kind::Trajectory => "trajectory",
            Kind::Depth => "depth",
            Kind::Altitude => "altitude",
            Kind::Heading => "heading",
            Kind::Surface => "surface",
            Kind::EmergencySurface => "emergency_surface",
            Kind::StationKeeping => "station_keeping",
            Kind::SearchPattern => "search_pattern",
            Kind::CableTracking => "cable_tracking",
            Kind::WallInspection => "wall_inspection",
            Kind::Distance => "distance",
            Kind::Detector => "detector",
            Kind::Alarm => "alarm",
            Kind::InvalidPositioning => "invalid_positioning",
            Kind::PositionFix => "position_fix",
            Kind::Timed => "timed",
            Kind::Forever => "forever",
            Kind::GotoObject => "goto_object",
        }
    }

    /// Its arguments (every one optional but the goal: `target`, `path`,
    /// `depth`, `altitude`, `angle`).
    pub fn args(self) -> &'static [&'static str] {
        match self {
            Kind::Goto => &["target", "speed", "tolerance", "timeout"],
            Kind::Trajectory => &["path", "speed", "tolerance", "timeout"],
            Kind::Depth => &["depth", "mode", "tolerance", "timeout"],
            Kind::Altitude => &["altitude", "mode", "tolerance", "timeout"],
            Kind::Heading => &["angle", "mode", "tolerance", "timeout"],
            Kind::Surface | Kind::EmergencySurface => &["tolerance", "timeout"],
            Kind::StationKeeping | Kind::Alarm | Kind::InvalidPositioning | Kind::Forever => &[],
            Kind::SearchPattern => &["direction", "amplitude", "growth", "wavelength", "length", "speed", "timeout"],
            Kind::CableTracking => &["speed", "lookahead", "tolerance", "timeout"],
            Kind::WallInspection => &["path", "distance", "speed", "tolerance", "timeout"],
            Kind::Distance => &["distance", "mode", "speed", "tolerance", "timeout"],
            Kind::Detector => &["target", "timeout"],
            Kind::PositionFix => &["duration", "timeout"],
            Kind::Timed => &["duration"],
            Kind::GotoObject => &["speed", "tolerance", "timeout"],
        }
    }
}

/// How a behaviour ended.
#[derive(Clone, Debug, PartialEq)]
pub enum End {
    /// Its goal is reached.
    Ok,
    /// It cannot be reached (why).
    Fail(String),
    /// A cable tracking lost the cable.
    Lost,
}

/// The vehicle as behaviours see it at one instant.
#[derive(Clone, Copy, Debug)]
pub struct Ctx<'a> {
    pub t: f64,
    /// The navigation's estimate of the position (what guidance uses).
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub yaw: f64,
    /// The seabed's depth under the vehicle.
    pub seabed: f64,
    /// Battery charge, fraction of the capacity.
    pub battery: f64,
    /// Navigation error, metres.
    pub nav_error: f64,
    /// The estimate minus the true position (what sensors that see the
    /// world, such as a camera or a sonar, are not fooled by).
    pub err: (f64, f64),
    pub world: &'a World,
    pub limits: &'a Limits,
    /// The objects this vehicle's detectors have found already (bit `i`:
    /// the world's object `i`; past the 64th none is remembered): a
    /// detector finds each object once.
    pub found: u64,
}

impl Ctx<'_> {
    /// The true position.
    pub fn true_pos(&self) -> (f64, f64) {
        (self.x - self.err.0, self.y - self.err.1)
    }
}

/// The vehicle is at the surface within this depth, metres.
pub const SURFACE: f64 = 0.2;

/// A horizontal set-point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Horizontal {
    /// Turn towards the point and go forward (line of sight), at `speed`.
    Los { x: f64, y: f64, speed: f64 },
    /// Move straight to the point whatever the heading (surge and sway).
    Holonomic { x: f64, y: f64, speed: f64 },
    /// Thrusters off.
    Stop,
}

/// The set-points a behaviour asks for, each with its priority (the
/// highest wins; among equals, the behaviour started last).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Command {
    pub horizontal: Option<(u8, Horizontal)>,
    /// Target depth and vertical speed.
    pub vertical: Option<(u8, f64, f64)>,
    /// Heading, radians.
    pub yaw: Option<(u8, f64)>,
}

/// Arguments of a behaviour: the model's fixed values and the action's
/// parameters, by behaviour argument name.
#[derive(Clone, Debug, Default)]
pub struct Args {
    pub values: BTreeMap<String, Value>,
}

impl Args {
    /// A number (a numeric string too); a symbol left without value is
    /// reported in `warn`.
    pub fn num(&self, k: &str, warn: &mut Vec<String>) -> Option<f64> {
        match self.values.get(k)? {
            Value::Number(n) => n.as_f64().filter(|x| x.is_finite()),
            Value::String(s) => match s.parse::<f64>() {
                Ok(x) if x.is_finite() => Some(x),
                _ => {
                    warn.push(format!(
                        "argument `{k}` is `{s}`, which has no numeric value (give the symbol a value in the model's or the world's [symbols], or with --set {s}=...)"
                    ));
                    None
                }
            },
            v => {
                warn.push(format!("argument `{k}` is {v}, not a number"));
                None
            }
        }
    }

    /// A string.
    pub fn text(&self, k: &str) -> Option<&str> {
        self.values.get(k).and_then(Value::as_str)
    }

    /// A point [x, y] (a third number is ignored).
    pub fn point(&self, k: &str, warn: &mut Vec<String>) -> Option<(f64, f64)> {
        let v = self.values.get(k)?;
        let p = as_point(v);
        if p.is_none() {
            warn.push(format!("argument `{k}` is {v}, not a point [x, y] (a symbol without value?)"));
        }
        p
    }

    /// A list of points [[x, y], ...].
    pub fn path(&self, k: &str, warn: &mut Vec<String>) -> Option<Vec<(f64, f64)>> {
        let v = self.values.get(k)?;
        let p = v.as_array().and_then(|a| a.iter().map(as_point).collect::<Option<Vec<_>>>()).filter(|p| !p.is_empty());
        if p.is_none() {
            warn.push(format!("argument `{k}` is {v}, not a list of points [[x, y], ...] (a symbol without value?)"));
        }
        p
    }
}

fn as_point(v: &Value) -> Option<(f64, f64)> {
    let a = v.as_array()?;
    if !(2..=3).contains(&a.len()) {
        return None;
    }
    Some((a[0].as_f64()?, a[1].as_f64()?))
}

/// Angle wrapped to (-π, π].
pub fn wrap(a: f64) -> f64 {
    let r = a.rem_euclid(TAU);
    if r > PI {
        r - TAU
    } else {
        r
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Goal {
    Point(f64, f64),
    Path(Vec<(f64, f64)>, usize),
    Depth(f64),
    Altitude(f64),
    Heading(f64),
    Surface,
    Emergency,
    Station(f64, f64, f64),
    Search { ox: f64, oy: f64, dir: f64, amplitude: f64, growth: f64, wavelength: f64, length: f64 },
    Cable { s: f64, lookahead: f64 },
    Wall { wall: Wall, path: Vec<(f64, f64)>, next: usize, standoff: f64 },
    Distance(Wall, f64),
    Detect(String),
    Alarm,
    InvalidPositioning,
    Fix { duration: f64, since: Option<f64> },
    Timed(f64),
    Forever,
}

/// A running behaviour. See the [module documentation](self).
#[derive(Clone, Debug, PartialEq)]
pub struct Behaviour {
    pub kind: Kind,
    /// When it started.
    pub started: f64,
    /// Keep mode: never ends on its own.
    pub keep: bool,
    timeout: Option<f64>,
    tolerance: f64,
    speed: f64,
    goal: Goal,
    /// Way-points it was given (drawn on the trajectory picture).
    pub waypoints: Vec<(f64, f64)>,
}

/// The wall of the world, or the default one (along x through the origin).
fn wall_of(w: &World) -> Wall {
    w.wall.unwrap_or(Wall { origin: (0.0, 0.0), direction: 0.0 })
}

impl Behaviour {
    /// Starts a behaviour at `ctx`; `Err` when it fails at once (`Fail`
    /// with why). `progress`: how far along the cable has been tracked.
    pub fn start(
        kind: Kind,
        args: &Args,
        ctx: &Ctx<'_>,
        progress: f64,
        warn: &mut Vec<String>,
    ) -> Result<Behaviour, End> {
        let l = ctx.limits;
        let keep = match args.text("mode") {
            None | Some("achieve") => false,
            Some("keep") => true,
            Some(m) => {
                warn.push(format!("mode `{m}` is neither \"achieve\" nor \"keep\": achieving"));
                false
            }
        };
        let timeout = args.num("timeout", warn).filter(|t| *t > 0.0);
        let speed_max = match kind {
            Kind::WallInspection | Kind::Distance => l.sway,
            _ => l.surge,
        };
        let speed = args.num("speed", warn).filter(|s| *s > 0.0).map_or(speed_max, |s| s.min(speed_max));
        let default_tol = match kind {
            Kind::Heading => 2.0,
            Kind::Depth | Kind::Altitude | Kind::Surface | Kind::EmergencySurface => SURFACE,
            _ => 1.0,
        };
        let tolerance = args.num("tolerance", warn).filter(|t| *t > 0.0).unwrap_or(default_tol);
        let tolerance = if kind == Kind::Heading { tolerance.to_radians() } else { tolerance };
        let missing = |what: &str| End::Fail(format!("no {what} (argument missing or without value)"));
        let mut waypoints = Vec::new();
        let goal = match kind {
            Kind::Goto => {
                let p = args.point("target", warn).ok_or_else(|| missing("target way-point"))?;
                waypoints.push(p);
                Goal::Point(p.0, p.1)
            }
            Kind::GotoObject => {
                let o = ctx
                    .world
                    .objects
                    .iter()
                    .min_by(|a, b| (a.x - ctx.x).hypot(a.y - ctx.y).total_cmp(&(b.x - ctx.x).hypot(b.y - ctx.y)))
                    .ok_or_else(|| End::Fail("the world has no object of interest".into()))?;
                waypoints.push((o.x, o.y));
                Goal::Point(o.x, o.y)
            }
            Kind::Trajectory => {
                let p = args.path("path", warn).ok_or_else(|| missing("path"))?;
                waypoints.extend(&p);
                Goal::Path(p, 0)
            }
            Kind::Depth => {
                let d = args.num("depth", warn).ok_or_else(|| missing("depth"))?;
                if d < 0.0 || d > ctx.seabed {
                    return Err(End::Fail(format!(
                        "depth {d} m cannot be reached (the seabed is at {:.1} m)",
                        ctx.seabed
                    )));
                }
                Goal::Depth(d)
            }
            Kind::Altitude => {
                let a = args.num("altitude", warn).ok_or_else(|| missing("altitude"))?;
                if a < 0.0 || a > ctx.seabed {
                    return Err(End::Fail(format!(
                        "altitude {a} m cannot be reached (the water is {:.1} m deep)",
                        ctx.seabed
                    )));
                }
                Goal::Altitude(a)
            }
            Kind::Heading => Goal::Heading(args.num("angle", warn).ok_or_else(|| missing("angle"))?.to_radians()),
            Kind::Surface => Goal::Surface,
            Kind::EmergencySurface => Goal::Emergency,
            Kind::StationKeeping => Goal::Station(ctx.x, ctx.y, ctx.z),
            Kind::SearchPattern => Goal::Search {
                ox: ctx.x,
                oy: ctx.y,
                dir: args.num("direction", warn).map_or(ctx.yaw, f64::to_radians),
                amplitude: args.num("amplitude", warn).unwrap_or(2.0).max(0.0),
                growth: args.num("growth", warn).unwrap_or(0.1).max(0.0),
                wavelength: args.num("wavelength", warn).filter(|w| *w > 0.0).unwrap_or(20.0),
                length: args.num("length", warn).filter(|w| *w > 0.0).unwrap_or(100.0),
            },
            Kind::CableTracking => {
                let c = ctx.world.cable.as_ref().ok_or_else(|| End::Fail("the world has no cable".into()))?;
                let (tx, ty) = ctx.true_pos();
                let Some(s) = c.visible_near(tx, ty, progress) else { return Err(End::Lost) };
                if !(ctx.z > SURFACE && ctx.seabed - ctx.z <= c.max_altitude) {
                    return Err(End::Lost);
                }
                Goal::Cable { s, lookahead: args.num("lookahead", warn).filter(|x| *x > 0.0).unwrap_or(3.0) }
            }
            Kind::WallInspection => {
                let path = args.path("path", warn).ok_or_else(|| missing("path"))?;
                let wall = wall_of(ctx.world);
                let standoff = args.num("distance", warn).filter(|d| *d > 0.0).unwrap_or(1.5);
                waypoints.extend(path.iter().map(|&(u, _)| wall.point(u, standoff)));
                Goal::Wall { wall, path, next: 0, standoff }
            }
            Kind::Distance => {
                let d = args.num("distance", warn).filter(|d| *d > 0.0).ok_or_else(|| missing("distance"))?;
                Goal::Distance(wall_of(ctx.world), d)
            }
            Kind::Detector => Goal::Detect(args.text("target").unwrap_or("cable").to_string()),
            Kind::Alarm => Goal::Alarm,
            Kind::InvalidPositioning => Goal::InvalidPositioning,
            Kind::PositionFix => {
                Goal::Fix { duration: args.num("duration", warn).unwrap_or(10.0).max(0.0), since: None }
            }
            Kind::Timed => Goal::Timed(ctx.t + args.num("duration", warn).unwrap_or(1.0).max(0.0)),
            Kind::Forever => Goal::Forever,
        };
        Ok(Behaviour { kind, started: ctx.t, keep, timeout, tolerance, speed, goal, waypoints })
    }

    /// The set-points it asks for at `ctx`.
    pub fn command(&self, ctx: &Ctx<'_>) -> Command {
        let l = ctx.limits;
        let mut c = Command::default();
        match &self.goal {
            Goal::Point(x, y) => c.horizontal = Some((2, Horizontal::Los { x: *x, y: *y, speed: self.speed })),
            Goal::Path(p, next) => {
                let (x, y) = p[(*next).min(p.len() - 1)];
                c.horizontal = Some((2, Horizontal::Los { x, y, speed: self.speed }));
            }
            Goal::Depth(d) => c.vertical = Some((2, *d, l.heave)),
            Goal::Altitude(a) => c.vertical = Some((2, (ctx.seabed - a).max(0.0), l.heave)),
            Goal::Heading(h) => c.yaw = Some((1, *h)),
            Goal::Surface => c.vertical = Some((5, 0.0, l.heave)),
            Goal::Emergency => {
                c.horizontal = Some((10, Horizontal::Stop));
                c.vertical = Some((10, 0.0, l.emergency_ascent));
            }
            Goal::Station(x, y, z) => {
                c.horizontal = Some((1, Horizontal::Holonomic { x: *x, y: *y, speed: l.sway }));
                c.vertical = Some((1, *z, l.heave));
            }
            Goal::Search { ox, oy, dir, amplitude, growth, wavelength, .. } => {
                let (s, co) = dir.sin_cos();
                let along = (ctx.x - ox) * co + (ctx.y - oy) * s;
                let u = along.max(0.0) + 3.0;
                let lat = (amplitude + growth * u) * (TAU * u / wavelength).sin();
                let (x, y) = (ox + u * co - lat * s, oy + u * s + lat * co);
                c.horizontal = Some((2, Horizontal::Los { x, y, speed: self.speed }));
            }
            Goal::Cable { s, lookahead } => {
                if let Some(cable) = &ctx.world.cable {
                    // Seen by the vehicle's sensors: a true point, steered to in the navigation's frame.
                    let (x, y) = cable.point_at(s + lookahead);
                    let (x, y) = (x + ctx.err.0, y + ctx.err.1);
                    c.horizontal = Some((2, Horizontal::Los { x, y, speed: self.speed }));
                }
            }
            Goal::Wall { wall, path, next, standoff } => {
                let (u, d) = path[(*next).min(path.len() - 1)];
                let (x, y) = wall.point(u, *standoff);
                c.horizontal = Some((3, Horizontal::Holonomic { x, y, speed: self.speed }));
                c.vertical = Some((3, d.max(0.0).min(ctx.seabed), l.heave));
                c.yaw = Some((0, wall.facing()));
            }
            Goal::Distance(wall, d) => {
                // Measured by the sonar: the true position.
                let (tx, ty) = ctx.true_pos();
                let (u, _) = wall.coords(tx, ty);
                let (x, y) = wall.point(u, *d);
                let (x, y) = (x + ctx.err.0, y + ctx.err.1);
                c.horizontal = Some((1, Horizontal::Holonomic { x, y, speed: self.speed }));
                c.yaw = Some((0, wall.facing()));
            }
            Goal::Detect(_)
            | Goal::Alarm
            | Goal::InvalidPositioning
            | Goal::Fix { .. }
            | Goal::Timed(_)
            | Goal::Forever => {}
        }
        c
    }

    /// Whether it has ended at `ctx` (after the step). `progress`: how far
    /// along the cable has been tracked (a cable tracking moves it on).
    pub fn check(&mut self, ctx: &Ctx<'_>, progress: &mut f64) -> Option<End> {
        let end = self.goal_end(ctx, progress);
        if self.keep && end == Some(End::Ok) {
            return None;
        }
        if end.is_some() {
            return end;
        }
        match self.timeout {
            Some(to) if !self.keep && ctx.t - self.started >= to - 1e-9 => {
                Some(End::Fail(format!("its time-out of {to} s passed")))
            }
            _ => None,
        }
    }

    fn goal_end(&mut self, ctx: &Ctx<'_>, progress: &mut f64) -> Option<End> {
        let tol = self.tolerance;
        let near = |x: f64, y: f64| (x - ctx.x).hypot(y - ctx.y) <= tol;
        let ok = |b: bool| b.then_some(End::Ok);
        match &mut self.goal {
            Goal::Point(x, y) => ok(near(*x, *y)),
            Goal::Path(p, next) => {
                while *next < p.len() && near(p[*next].0, p[*next].1) {
                    *next += 1;
                }
                ok(*next == p.len())
            }
            Goal::Depth(d) => ok((ctx.z - *d).abs() <= tol),
            Goal::Altitude(a) => ok(((ctx.seabed - ctx.z) - *a).abs() <= tol),
            Goal::Heading(h) => ok(wrap(ctx.yaw - *h).abs() <= tol),
            Goal::Surface | Goal::Emergency => ok(ctx.z <= tol),
            Goal::Station(..) | Goal::Forever => None,
            Goal::Search { ox, oy, dir, length, .. } => {
                let (s, c) = dir.sin_cos();
                ok((ctx.x - *ox) * c + (ctx.y - *oy) * s >= *length)
            }
            Goal::Cable { s, .. } => {
                let cable = ctx.world.cable.as_ref()?;
                let (tx, ty) = ctx.true_pos();
                let (ns, d) = cable.project(tx, ty, *s - 2.0, *s + 10.0);
                *s = ns.max(*s);
                *progress = progress.max(*s);
                if *s >= cable.length() - tol {
                    Some(End::Ok)
                } else if cable.is_buried(*s) || d > cable.range || ctx.seabed - ctx.z > cable.max_altitude {
                    Some(End::Lost)
                } else {
                    None
                }
            }
            Goal::Wall { wall, path, next, standoff } => {
                while *next < path.len() {
                    let (u, d) = path[*next];
                    let (x, y) = wall.point(u, *standoff);
                    if (x - ctx.x).hypot(y - ctx.y).hypot(d.max(0.0) - ctx.z) <= tol {
                        *next += 1;
                    } else {
                        break;
                    }
                }
                ok(*next == path.len())
            }
            Goal::Distance(wall, d) => {
                let (tx, ty) = ctx.true_pos();
                ok((wall.coords(tx, ty).1 - *d).abs() <= tol)
            }
            Goal::Detect(target) => {
                if ctx.z <= SURFACE {
                    return None;
                }
                let cable = ctx.world.cable.as_ref().filter(|c| target == "cable" || *target == c.name);
                let (tx, ty) = ctx.true_pos();
                if let Some(c) = cable {
                    let seen =
                        ctx.seabed - ctx.z <= c.max_altitude && c.visible_near(tx, ty, *progress + 1.0).is_some();
                    ok(seen)
                } else {
                    ok(self.found_object(ctx).is_some())
                }
            }
            Goal::Alarm => ok(ctx.battery <= ctx.world.battery.alarm_below),
            Goal::InvalidPositioning => ok(ctx.nav_error > ctx.world.navigation.bound),
            Goal::Fix { duration, since } => {
                if ctx.z > SURFACE {
                    *since = None;
                    return None;
                }
                let s = *since.get_or_insert(ctx.t);
                ok(ctx.t - s >= *duration - 1e-9)
            }
            Goal::Timed(until) => ok(ctx.t >= *until - 1e-9),
        }
    }

    /// The object a detector sees at `ctx`: one of its target's name, in
    /// range and not found before.
    pub fn found_object(&self, ctx: &Ctx<'_>) -> Option<usize> {
        let Goal::Detect(target) = &self.goal else { return None };
        let (tx, ty) = ctx.true_pos();
        ctx.world.objects.iter().enumerate().position(|(i, o)| {
            &o.name == target && (o.x - tx).hypot(o.y - ty) <= o.range && (i >= 64 || ctx.found & (1 << i) == 0)
        })
    }

    /// A position fix that has just ended resets the navigation.
    pub fn is_fix(&self) -> bool {
        matches!(self.goal, Goal::Fix { .. })
    }
}

/// Line of sight: surge towards (x, y) when the heading error is under 45°
/// (slower as it grows), turning in place otherwise (seed 8.1, trajectory:
/// "it stops and turns over itself until heading the next way-point").
pub fn los_surge(yaw: f64, dx: f64, dy: f64, speed: f64) -> f64 {
    let e = wrap(dy.atan2(dx) - yaw).abs();
    if e < FRAC_PI_4 {
        speed * e.cos()
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Model;
    use serde_json::json;

    fn ctx<'a>(world: &'a World, limits: &'a Limits, z: f64) -> Ctx<'a> {
        Ctx {
            t: 0.0,
            x: 0.0,
            y: 0.0,
            z,
            yaw: 0.0,
            seabed: world.seabed.depth_at(0.0, 0.0),
            battery: 1.0,
            nav_error: 0.0,
            err: (0.0, 0.0),
            world,
            limits,
            found: 0,
        }
    }

    fn args(v: Value) -> Args {
        Args { values: serde_json::from_value(v).unwrap() }
    }

    #[test]
    fn unreachable_depth_and_altitude_fail_at_once() {
        let (w, l) = (World::default(), Model::default_model().limits);
        let c = ctx(&w, &l, 0.0);
        let mut warn = Vec::new();
        let e = Behaviour::start(Kind::Depth, &args(json!({"depth": 50})), &c, 0.0, &mut warn).unwrap_err();
        assert!(matches!(e, End::Fail(ref m) if m.contains("seabed is at 20.0 m")), "{e:?}");
        let e = Behaviour::start(Kind::Altitude, &args(json!({"altitude": 25})), &c, 0.0, &mut warn).unwrap_err();
        assert!(matches!(e, End::Fail(_)));
        assert!(Behaviour::start(Kind::Depth, &args(json!({"depth": 5})), &c, 0.0, &mut warn).is_ok());
    }

    #[test]
    fn keep_mode_never_ends_and_achieve_ends_ok() {
        let (w, l) = (World::default(), Model::default_model().limits);
        let c = ctx(&w, &l, 5.0);
        let mut warn = Vec::new();
        let mut keep =
            Behaviour::start(Kind::Depth, &args(json!({"depth": 5, "mode": "keep", "timeout": 1})), &c, 0.0, &mut warn)
                .unwrap();
        let mut ach = Behaviour::start(Kind::Depth, &args(json!({"depth": 5})), &c, 0.0, &mut warn).unwrap();
        let mut p = 0.0;
        let later = Ctx { t: 100.0, ..c };
        assert_eq!(keep.check(&later, &mut p), None);
        assert_eq!(ach.check(&c, &mut p), Some(End::Ok));
        assert_eq!(keep.command(&c).vertical, Some((2, 5.0, l.heave)));
    }

    #[test]
    fn own_timeout_fails_the_primitive() {
        let (w, l) = (World::default(), Model::default_model().limits);
        let c = ctx(&w, &l, 0.0);
        let mut warn = Vec::new();
        let mut g = Behaviour::start(Kind::Goto, &args(json!({"target": [100, 0], "timeout": 10})), &c, 0.0, &mut warn)
            .unwrap();
        let mut p = 0.0;
        assert_eq!(g.check(&Ctx { t: 9.0, ..c }, &mut p), None);
        assert!(matches!(g.check(&Ctx { t: 10.0, ..c }, &mut p), Some(End::Fail(_))));
    }

    #[test]
    fn symbols_without_value_are_reported() {
        let (w, l) = (World::default(), Model::default_model().limits);
        let c = ctx(&w, &l, 0.0);
        let mut warn = Vec::new();
        let e = Behaviour::start(Kind::Goto, &args(json!({"target": "initial_pos"})), &c, 0.0, &mut warn).unwrap_err();
        assert!(matches!(e, End::Fail(_)));
        assert!(warn[0].contains("initial_pos"), "{warn:?}");
    }

    #[test]
    fn detectors() {
        let w = World::from_toml(
            "[cable]\npoints = [[0, 0], [50, 0]]\nburied = [[10, 20]]\n[[objects]]\nname = \"red box\"\nposition = [0, 2]\n[battery]\nalarm_below = 0.2\n[navigation]\nbound = 5\n",
            "w",
        )
        .unwrap();
        let l = Model::default_model().limits;
        let c = Ctx { z: 18.0, ..ctx(&w, &l, 18.0) };
        let mut warn = Vec::new();
        let mut p = 0.0;
        let mut cable =
            Behaviour::start(Kind::Detector, &args(json!({"target": "cable"})), &c, 0.0, &mut warn).unwrap();
        assert_eq!(cable.check(&c, &mut p), Some(End::Ok));
        // Inside the buried section nothing is seen; beyond what was tracked neither.
        assert_eq!(cable.check(&Ctx { x: 15.0, ..c }, &mut p), None);
        let mut tracked = 30.0;
        assert_eq!(cable.check(&Ctx { x: 25.0, ..c }, &mut tracked), None);
        let mut obj =
            Behaviour::start(Kind::Detector, &args(json!({"target": "red box"})), &c, 0.0, &mut warn).unwrap();
        assert_eq!(obj.check(&c, &mut p), Some(End::Ok));
        assert_eq!(obj.found_object(&c), Some(0));
        assert_eq!(obj.check(&Ctx { found: 1, ..c }, &mut p), None, "an object is found once");
        let mut alarm = Behaviour::start(Kind::Alarm, &Args::default(), &c, 0.0, &mut warn).unwrap();
        assert_eq!(alarm.check(&Ctx { battery: 0.3, ..c }, &mut p), None);
        assert_eq!(alarm.check(&Ctx { battery: 0.2, ..c }, &mut p), Some(End::Ok));
        let mut nav = Behaviour::start(Kind::InvalidPositioning, &Args::default(), &c, 0.0, &mut warn).unwrap();
        assert_eq!(nav.check(&Ctx { nav_error: 5.0, ..c }, &mut p), None);
        assert_eq!(nav.check(&Ctx { nav_error: 5.1, ..c }, &mut p), Some(End::Ok));
    }

    #[test]
    fn cable_tracking_follows_then_loses_then_ends() {
        let w = World::from_toml("[cable]\npoints = [[0, 0], [50, 0]]\nburied = [[10, 20]]\n", "w").unwrap();
        let l = Model::default_model().limits;
        let c = ctx(&w, &l, 18.0);
        let mut warn = Vec::new();
        let mut p = 0.0;
        let mut t = Behaviour::start(Kind::CableTracking, &Args::default(), &c, 0.0, &mut warn).unwrap();
        assert!(matches!(t.command(&c).horizontal, Some((2, Horizontal::Los { x, .. }))if x == 3.0));
        assert_eq!(t.check(&Ctx { x: 5.0, ..c }, &mut p), None);
        assert_eq!(p, 5.0);
        assert_eq!(t.check(&Ctx { x: 10.5, ..c }, &mut p), Some(End::Lost));
        let c2 = Ctx { x: 21.0, ..c };
        let mut t = Behaviour::start(Kind::CableTracking, &Args::default(), &c2, p, &mut warn).unwrap();
        assert_eq!(t.check(&Ctx { x: 29.0, ..c }, &mut p), None);
        assert_eq!(t.check(&Ctx { x: 38.0, ..c }, &mut p), None);
        assert_eq!(t.check(&Ctx { x: 45.0, ..c }, &mut p), None);
        assert_eq!(t.check(&Ctx { x: 49.5, ..c }, &mut p), Some(End::Ok));
        // Too high over the seabed to see it.
        assert_eq!(
            Behaviour::start(Kind::CableTracking, &Args::default(), &Ctx { z: 2.0, ..c2 }, 0.0, &mut warn),
            Err(End::Lost)
        );
    }

    #[test]
    fn trajectory_passes_way_points_in_order() {
        let (w, l) = (World::default(), Model::default_model().limits);
        let c = ctx(&w, &l, 0.0);
        let mut warn = Vec::new();
        let mut p = 0.0;
        let mut t =
            Behaviour::start(Kind::Trajectory, &args(json!({"path": [[0, 0], [10, 0], [10, 10]]})), &c, 0.0, &mut warn)
                .unwrap();
        assert_eq!(t.check(&c, &mut p), None);
        assert!(matches!(t.command(&c).horizontal, Some((_, Horizontal::Los { x, y, .. })) if x == 10.0 && y == 0.0));
        // Jumping to the last point does not skip the second.
        assert_eq!(t.check(&Ctx { x: 10.0, y: 10.0, ..c }, &mut p), None);
        assert_eq!(t.check(&Ctx { x: 10.0, y: 0.0, ..c }, &mut p), None);
        assert_eq!(t.check(&Ctx { x: 10.0, y: 10.0, ..c }, &mut p), Some(End::Ok));
    }

    #[test]
    fn surface_heading_fix_timed_and_search() {
        let (w, l) = (World::default(), Model::default_model().limits);
        let c = ctx(&w, &l, 3.0);
        let mut warn = Vec::new();
        let mut p = 0.0;
        let mut s = Behaviour::start(Kind::Surface, &Args::default(), &c, 0.0, &mut warn).unwrap();
        assert_eq!(s.check(&c, &mut p), None);
        assert_eq!(s.check(&Ctx { z: 0.0, ..c }, &mut p), Some(End::Ok));
        let mut e = Behaviour::start(Kind::EmergencySurface, &Args::default(), &c, 0.0, &mut warn).unwrap();
        assert_eq!(e.command(&c).horizontal, Some((10, Horizontal::Stop)));
        assert_eq!(e.check(&Ctx { z: 0.1, ..c }, &mut p), Some(End::Ok));
        let mut h = Behaviour::start(Kind::Heading, &args(json!({"angle": 90})), &c, 0.0, &mut warn).unwrap();
        assert_eq!(h.check(&c, &mut p), None);
        assert_eq!(h.check(&Ctx { yaw: 1.56, ..c }, &mut p), Some(End::Ok));
        let mut f = Behaviour::start(Kind::PositionFix, &args(json!({"duration": 5})), &c, 0.0, &mut warn).unwrap();
        assert_eq!(f.check(&Ctx { t: 10.0, ..c }, &mut p), None);
        assert_eq!(f.check(&Ctx { t: 11.0, z: 0.0, ..c }, &mut p), None);
        assert_eq!(f.check(&Ctx { t: 16.0, z: 0.0, ..c }, &mut p), Some(End::Ok));
        let mut tm = Behaviour::start(Kind::Timed, &args(json!({"duration": 4})), &c, 0.0, &mut warn).unwrap();
        assert_eq!(tm.check(&Ctx { t: 3.9, ..c }, &mut p), None);
        assert_eq!(tm.check(&Ctx { t: 4.0, ..c }, &mut p), Some(End::Ok));
        let mut fo = Behaviour::start(Kind::Forever, &Args::default(), &c, 0.0, &mut warn).unwrap();
        assert_eq!(fo.check(&Ctx { t: 1e6, ..c }, &mut p), None);
        let mut sp = Behaviour::start(Kind::SearchPattern, &args(json!({"length": 30})), &c, 0.0, &mut warn).unwrap();
        assert_eq!(sp.check(&Ctx { x: 29.0, y: 4.0, ..c }, &mut p), None);
        assert_eq!(sp.check(&Ctx { x: 30.0, y: -4.0, ..c }, &mut p), Some(End::Ok));
        let mut sk = Behaviour::start(Kind::StationKeeping, &Args::default(), &c, 0.0, &mut warn).unwrap();
        assert_eq!(sk.check(&Ctx { t: 1e6, ..c }, &mut p), None);
        assert!(
            matches!(sk.command(&Ctx { x: 3.0, ..c }).horizontal, Some((1, Horizontal::Holonomic { x, .. })) if x == 0.0)
        );
    }

    #[test]
    fn goto_object_goes_to_the_nearest_object() {
        let w = World::from_toml(
            "[[objects]]\nname = \"a\"\nposition = [30, 0]\n[[objects]]\nname = \"b\"\nposition = [0, 10]\n",
            "w",
        )
        .unwrap();
        let l = Model::default_model().limits;
        let c = ctx(&w, &l, 0.0);
        let mut warn = Vec::new();
        let mut p = 0.0;
        let mut g = Behaviour::start(Kind::GotoObject, &Args::default(), &c, 0.0, &mut warn).unwrap();
        assert_eq!(g.waypoints, vec![(0.0, 10.0)]);
        assert_eq!(g.check(&Ctx { y: 9.5, ..c }, &mut p), Some(End::Ok));
        let none = World::default();
        let c = ctx(&none, &l, 0.0);
        assert!(matches!(Behaviour::start(Kind::GotoObject, &Args::default(), &c, 0.0, &mut warn), Err(End::Fail(_))));
    }

    #[test]
    fn wall_inspection_and_distance() {
        let w = World::from_toml("[wall]\norigin = [0, 10]\ndirection = 0\n", "w").unwrap();
        let l = Model::default_model().limits;
        let c = ctx(&w, &l, 0.0);
        let mut warn = Vec::new();
        let mut p = 0.0;
        // The water is north of the wall: 1.5 m in front of it is y = 11.5.
        let mut wi =
            Behaviour::start(Kind::WallInspection, &args(json!({"path": [[0, 1], [0, 5]]})), &c, 0.0, &mut warn)
                .unwrap();
        let cmd = wi.command(&c);
        assert!(matches!(cmd.horizontal, Some((3, Horizontal::Holonomic { x, y, .. })) if x == 0.0 && y == 11.5));
        assert_eq!(cmd.vertical.map(|v| v.1), Some(1.0));
        assert_eq!(wi.check(&Ctx { y: 11.5, z: 1.0, ..c }, &mut p), None);
        assert_eq!(wi.check(&Ctx { y: 11.5, z: 5.0, ..c }, &mut p), Some(End::Ok));
        let mut d = Behaviour::start(Kind::Distance, &args(json!({"distance": 2})), &c, 0.0, &mut warn).unwrap();
        assert_eq!(d.check(&Ctx { y: 10.5, ..c }, &mut p), None);
        assert_eq!(d.check(&Ctx { y: 12.0, ..c }, &mut p), Some(End::Ok));
    }
}
