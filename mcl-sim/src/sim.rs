//! A simulated vehicle: the [`VirtualVehicle`] that the virtual-time driver
//! plays a mission against, instead of the mock. Sans-IO and deterministic.
//!
//! * **Actions.** An action whose command is one of its primitive's
//!   `start` commands (`enable`) starts the primitive's behaviour with the
//!   action's parameters (restarts it if it runs); a `stop` command
//!   (`disable`) stops it and drops any answer of it not yet taken (an
//!   aborted primitive says nothing, `docs/aac-protocol.md` §11). A
//!   primitive the model does not know never answers (one warning).
//! * **Time.** The simulation advances by the model's fixed step while a
//!   behaviour runs ([`SimVehicle::next_deadline`] is then the next step);
//!   `pop_due(now)` integrates up to `now` and returns what the step raised,
//!   if anything. With nothing running the vehicle rests and has no deadline.
//! * **Answers.** A behaviour that ends raises its primitive's `ok`, `fail`
//!   (or `lost`) event, naming the action that started it (`activation`).
//! * **Perceptions** (names from the model): the navigation quality (in
//!   tenths), whether the cable is in sight (while submerged), the battery
//!   charge (every 5 %), each sent when it changes.
//! * **Poses:** one per `pose_period` while the vehicle moves, one at every
//!   action and every event it raises.
//! * **A scenario** (`--scenario`) applies on top: its `[[events]]` and
//!   `[[perceptions]]` at fixed times are sent, and its perceptions `after`
//!   an event once the vehicle sends that event; a task rule that gives an
//!   outcome (or `probabilities` to draw it from), most specific first
//!   (activation, call label, task: [`Scenario::rule_for`]), ends the
//!   primitive that way after its delay (`never`: the primitive does not
//!   end on its own), whatever the behaviour does meanwhile.
//!
//! Several vehicles share one [`World`] (an `Arc`): each has its own
//! `SimVehicle` (position, battery, navigation, cable progress).

use std::collections::{BTreeMap, HashMap, HashSet};
use std::sync::Arc;

use mcl_runtime::link::{Action, Inbound};
use mcl_runtime::mock::CallInfo;
use mcl_runtime::scenario::{OutcomeRule, Scenario};
use mcl_runtime::vehicle::{Pose, VirtualVehicle};
use serde_json::Value;

use crate::behaviour::{los_surge, Args, Behaviour, Command, Ctx, End, Horizontal, Kind, SURFACE};
use crate::model::{ArgSource, Model};
use crate::world::{Start, World};

/// A pose and the task that moved the vehicle there (an index in
/// [`Track::labels`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Track {
    pub points: Vec<(Pose, usize)>,
    /// Task names (the first, `-`, for no task).
    pub labels: Vec<String>,
    /// Way-points given to the behaviours, in order.
    pub waypoints: Vec<(f64, f64)>,
}

#[derive(Clone, Debug)]
struct Run {
    seq: u64,
    primitive: String,
    /// The task (or the primitive) that started it: the colour of the path.
    label: String,
    b: Behaviour,
    /// A scenario's rule: end this way at this time (`Never`: do not end).
    forced: Option<Forced>,
}

/// How a scenario's rule ends a primitive, whatever its behaviour does.
#[derive(Clone, Debug, PartialEq)]
struct Forced {
    at: f64,
    outcome: OutcomeRule,
    /// The rule's `event`, raised instead of the primitive's.
    event: Option<String>,
}

#[derive(Clone, Debug)]
struct Pending {
    msg: Inbound,
    /// The primitive whose answer this is.
    owner: Option<String>,
}

/// A simulated vehicle. See the [module documentation](self).
#[derive(Clone, Debug)]
pub struct SimVehicle {
    model: Arc<Model>,
    world: Arc<World>,
    scenario: Scenario,
    t: f64,
    x: f64,
    y: f64,
    z: f64,
    yaw: f64,
    energy_wh: f64,
    nav_err: (f64, f64),
    progress: f64,
    /// Objects found by its detectors ([`Ctx::found`]).
    found: u64,
    running: Vec<Run>,
    agenda: BTreeMap<(u64, u64), Pending>,
    next_id: u64,
    last_seq: u64,
    poses: Vec<Pose>,
    last_pose: Option<Pose>,
    track: Track,
    warnings: Vec<String>,
    warned: HashSet<String>,
    activations: HashMap<String, u32>,
    sent_quality: Option<i64>,
    sent_cable: Option<bool>,
    sent_battery: Option<i64>,
    /// Position (m), depth (dm), alarm and cable tracked (m) last sent.
    sent_position: (Option<i64>, Option<i64>, Option<i64>),
    sent_alarm: Option<bool>,
    sent_tracked: Option<i64>,
    initialised: bool,
    /// The calls of the mission (labels of the scenario's rules), by call site.
    calls: HashMap<u32, CallInfo>,
    /// State of the scenario's random draws (probabilities, delay ranges).
    rng: u64,
    /// Times each event was sent (perceptions scripted `after` an event).
    sent_events: HashMap<String, u32>,
}

fn key(t: f64, id: u64) -> (u64, u64) {
    (t.max(0.0).to_bits(), id)
}

impl SimVehicle {
    /// A vehicle of `model` at the world's start, with `scenario` on top.
    pub fn new(model: Arc<Model>, world: Arc<World>, scenario: Scenario) -> SimVehicle {
        let s = world.start;
        let energy_wh = world.battery.capacity_wh * world.battery.initial;
        SimVehicle {
            model,
            scenario,
            t: 0.0,
            x: s.x,
            y: s.y,
            z: s.z,
            yaw: s.yaw,
            energy_wh,
            nav_err: (0.0, 0.0),
            progress: 0.0,
            found: 0,
            running: Vec::new(),
            agenda: BTreeMap::new(),
            next_id: 0,
            last_seq: 0,
            poses: Vec::new(),
            last_pose: None,
            track: Track { labels: vec!["-".into()], ..Track::default() },
            warnings: Vec::new(),
            warned: HashSet::new(),
            activations: HashMap::new(),
            sent_quality: None,
            sent_cable: None,
            sent_battery: None,
            sent_position: (None, None, None),
            sent_alarm: None,
            sent_tracked: None,
            initialised: false,
            calls: HashMap::new(),
            rng: 0x73_696d,
            sent_events: HashMap::new(),
            world,
        }
    }

    /// The same vehicle knowing the calls of the mission `net` (so that the
    /// scenario's `[tasks.T.label.L]` rules apply), its scenario's random
    /// draws seeded by the scenario's seed, else `seed` (as the mock's).
    pub fn with_program(mut self, net: &mcl_net::Net, seed: u64) -> SimVehicle {
        self.calls = mcl_runtime::mock::tables_of(net).1;
        self.rng = self.scenario.seed.unwrap_or(seed) ^ 0x73_696d; // "sim"
        self
    }

    /// A uniform draw in [0, 1) (splitmix64).
    fn uniform(&mut self) -> f64 {
        self.rng = self.rng.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.rng;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Schedules the perceptions the scenario scripts `after` the event of
    /// `msg` (sent at `t`), if it is one.
    fn sent(&mut self, t: f64, msg: &Inbound) {
        let Inbound::Event { event, .. } = msg else { return };
        let n = self.sent_events.entry(event.clone()).or_insert(0);
        *n += 1;
        let n = *n;
        let due: Vec<(f64, Inbound)> = self
            .scenario
            .perceptions
            .iter()
            .filter(|p| p.after.as_deref() == Some(event.as_str()) && p.occurrence.is_none_or(|o| o == n))
            .map(|p| {
                let at = t + p.delay.unwrap_or(0.0);
                (at, Inbound::Perception { name: p.name.clone(), value: p.value.clone(), n: None })
            })
            .collect();
        for (at, m) in due {
            self.schedule(at, m, None);
        }
    }

    /// The same vehicle at `s` instead of the world's start (one of
    /// several in the world, [`World::start_of`]); before it runs.
    pub fn starting_at(mut self, s: Start) -> SimVehicle {
        (self.x, self.y, self.z, self.yaw) = (s.x, s.y, s.z, s.yaw);
        self
    }

    /// The world it moves in.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// Its path so far, for [`crate::trajectory::svg`].
    pub fn track(&self) -> &Track {
        &self.track
    }

    /// Its true pose now.
    pub fn pose(&self) -> Pose {
        Pose { t: self.t, x: self.x, y: self.y, z: self.z, yaw: self.yaw }
    }

    /// Battery charge, fraction of the capacity.
    pub fn battery(&self) -> f64 {
        self.energy_wh / self.world.battery.capacity_wh
    }

    fn warn_once(&mut self, w: String) {
        if self.warned.insert(w.clone()) {
            self.warnings.push(format!("sim: {w}"));
        }
    }

    fn schedule(&mut self, t: f64, msg: Inbound, owner: Option<String>) {
        self.next_id += 1;
        self.agenda.insert(key(t, self.next_id), Pending { msg, owner });
    }

    fn ctx(&self) -> Ctx<'_> {
        self.ctx_with(&self.world, &self.model)
    }

    /// The behaviours' view, borrowing the world and model given (clones
    /// of the vehicle's `Arc`s) instead of the vehicle.
    fn ctx_with<'a>(&self, world: &'a World, model: &'a Model) -> Ctx<'a> {
        Ctx {
            t: self.t,
            x: self.x + self.nav_err.0,
            y: self.y + self.nav_err.1,
            z: self.z,
            yaw: self.yaw,
            seabed: self.world.seabed.depth_at(self.x, self.y),
            battery: self.battery(),
            nav_error: self.nav_err.0.hypot(self.nav_err.1),
            err: self.nav_err,
            world,
            limits: &model.limits,
            found: self.found,
        }
    }

    /// Records the pose now (at an action or an event), or when the period
    /// has passed and the vehicle moved (`periodic`).
    fn record_pose(&mut self, periodic: bool) {
        let p = self.pose();
        if let Some(last) = self.last_pose {
            if p.t <= last.t + 1e-12 {
                // Same instant: nothing moved.
                return;
            }
            if periodic {
                let moved =
                    (p.x - last.x).abs() + (p.y - last.y).abs() + (p.z - last.z).abs() + (p.yaw - last.yaw).abs()
                        > 1e-9;
                if p.t - last.t < self.model.limits.pose_period - 1e-9 || !moved {
                    return;
                }
            }
        }
        let label = self.motion_label();
        self.poses.push(p);
        self.track.points.push((p, label));
        self.last_pose = Some(p);
    }

    /// The task that moves the vehicle now: the owner of the horizontal
    /// set-point, else of the vertical one.
    fn motion_label(&mut self) -> usize {
        let ctx = self.ctx();
        let mut best: Option<(u8, usize, bool)> = None;
        for (i, r) in self.running.iter().enumerate() {
            let c = r.b.command(&ctx);
            let cand = c.horizontal.map(|h| (h.0, true)).or(c.vertical.map(|v| (v.0, false)));
            if let Some((p, h)) = cand {
                let better = match best {
                    None => true,
                    Some((bp, _, bh)) => (h, p) >= (bh, bp),
                };
                if better {
                    best = Some((p, i, h));
                }
            }
        }
        let Some((_, i, _)) = best else { return 0 };
        let name = self.running[i].label.clone();
        match self.track.labels.iter().position(|l| *l == name) {
            Some(k) => k,
            None => {
                self.track.labels.push(name);
                self.track.labels.len() - 1
            }
        }
    }

    /// Ends run `i` with `end`: raises its event now (`event`, a scenario's, instead of the model's).
    fn end_run(&mut self, i: usize, end: End, event: Option<String>) {
        let r = self.running.remove(i);
        let pm = &self.model.primitives[&r.primitive];
        let (model_event, what) = match &end {
            End::Ok => (pm.ok.clone(), "ok".to_string()),
            End::Fail(why) => (pm.fail.clone(), format!("fail ({why})")),
            End::Lost => (pm.lost.clone().or(pm.fail.clone()), "lost (the cable is out of sight)".to_string()),
        };
        let event = event.or(model_event);
        if r.b.is_fix() && end == End::Ok {
            self.nav_err = (0.0, 0.0);
        }
        if end == End::Ok {
            if let Some(k) = r.b.found_object(&self.ctx()).filter(|k| *k < 64) {
                self.found |= 1 << k;
            }
        }
        match event {
            Some(event) => {
                self.schedule(
                    self.t,
                    Inbound::Event { event, activation: Some(r.seq), n: None },
                    Some(r.primitive.clone()),
                );
            }
            None => self.warn_once(format!(
                "primitive `{}` ended {what} but the vehicle model names no event for that",
                r.primitive
            )),
        }
        self.record_pose(false);
    }

    /// One integration step of `dt` seconds, then the behaviours' checks
    /// and the perceptions.
    fn step(&mut self, dt: f64) {
        let ctx = self.ctx();
        let mut cmd = Command::default();
        // The owner of each degree of freedom: highest priority, then the latest started.
        for r in &self.running {
            let c = r.b.command(&ctx);
            if c.horizontal.is_some() && c.horizontal.map(|h| h.0) >= cmd.horizontal.map(|h| h.0) {
                cmd.horizontal = c.horizontal;
            }
            if c.vertical.is_some() && c.vertical.map(|v| v.0) >= cmd.vertical.map(|v| v.0) {
                cmd.vertical = c.vertical;
            }
            if c.yaw.is_some() && c.yaw.map(|v| v.0) >= cmd.yaw.map(|v| v.0) {
                cmd.yaw = c.yaw;
            }
        }
        let l = self.model.limits;
        let (ex, ey) = self.nav_err;
        // Set-points are in the navigation's frame: the true target is off by its error.
        let (mut vx, mut vy) = self.world.current;
        let mut desired_yaw = cmd.yaw.map(|y| y.1);
        match cmd.horizontal.map(|h| h.1) {
            Some(Horizontal::Los { x, y, speed }) => {
                let (dx, dy) = (x - ex - self.x, y - ey - self.y);
                let d = dx.hypot(dy);
                if d > 1e-6 {
                    desired_yaw = Some(dy.atan2(dx));
                    let s = los_surge(self.yaw, dx, dy, speed).min(d / dt);
                    vx += s * self.yaw.cos();
                    vy += s * self.yaw.sin();
                }
            }
            Some(Horizontal::Holonomic { x, y, speed }) => {
                // The controller cancels the current.
                let (dx, dy) = (x - ex - self.x, y - ey - self.y);
                let d = dx.hypot(dy);
                let s = speed.min(d / dt);
                (vx, vy) = if d > 1e-9 { (s * dx / d, s * dy / d) } else { (0.0, 0.0) };
            }
            Some(Horizontal::Stop) | None => {}
        }
        if let Some(want) = desired_yaw {
            let e = crate::behaviour::wrap(want - self.yaw);
            let m = l.turn_rate * dt;
            self.yaw = crate::behaviour::wrap(self.yaw + e.clamp(-m, m));
        }
        let (ox, oy, oz) = (self.x, self.y, self.z);
        self.x += vx * dt;
        self.y += vy * dt;
        if let Some((_, zt, speed)) = cmd.vertical {
            let m = speed * dt;
            self.z += (zt - self.z).clamp(-m, m);
        }
        self.z = if l.surface { 0.0 } else { self.z.clamp(0.0, self.world.seabed.depth_at(self.x, self.y)) };
        // Energy: hotel load plus distance through the water (the current's drift costs nothing).
        let (cx, cy) = self.world.current;
        let through_water = (self.x - ox - cx * dt).hypot(self.y - oy - cy * dt).hypot(self.z - oz);
        let b = self.world.battery;
        self.energy_wh = (self.energy_wh - (b.hotel_w * dt + b.per_metre_j * through_water) / 3600.0).max(0.0);
        let n = self.world.navigation;
        if self.z > SURFACE && n.drift > 0.0 {
            self.nav_err.0 += n.drift * dt * n.direction.cos();
            self.nav_err.1 += n.drift * dt * n.direction.sin();
        }
        self.t += dt;
        self.check_runs();
        self.perceptions();
        self.record_pose(true);
    }

    fn check_runs(&mut self) {
        let (world, model) = (Arc::clone(&self.world), Arc::clone(&self.model));
        let mut i = 0;
        while i < self.running.len() {
            let ctx = self.ctx_with(&world, &model);
            let mut progress = self.progress;
            let forced = self.running[i].forced.clone();
            let due = forced.as_ref().is_some_and(|f| self.t >= f.at - 1e-9);
            let (end, event) = match forced {
                Some(f) if f.outcome == OutcomeRule::Ok && due => (Some(End::Ok), f.event),
                Some(f) if f.outcome == OutcomeRule::Fail && due => {
                    (Some(End::Fail("the scenario makes it fail".into())), f.event)
                }
                // Not yet due, or never: the behaviour does not end it meanwhile.
                Some(_) => (None, None),
                None => (self.running[i].b.check(&ctx, &mut progress), None),
            };
            self.progress = progress;
            match end {
                Some(e) => self.end_run(i, e, event),
                None => i += 1,
            }
        }
    }

    fn perceptions(&mut self) {
        let (world, model) = (Arc::clone(&self.world), Arc::clone(&self.model));
        let p = model.perceptions.clone();
        let ctx = self.ctx_with(&world, &model);
        let (tx, ty) = ctx.true_pos();
        if let Some(name) = p.position_quality {
            let q = ((1.0 - ctx.nav_error / self.world.navigation.bound).max(0.0) * 10.0).round() as i64;
            if self.sent_quality != Some(q) {
                self.sent_quality = Some(q);
                self.schedule(self.t, Inbound::Perception { name, value: Value::from(q as f64 / 10.0), n: None }, None);
            }
        }
        if let (Some(name), Some(c)) = (p.cable_seen, &self.world.cable) {
            let seen = ctx.z > SURFACE
                && ctx.seabed - ctx.z <= c.max_altitude
                && c.visible_near(tx, ty, self.progress).is_some();
            if self.sent_cable != Some(seen) && (seen || self.sent_cable.is_some()) {
                self.sent_cable = Some(seen);
                self.schedule(
                    self.t,
                    Inbound::Perception { name, value: flag(seen, p.flags_as_numbers), n: None },
                    None,
                );
            }
        }
        let (ex, ey) = (ctx.x.round() as i64, ctx.y.round() as i64);
        let ez = (ctx.z * 10.0).round() as i64;
        let sent = self.sent_position;
        for (name, v, last, scale) in [(p.x, ex, sent.0, 1.0), (p.y, ey, sent.1, 1.0), (p.depth, ez, sent.2, 10.0)] {
            if let Some(name) = name.filter(|_| last != Some(v)) {
                self.schedule(
                    self.t,
                    Inbound::Perception { name, value: Value::from(v as f64 / scale), n: None },
                    None,
                );
            }
        }
        self.sent_position = (Some(ex), Some(ey), Some(ez));
        if let Some(name) = p.alarm {
            let alarm = self.battery() <= self.world.battery.alarm_below;
            if self.sent_alarm != Some(alarm) {
                self.sent_alarm = Some(alarm);
                self.schedule(
                    self.t,
                    Inbound::Perception { name, value: flag(alarm, p.flags_as_numbers), n: None },
                    None,
                );
            }
        }
        if let (Some(name), Some(_)) = (p.cable_tracked, &self.world.cable) {
            let m = self.progress.round() as i64;
            if m > 0 && self.sent_tracked != Some(m) {
                self.sent_tracked = Some(m);
                self.schedule(self.t, Inbound::Perception { name, value: Value::from(m as f64), n: None }, None);
            }
        }
        if let Some(name) = p.battery {
            let b = (self.battery() * 20.0).ceil() as i64;
            if self.sent_battery != Some(b) {
                self.sent_battery = Some(b);
                self.schedule(self.t, Inbound::Perception { name, value: Value::from(b as f64 / 20.0), n: None }, None);
            }
        }
    }

    /// Integrates up to `to`, by steps; with `stop_early`, stops after a
    /// step that raised an event or a perception.
    fn advance(&mut self, to: f64, stop_early: bool) {
        let step = self.model.limits.step;
        while self.t < to - 1e-9 {
            if self.running.is_empty() {
                // At rest: nothing changes but the clock and the hotel load.
                let dt = to - self.t;
                self.energy_wh = (self.energy_wh - self.world.battery.hotel_w * dt / 3600.0).max(0.0);
                self.t = to;
                break;
            }
            let before = self.agenda.len();
            self.step(step.min(to - self.t));
            if stop_early && self.agenda.len() > before {
                break;
            }
        }
    }

    fn start(&mut self, now: f64, a: &Action) {
        let Some(pm) = self.model.primitives.get(&a.primitive).cloned() else {
            self.warn_once(format!(
                "the vehicle model has no primitive `{}`: `{}` does nothing and the primitive never answers",
                a.primitive, a.action
            ));
            return;
        };
        let label = a.task.clone().unwrap_or_else(|| a.primitive.clone());
        if pm.stop.contains(&a.command) {
            self.running.retain(|r| r.primitive != a.primitive);
            self.agenda.retain(|_, p| p.owner.as_deref() != Some(a.primitive.as_str()));
            return;
        }
        if !pm.start.contains(&a.command) {
            self.warn_once(format!(
                "primitive `{}`: the vehicle model neither starts nor stops it on command `{}` (ignored)",
                a.primitive, a.command
            ));
            return;
        }
        // (Re)start.
        self.running.retain(|r| r.primitive != a.primitive);
        self.agenda.retain(|_, p| p.owner.as_deref() != Some(a.primitive.as_str()));
        let mut args = Args::default();
        for (name, src) in &pm.args {
            let v = match src {
                ArgSource::Value(v) => Some(v.clone()),
                ArgSource::Param(p) => match a.params.get(p) {
                    Some(v) => Some(resolve(v, &self.model.symbols, &self.world.symbols)),
                    None => {
                        self.warn_once(format!(
                            "primitive `{}`: action `{}` has no parameter `{p}` (behaviour argument `{name}`)",
                            a.primitive, a.action
                        ));
                        None
                    }
                },
            };
            if let Some(v) = v {
                args.values.insert(name.clone(), v);
            }
        }
        let mut warn = Vec::new();
        let started = Behaviour::start(pm.behaviour, &args, &self.ctx(), self.progress, &mut warn);
        for w in warn {
            self.warn_once(format!("primitive `{}` ({}): {w}", a.primitive, pm.behaviour.name()));
        }
        let forced = self.forced(&label, a.call_site, now);
        let started = match started {
            Ok(_)
                if self.model.limits.surface
                    && matches!(pm.behaviour, Kind::Depth | Kind::Altitude | Kind::WallInspection) =>
            {
                Err(End::Fail("a surface vehicle does not dive".into()))
            }
            s => s,
        };
        match started {
            Ok(b) => {
                self.track.waypoints.extend(&b.waypoints);
                self.running.push(Run { seq: a.seq, primitive: a.primitive.clone(), label, b, forced });
            }
            Err(end) => {
                // Ends at once: as if it had run for no time.
                let b = Behaviour::start(Kind::Forever, &Args::default(), &self.ctx(), 0.0, &mut Vec::new())
                    .expect("forever always starts");
                self.running.push(Run { seq: a.seq, primitive: a.primitive.clone(), label, b, forced: None });
                let i = self.running.len() - 1;
                self.end_run(i, end, None);
            }
        }
    }

    /// The scenario's rule for the next activation of `task` (called at
    /// `call_site`): its outcome (given, or drawn from its probabilities)
    /// and when (its delay, drawn from a range); none when the rule leaves
    /// the outcome to the behaviour.
    fn forced(&mut self, task: &str, call_site: Option<u32>, now: f64) -> Option<Forced> {
        let n = self.activations.entry(task.to_string()).or_insert(0);
        *n += 1;
        let n = *n;
        let label = call_site.and_then(|c| self.calls.get(&c)).and_then(|c| c.label.clone());
        let rule = self.scenario.rule_for(task, label.as_deref(), n);
        let outcome = match (rule.outcome, rule.probabilities) {
            (Some(o), _) => o,
            (None, Some(p)) => p.pick(self.uniform()),
            (None, None) => return None,
        };
        let delay = match rule.delay {
            Some(d) => d.seconds(|| self.uniform()),
            None => self.scenario.default_duration.unwrap_or(mcl_runtime::mock::DEFAULT_DURATION),
        };
        Some(Forced { at: now + delay, outcome, event: rule.event })
    }
}

/// A parameter that names a symbol takes the symbol's value (the world's
/// over the model's); the player has already resolved `--set` and the
/// scenario's symbols.
fn resolve(v: &Value, model: &BTreeMap<String, Value>, world: &BTreeMap<String, Value>) -> Value {
    match v {
        Value::String(s) => world.get(s).or_else(|| model.get(s)).cloned().unwrap_or_else(|| v.clone()),
        _ => v.clone(),
    }
}

/// A true/false perception's value: 1/0 with `numbers`.
fn flag(b: bool, numbers: bool) -> Value {
    if numbers {
        Value::from(if b { 1.0 } else { 0.0 })
    } else {
        Value::Bool(b)
    }
}

impl VirtualVehicle for SimVehicle {
    fn initial(&mut self) -> Vec<(f64, Inbound)> {
        if self.initialised {
            return Vec::new();
        }
        self.initialised = true;
        self.record_pose(false);
        let mut out: Vec<(f64, Inbound)> = Vec::new();
        for e in &self.scenario.events {
            out.push((e.at, Inbound::Event { event: e.event.clone(), activation: None, n: None }));
        }
        for p in &self.scenario.perceptions {
            // Those `after` an event are scheduled when the vehicle sends it.
            if let Some(at) = p.at {
                out.push((at, Inbound::Perception { name: p.name.clone(), value: p.value.clone(), n: None }));
            }
        }
        out.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (t, m) in &out {
            self.schedule(*t, m.clone(), None);
        }
        out
    }

    fn on_action(&mut self, now: f64, a: &Action) {
        if a.seq <= self.last_seq {
            return;
        }
        self.last_seq = a.seq;
        self.advance(now, false);
        self.start(now, a);
        self.record_pose(false);
    }

    fn next_deadline(&self) -> Option<f64> {
        let due = self.agenda.keys().next().map(|&(k, _)| f64::from_bits(k));
        let step = (!self.running.is_empty()).then(|| {
            let forced =
                self.running.iter().filter_map(|r| r.forced.as_ref()).filter(|f| f.outcome != OutcomeRule::Never);
            forced.map(|f| f.at.max(self.t)).fold(self.t + self.model.limits.step, f64::min)
        });
        match (due, step) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    fn pop_due(&mut self, now: f64) -> Option<(f64, Inbound)> {
        let first = self.agenda.keys().next().map(|&(k, _)| f64::from_bits(k));
        let target = match first {
            Some(f) if f <= now => f,
            _ => now,
        };
        if target > self.t {
            self.advance(target, true);
        }
        let (&k, _) = self.agenda.iter().next()?;
        let t = f64::from_bits(k.0);
        if t > now {
            return None;
        }
        let p = self.agenda.remove(&k)?;
        self.sent(t, &p.msg);
        Some((t, p.msg))
    }

    fn take_delivered(&mut self, msg: &Inbound) -> bool {
        let Some(k) = self.agenda.iter().find(|(_, p)| &p.msg == msg).map(|(k, _)| *k) else { return false };
        if let Some(p) = self.agenda.remove(&k) {
            self.sent(f64::from_bits(k.0), &p.msg);
        }
        true
    }

    fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }

    fn take_poses(&mut self) -> Vec<Pose> {
        std::mem::take(&mut self.poses)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn action(seq: u64, name: &str, primitive: &str, command: &str, params: Value) -> Action {
        let params: mcl_runtime::params::Params = serde_json::from_value(params).unwrap();
        Action {
            seq,
            action: name.into(),
            primitive: primitive.into(),
            command: command.into(),
            params,
            task: None,
            call_site: None,
        }
    }

    /// Runs the vehicle alone until it sends something or `until`.
    fn run_until(v: &mut SimVehicle, until: f64) -> Option<(f64, Inbound)> {
        while let Some(d) = v.next_deadline() {
            if d > until {
                return None;
            }
            if let Some(m) = v.pop_due(d) {
                return Some(m);
            }
        }
        None
    }

    fn vehicle(world: &str) -> SimVehicle {
        SimVehicle::new(
            Arc::new(Model::default_model()),
            Arc::new(World::from_toml(world, "w").unwrap()),
            Scenario::default(),
        )
    }

    fn event(m: Option<(f64, Inbound)>) -> (f64, String) {
        match m {
            Some((t, Inbound::Event { event, .. })) => (t, event),
            other => panic!("expected an event, got {other:?}"),
        }
    }

    #[test]
    fn goto_takes_distance_over_speed_and_answers_its_activation() {
        let mut v = vehicle("");
        v.initial();
        v.on_action(0.0, &action(1, "enableGoto", "GotoPrimitive", "enable", json!({"way-point": [50, 0]})));
        let (t, e) = loop {
            match run_until(&mut v, 1000.0) {
                Some((t, Inbound::Event { event, activation, .. })) => {
                    assert_eq!(activation, Some(1));
                    break (t, event);
                }
                Some(_) => continue, // perceptions
                None => panic!("no answer"),
            }
        };
        assert_eq!(e, "eventGotoOk");
        // 49 m (1 m tolerance) at the bundled model's 1 m/s top speed.
        assert!((t - 49.0).abs() < 0.5, "t = {t}");
        let poses = v.take_poses();
        assert!(poses.len() >= 49, "{}", poses.len());
        assert!(poses.windows(2).all(|w| w[1].t > w[0].t && w[1].t - w[0].t <= 1.0 + 1e-9));
        assert_eq!(v.next_deadline(), None, "at rest, nothing scheduled");
    }

    #[test]
    fn perceptions_for_a_planner_position_depth_and_cable_tracked_as_numbers() {
        let model = Model::from_toml(
            "base = \"default\"\n[perceptions]\nx = \"x\"\ny = \"y\"\ndepth = \"z\"\nalarm = \"alarm\"\ncable_seen = \"seen\"\ncable_tracked = \"tracked\"\nbattery = \"\"\nflags_as_numbers = true\n",
            "m",
        )
        .unwrap();
        let world =
            World::from_toml("[seabed]\ndepth = 5\n[cable]\npoints = [[0, 0], [30, 0]]\nburied = [[20, 25]]\n", "w")
                .unwrap();
        let mut v = SimVehicle::new(Arc::new(model), Arc::new(world), Scenario::default());
        v.initial();
        v.on_action(0.0, &action(1, "enableDepth", "DepthPrimitive", "enable", json!({"depth": 3, "mode": "keep"})));
        let mut got: Vec<(f64, String, Value)> = Vec::new();
        for (until, then) in [(15.0, true), (200.0, false)] {
            while let Some(m) = run_until(&mut v, until) {
                if let (t, Inbound::Perception { name, value, .. }) = m {
                    got.push((t, name, value));
                }
            }
            if then {
                let track = action(2, "enableCableTracking", "CableTrackingPrimitive", "enable", json!({}));
                v.on_action(until, &track);
            }
        }
        let last = |n: &str| got.iter().rev().find(|g| g.1 == n).map(|g| g.2.clone());
        assert_eq!(last("z"), Some(json!(3.0)), "depth in tenths of a metre");
        assert!(got.iter().filter(|g| g.1 == "x").count() >= 19, "x in whole metres as the vehicle moves");
        assert_eq!(last("alarm"), Some(json!(0.0)));
        // Seen (1), then lost (0) where the cable is buried, 20 m tracked by then.
        let seen: Vec<&Value> = got.iter().filter(|g| g.1 == "seen").map(|g| &g.2).collect();
        assert_eq!(seen, [&json!(1.0), &json!(0.0)]);
        assert_eq!(last("tracked"), Some(json!(20.0)));
        assert!(got.iter().all(|g| g.1 != "battery"));
    }

    #[test]
    fn disable_stops_and_silences_the_primitive() {
        let mut v = vehicle("");
        v.initial();
        v.on_action(
            0.0,
            &action(1, "enableDepth", "DepthPrimitive", "enable", json!({"depth": 10, "mode": "achieve"})),
        );
        let _ = run_until(&mut v, 5.0);
        v.on_action(5.0, &action(2, "disableDepth", "DepthPrimitive", "disable", json!({})));
        let z = v.pose().z;
        assert!(z > 0.0 && z < 10.0);
        while let Some(m) = run_until(&mut v, 100.0) {
            assert!(!matches!(m.1, Inbound::Event { .. }), "{m:?}");
        }
        assert_eq!(v.pose().z, z, "nothing moves it any more");
    }

    #[test]
    fn unreachable_depth_fails_at_once() {
        let mut v = vehicle("[seabed]\ndepth = 8\n");
        v.initial();
        v.on_action(3.0, &action(1, "enableDepth", "DepthPrimitive", "enable", json!({"depth": 10, "mode": "keep"})));
        assert_eq!(event(v.pop_due(3.0)), (3.0, "eventDepthFail".into()));
    }

    #[test]
    fn a_surface_vehicle_does_not_dive() {
        let model = Model::from_toml("base = \"default\"\n[vehicle]\nsurface = true\n", "m").unwrap();
        let mut v = SimVehicle::new(Arc::new(model), Arc::new(World::default()), Scenario::default());
        v.initial();
        v.on_action(1.0, &action(1, "enableDepth", "DepthPrimitive", "enable", json!({"depth": 5, "mode": "keep"})));
        assert_eq!(event(v.pop_due(1.0)), (1.0, "eventDepthFail".into()));
        v.on_action(1.0, &action(2, "enableGoto", "GotoPrimitive", "enable", json!({"way-point": [10, 0]})));
        while let Some(m) = run_until(&mut v, 100.0) {
            if matches!(m.1, Inbound::Event { .. }) {
                break;
            }
        }
        let p = v.pose();
        assert!((p.x - 9.0).abs() < 0.2 && p.z == 0.0, "{p:?}");
    }

    #[test]
    fn battery_alarm_at_the_predicted_time() {
        // 10 Wh, alarm at 50 %: 5 Wh at 100 W of hotel load is 180 s at rest.
        let mut v = vehicle("[battery]\ncapacity = 10\nhotel = 100\nper_metre = 0\nalarm_below = 0.5\n");
        v.initial();
        v.on_action(0.0, &action(1, "enableAlarm", "AlarmPrimitive", "enable", json!({})));
        let e = loop {
            match run_until(&mut v, 1000.0) {
                Some((t, Inbound::Event { event, .. })) => break (t, event),
                Some(_) => continue,
                None => panic!("no alarm"),
            }
        };
        assert_eq!(e.1, "eventAlarmOk");
        assert!((e.0 - 180.0).abs() < 0.11, "{}", e.0);
    }

    #[test]
    fn unknown_primitive_warns_once() {
        let mut v = vehicle("");
        v.on_action(0.0, &action(1, "enableX", "XPrimitive", "enable", json!({})));
        v.on_action(1.0, &action(2, "enableX", "XPrimitive", "enable", json!({})));
        let w = v.take_warnings();
        assert_eq!(w.len(), 1);
        assert!(w[0].contains("XPrimitive"));
        assert_eq!(v.next_deadline(), None);
    }

    #[test]
    fn navigation_drifts_and_a_fix_resets_it() {
        let mut v = vehicle("[navigation]\ndrift = 0.1\nbound = 3\n");
        v.initial();
        v.on_action(0.0, &action(1, "enableInvalidPositioning", "InvalidPositioningPrimitive", "enable", json!({})));
        v.on_action(0.0, &action(2, "enableDepth", "DepthPrimitive", "enable", json!({"depth": 5, "mode": "keep"})));
        let mut got = None;
        while let Some(m) = run_until(&mut v, 1000.0) {
            if let (t, Inbound::Event { event, .. }) = m {
                got = Some((t, event));
                break;
            }
        }
        let (t, e) = got.expect("invalid positioning");
        assert_eq!(e, "eventInvalidPositioningOk");
        // Submerged after ~0.7 s (0.2 m at 0.3 m/s), then 3 m at 0.1 m/s.
        assert!((t - 30.7).abs() < 0.3, "{t}");
        v.on_action(t, &action(3, "disableDepth", "DepthPrimitive", "disable", json!({})));
        v.on_action(t, &action(4, "enableSurface", "SurfacePrimitive", "enable", json!({})));
        assert_eq!(
            event(loop {
                match run_until(&mut v, 1000.0) {
                    Some(m @ (_, Inbound::Event { .. })) => break Some(m),
                    Some(_) => continue,
                    None => break None,
                }
            })
            .1,
            "eventSurfaceOk"
        );
        let t = v.pose().t;
        v.on_action(t, &action(5, "enableGetPositionFix", "GetPositionFixPrimitive", "enable", json!({})));
        loop {
            match run_until(&mut v, 1000.0) {
                Some((_, Inbound::Event { event, .. })) => {
                    assert_eq!(event, "eventGetPositionFixOk");
                    break;
                }
                Some(_) => continue,
                None => panic!("no fix"),
            }
        }
        assert_eq!(v.nav_err, (0.0, 0.0));
    }
}
