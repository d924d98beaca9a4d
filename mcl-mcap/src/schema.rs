//! The JSON Schema (draft 2020-12) of each channel: the fields of the trace
//! records it carries (docs/scenarios.md, *Traces*), so that Foxglove lists
//! them for plots and filters.

use serde_json::{json, Map, Value};

use crate::Topic;

/// The schema of the messages of `topic`.
pub fn schema_of(topic: &Topic) -> Value {
    let string = json!({"type": "string"});
    let integer = json!({"type": "integer", "minimum": 0});
    let number = json!({"type": "number"});
    let mut props: Vec<(&str, Value)> = vec![
        ("t", json!({"type": "number", "description": "mission time, seconds"})),
        ("mission", json!({"type": "string", "description": "the mission (a vehicle of a coordinated run)"})),
        ("kind", json!({"type": "string", "enum": topic.kinds})),
    ];
    let call = [
        ("task", string.clone()),
        ("call_site", integer.clone()),
        ("label", string.clone()),
        ("src", json!({"type": "string", "description": "file:line of the call"})),
    ];
    let ends = json!({"type": "string", "enum": ["ok", "fail", "neither", "timeout", "catch", "condition"]});
    let (title, required): (&str, &[&str]) = match topic.schema {
        "mcl.Action" => {
            props.extend([
                ("seq", integer.clone()),
                ("action", string.clone()),
                ("primitive", string.clone()),
                ("command", string.clone()),
                (
                    "params",
                    json!({"type": "object", "description": "parameters, in the order the action declares them"}),
                ),
                ("queued", json!({"type": "boolean"})),
            ]);
            props.extend(call.clone());
            ("An action sent to the vehicle", &["seq", "action", "primitive", "command", "params"])
        }
        "mcl.Event" => {
            props.extend([
                ("event", string.clone()),
                ("transition", string.clone()),
                ("activation", integer.clone()),
                ("ends", ends.clone()),
                ("reason", string.clone()),
            ]);
            props.extend(call.clone());
            ("An event from the vehicle: handled, unexpected or stale", &["event"])
        }
        "mcl.Firing" => {
            props.extend([("transition", string.clone()), ("ends", ends), ("deadline", number.clone())]);
            props.extend(call);
            ("A transition fired, or a timer started", &["transition"])
        }
        "mcl.Perception" => {
            props.extend([("name", string.clone()), ("value", json!({}))]);
            ("A perception from the vehicle", &["name", "value"])
        }
        "mcl.Pose" => {
            props.extend([
                ("x", json!({"type": "number", "description": "east, metres"})),
                ("y", json!({"type": "number", "description": "north, metres"})),
                ("z", json!({"type": "number", "description": "depth, metres"})),
                ("yaw", json!({"type": "number", "description": "heading, radians, counter-clockwise from east"})),
            ]);
            ("Where a simulated vehicle is", &["x", "y", "z", "yaw"])
        }
        "mcl.Outcome" => {
            props.extend([
                ("result", string.clone()),
                ("reason", string.clone()),
                ("via", string.clone()),
                ("messages", integer.clone()),
                ("value", json!({})),
            ]);
            ("How a mission (or a coordinated run) ended", &["result"])
        }
        "mcl.Coordination" => {
            props.extend([
                ("seq", integer.clone()),
                ("transition", string.clone()),
                ("event", string.clone()),
                ("to", string.clone()),
                ("from", string.clone()),
                ("message", string.clone()),
                ("what", string.clone()),
                ("bytes", integer.clone()),
                ("json_bytes", integer.clone()),
                ("attempt", integer.clone()),
                ("reason", string.clone()),
                ("status", string.clone()),
            ]);
            ("A coordination message sent, received or refused, or a frame of the modelled acoustic link", &[])
        }
        "mcl.Log" => {
            props.push(("message", string));
            ("A warning, or a notice of the link to the vehicle", &["message"])
        }
        _ => ("A trace record of another kind", &[]),
    };
    let mut required: Vec<&str> = required.to_vec();
    required.splice(0..0, ["t", "kind"]);
    let properties: Map<String, Value> = props.into_iter().map(|(k, v)| (k.to_string(), v)).collect();
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": format!("{} ({})", topic.schema, title),
        "type": "object",
        "properties": properties,
        "required": required,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TOPICS;

    #[test]
    fn every_schema_is_an_object_schema_that_requires_t_and_kind() {
        for t in &TOPICS {
            let s = schema_of(t);
            assert_eq!(s["type"], "object", "{}", t.schema);
            assert_eq!(s["required"][0], "t");
            assert!(s["properties"]["kind"].is_object());
        }
        assert_eq!(schema_of(&TOPICS[0])["properties"]["kind"]["enum"], json!(["action"]));
    }
}
