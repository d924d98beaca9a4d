//! The vehicle model file (TOML): the vehicle's limits, and for each AAC
//! primitive the behaviour that simulates it, where its arguments come from
//! (the action's parameters or fixed values) and which events it raises.
//! With it any vehicle file can be simulated. Format: `docs/simulator.md`.

use std::collections::BTreeMap;
use std::path::Path;

use serde::de::{self, Deserializer};
use serde::Deserialize;
use serde_json::Value;

use crate::behaviour::Kind;
use crate::error::{located, toml_error};

/// The model of `examples/vehicle.mcl`, used when no model is given.
pub const DEFAULT_MODEL: &str = include_str!("../../examples/sim/vehicle-model.toml");

/// The vehicle's kinematic limits and the simulation's clock.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Top forward speed, m/s.
    pub surge: f64,
    /// Top sideways speed (station keeping, wall inspection), m/s.
    pub sway: f64,
    /// Top vertical speed, m/s.
    pub heave: f64,
    /// Top turn rate, rad/s.
    pub turn_rate: f64,
    /// Ascent speed of an emergency surface, m/s.
    pub emergency_ascent: f64,
    /// Simulation step, s.
    pub step: f64,
    /// Seconds between two poses while the vehicle moves.
    pub pose_period: f64,
    /// A surface vehicle (an ASC): its depth stays 0, and the behaviours
    /// that would take it down (depth, altitude, wall inspection) fail at once.
    pub surface: bool,
}

/// Names of the perceptions the simulation sends (none when absent).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Perceptions {
    /// Navigation quality, 0 to 1 in tenths.
    pub position_quality: Option<String>,
    /// Whether the cable is in sight (true/false), sent when it changes.
    pub cable_seen: Option<String>,
    /// Battery charge (a fraction of the capacity), sent at every 5 % step.
    pub battery: Option<String>,
    /// The navigation's estimate of the position, east and north, in whole
    /// metres, and the depth in tenths of a metre, each sent when it
    /// changes (for a planner's world modeler; none by default).
    pub x: Option<String>,
    pub y: Option<String>,
    pub depth: Option<String>,
    /// Whether the battery is at or below the alarm level (true/false),
    /// sent when it changes (none by default).
    pub alarm: Option<String>,
    /// Metres of cable tracked so far, whole metres, sent when it grows
    /// (none by default).
    pub cable_tracked: Option<String>,
    /// True/false perceptions (`cable_seen`, `alarm`) are sent as 1/0.
    pub flags_as_numbers: bool,
}

/// Where a behaviour argument comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum ArgSource {
    /// The action's parameter of that name.
    Param(String),
    /// A fixed value.
    Value(Value),
}

/// How one primitive is simulated.
#[derive(Clone, Debug, PartialEq)]
pub struct PrimitiveModel {
    pub behaviour: Kind,
    /// Event raised when the behaviour reaches its goal.
    pub ok: Option<String>,
    /// Event raised when it cannot.
    pub fail: Option<String>,
    /// Event raised when a cable tracking loses the cable (else `fail`).
    pub lost: Option<String>,
    /// Behaviour arguments.
    pub args: BTreeMap<String, ArgSource>,
    /// Commands that start (or restart) the behaviour.
    pub start: Vec<String>,
    /// Commands that stop it.
    pub stop: Vec<String>,
}

/// A vehicle model. See the [module documentation](self).
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    pub limits: Limits,
    pub perceptions: Perceptions,
    /// Default values of symbolic call arguments (a world's and `--set`
    /// override them).
    pub symbols: BTreeMap<String, Value>,
    /// By AAC primitive name (`GotoPrimitive`).
    pub primitives: BTreeMap<String, PrimitiveModel>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelFile {
    /// `"default"`: this file overrides the bundled model.
    #[serde(default)]
    base: Option<toml::Spanned<String>>,
    #[serde(default)]
    vehicle: Option<VehicleFile>,
    #[serde(default)]
    perceptions: Option<PerceptionsFile>,
    #[serde(default)]
    symbols: BTreeMap<String, Value>,
    #[serde(default)]
    primitives: BTreeMap<String, PrimitiveFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct VehicleFile {
    #[serde(default, deserialize_with = "opt_positive")]
    surge_speed: Option<f64>,
    #[serde(default, deserialize_with = "opt_positive")]
    sway_speed: Option<f64>,
    #[serde(default, deserialize_with = "opt_positive")]
    heave_speed: Option<f64>,
    #[serde(default, deserialize_with = "opt_positive")]
    turn_rate: Option<f64>,
    #[serde(default, deserialize_with = "opt_positive")]
    emergency_ascent: Option<f64>,
    #[serde(default, deserialize_with = "opt_step")]
    step: Option<f64>,
    #[serde(default, deserialize_with = "opt_positive")]
    pose_period: Option<f64>,
    surface: Option<bool>,
}

#[derive(Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct PerceptionsFile {
    position_quality: Option<String>,
    cable_seen: Option<String>,
    battery: Option<String>,
    x: Option<String>,
    y: Option<String>,
    depth: Option<String>,
    alarm: Option<String>,
    cable_tracked: Option<String>,
    flags_as_numbers: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PrimitiveFile {
    behaviour: Kind,
    ok: Option<String>,
    fail: Option<String>,
    lost: Option<String>,
    #[serde(default)]
    params: Option<toml::Spanned<BTreeMap<String, String>>>,
    #[serde(default)]
    set: Option<toml::Spanned<BTreeMap<String, Value>>>,
    start: Option<Vec<String>>,
    stop: Option<Vec<String>>,
}

fn opt_positive<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    let v = f64::deserialize(d)?;
    if v.is_finite() && v > 0.0 {
        Ok(Some(v))
    } else {
        Err(de::Error::custom(format!("expected a number > 0, found {v}")))
    }
}

fn opt_step<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    let v = f64::deserialize(d)?;
    if v.is_finite() && (0.001..=1.0).contains(&v) {
        Ok(Some(v))
    } else {
        Err(de::Error::custom(format!("the simulation step is between 0.001 and 1 s, found {v}")))
    }
}

/// The name in `perceptions`: absent means the default, "" means none.
fn name_or(v: Option<String>, default: Option<&String>) -> Option<String> {
    match v {
        None => default.cloned(),
        Some(s) if s.is_empty() => None,
        Some(s) => Some(s),
    }
}

impl Model {
    /// Parses a vehicle model. Errors are `origin:line:col: message`.
    pub fn from_toml(text: &str, origin: &str) -> Result<Model, String> {
        let f: ModelFile = toml::from_str(text).map_err(|e| toml_error(origin, text, &e))?;
        // What the file does not say: the bundled model's (`base`), else the defaults.
        let base = match &f.base {
            None => Model::builtin_defaults(),
            Some(b) if b.get_ref() == "default" => Model::default_model(),
            Some(b) => {
                return Err(located(
                    origin,
                    text,
                    b.span(),
                    &format!("`base = \"{}\"`: the only base is \"default\" (the bundled model)", b.get_ref()),
                ))
            }
        };
        let d = base.limits;
        let v = f.vehicle.unwrap_or(VehicleFile {
            surge_speed: None,
            sway_speed: None,
            heave_speed: None,
            turn_rate: None,
            emergency_ascent: None,
            step: None,
            pose_period: None,
            surface: None,
        });
        let limits = Limits {
            surge: v.surge_speed.unwrap_or(d.surge),
            sway: v.sway_speed.unwrap_or(d.sway),
            heave: v.heave_speed.unwrap_or(d.heave),
            turn_rate: v.turn_rate.map_or(d.turn_rate, f64::to_radians),
            emergency_ascent: v.emergency_ascent.unwrap_or(d.emergency_ascent),
            step: v.step.unwrap_or(d.step),
            pose_period: v.pose_period.unwrap_or(d.pose_period),
            surface: v.surface.unwrap_or(d.surface),
        };
        let p = f.perceptions.unwrap_or_default();
        let b = &base.perceptions;
        let perceptions = Perceptions {
            position_quality: name_or(p.position_quality, b.position_quality.as_ref()),
            cable_seen: name_or(p.cable_seen, b.cable_seen.as_ref()),
            battery: name_or(p.battery, b.battery.as_ref()),
            x: name_or(p.x, b.x.as_ref()),
            y: name_or(p.y, b.y.as_ref()),
            depth: name_or(p.depth, b.depth.as_ref()),
            alarm: name_or(p.alarm, b.alarm.as_ref()),
            cable_tracked: name_or(p.cable_tracked, b.cable_tracked.as_ref()),
            flags_as_numbers: p.flags_as_numbers.unwrap_or(b.flags_as_numbers),
        };
        let mut primitives = base.primitives;
        for (name, pf) in f.primitives {
            let allowed = pf.behaviour.args();
            let mut args = BTreeMap::new();
            let check_keys = |span: std::ops::Range<usize>, keys: Vec<&String>, table: &str| {
                for k in keys {
                    if !allowed.contains(&k.as_str()) {
                        // Point at the key inside the table.
                        let body = &text[span.start.min(text.len())..span.end.min(text.len())];
                        let at =
                            body.find(k.as_str()).map_or(span.clone(), |i| span.start + i..span.start + i + k.len());
                        let list = if allowed.is_empty() { "none".to_string() } else { allowed.join(", ") };
                        return Err(located(
                            origin,
                            text,
                            at,
                            &format!(
                                "`{k}` in `{table}` of primitive `{name}`: behaviour `{}` has no such argument (its arguments: {list})",
                                pf.behaviour.name()
                            ),
                        ));
                    }
                }
                Ok(())
            };
            if let Some(params) = &pf.params {
                check_keys(params.span(), params.get_ref().keys().collect(), "params")?;
                for (k, p) in params.get_ref() {
                    args.insert(k.clone(), ArgSource::Param(p.clone()));
                }
            }
            if let Some(set) = &pf.set {
                check_keys(set.span(), set.get_ref().keys().collect(), "set")?;
                for (k, v) in set.get_ref() {
                    if args.contains_key(k) {
                        let body = &text[set.span().start.min(text.len())..set.span().end.min(text.len())];
                        let at = body
                            .find(k.as_str())
                            .map_or(set.span(), |i| set.span().start + i..set.span().start + i + k.len());
                        return Err(located(
                            origin,
                            text,
                            at,
                            &format!("`{k}` of primitive `{name}` is in both `params` and `set`; keep one"),
                        ));
                    }
                    args.insert(k.clone(), ArgSource::Value(v.clone()));
                }
            }
            primitives.insert(
                name,
                PrimitiveModel {
                    behaviour: pf.behaviour,
                    ok: pf.ok,
                    fail: pf.fail,
                    lost: pf.lost,
                    args,
                    start: pf.start.unwrap_or_else(|| vec!["enable".to_string()]),
                    stop: pf.stop.unwrap_or_else(|| vec!["disable".to_string()]),
                },
            );
        }
        let mut symbols = base.symbols;
        symbols.extend(f.symbols);
        Ok(Model { limits, perceptions, symbols, primitives })
    }

    /// What a model file without `base` starts from: the default limits
    /// and perception names, no symbol, no primitive.
    fn builtin_defaults() -> Model {
        let name = |s: &str| Some(s.to_string());
        Model {
            limits: Limits {
                surge: 1.0,
                sway: 0.3,
                heave: 0.3,
                turn_rate: 30f64.to_radians(),
                emergency_ascent: 1.0,
                step: 0.1,
                pose_period: 1.0,
                surface: false,
            },
            perceptions: Perceptions {
                position_quality: name("nav.quality"),
                cable_seen: name("cable.seen"),
                battery: name("battery"),
                ..Perceptions::default()
            },
            symbols: BTreeMap::new(),
            primitives: BTreeMap::new(),
        }
    }

    /// Reads and parses a vehicle model file.
    pub fn load(path: &Path) -> Result<Model, String> {
        let text = mcl_net::input::read_source(path).map_err(|e| format!("vehicle model: {e}"))?;
        Model::from_toml(&text, &path.display().to_string())
    }

    /// The bundled model of `examples/vehicle.mcl`.
    pub fn default_model() -> Model {
        Model::from_toml(DEFAULT_MODEL, "examples/sim/vehicle-model.toml").expect("the bundled model parses")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bundled_model_maps_the_seed_primitives() {
        let m = Model::default_model();
        let g = &m.primitives["GotoPrimitive"];
        assert_eq!(g.behaviour, Kind::Goto);
        assert_eq!(g.ok.as_deref(), Some("eventGotoOk"));
        assert_eq!(g.args.get("target"), Some(&ArgSource::Param("way-point".into())));
        assert_eq!(m.primitives["CableTrackingPrimitive"].lost.as_deref(), Some("eventCableTrackingOk"));
    }

    #[test]
    fn a_model_based_on_the_bundled_one_overrides_what_it_says() {
        let text = "base = \"default\"\n[vehicle]\nsurge_speed = 2\n[perceptions]\ncable_seen = \"cable.detected\"\nx = \"auv.x\"\nflags_as_numbers = true\n[symbols]\naltitude = 1.5\n[primitives.GotoPrimitive]\nbehaviour = \"goto\"\nok = \"done\"\n";
        let m = Model::from_toml(text, "m.toml").unwrap();
        let d = Model::default_model();
        assert_eq!((m.limits.surge, m.limits.heave), (2.0, d.limits.heave));
        assert_eq!(m.perceptions.cable_seen.as_deref(), Some("cable.detected"));
        assert_eq!(m.perceptions.position_quality, d.perceptions.position_quality);
        assert_eq!((m.perceptions.x.as_deref(), m.perceptions.y.as_deref()), (Some("auv.x"), None));
        assert!(m.perceptions.flags_as_numbers && !d.perceptions.flags_as_numbers);
        assert_eq!(m.symbols["altitude"], 1.5);
        assert_eq!(m.symbols["velocity"], d.symbols["velocity"]);
        assert_eq!(m.primitives["GotoPrimitive"].ok.as_deref(), Some("done"));
        assert_eq!(m.primitives["SurfacePrimitive"], d.primitives["SurfacePrimitive"]);
        let e = Model::from_toml("base = \"rov\"\n", "m.toml").unwrap_err();
        assert!(e.starts_with("m.toml:1:8:") && e.contains("default"), "{e}");
    }

    #[test]
    fn errors_are_located() {
        let e = Model::from_toml("[primitives.X]\nbehaviour = \"gotoo\"\n", "m.toml").unwrap_err();
        assert!(e.starts_with("m.toml:2:13:") && e.contains("gotoo"), "{e}");
        let e = Model::from_toml(
            "[primitives.X]\nbehaviour = \"goto\"\nparams = { target = \"p\", speeed = \"v\" }\n",
            "m.toml",
        )
        .unwrap_err();
        assert!(e.starts_with("m.toml:3:26:") && e.contains("speeed"), "{e}");
        let e = Model::from_toml("[vehicle]\nstep = 5\n", "m.toml").unwrap_err();
        assert!(e.starts_with("m.toml:2:8:"), "{e}");
    }
}
