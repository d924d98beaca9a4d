//! The key expressions of MCL over Zenoh (docs/zenoh.md *Key expressions*).
//!
//! | key | publisher | payload |
//! |---|---|---|
//! | `mcl/<fleet>/<to>/coord/in/<from>/<kind>` | the sending vehicle | a coordination message ([`crate::coord::ZMsg`]) |
//! | `mcl/<fleet>/<from>/coord/ack/<to>` | the receiving vehicle | an acknowledgement ([`crate::coord::ZAck`]) |
//! | `mcl/<vehicle>/aac/player/<type>` | the player | an AAC protocol message (`hello`, `action`, `ping`) |
//! | `mcl/<vehicle>/aac/vehicle/<type>` | the vehicle (AAC) | an AAC protocol message (`welcome`, `ack`, `event`, `perception`, `pong`, `error`) |
//! | `mcl/<vehicle>/status` | the player | the mission's state ([`crate::status::Status`]) |

/// One chunk of a key: a fleet, vehicle or mission name. Refuses what
/// would change the key's shape (`/`, wildcards, `$`, `?`, `#`, an empty
/// name, a leading `@`).
pub fn check_chunk(what: &str, name: &str) -> Result<(), String> {
    let bad = name.is_empty()
        || name.starts_with('@')
        || name.chars().any(|c| matches!(c, '/' | '*' | '$' | '?' | '#') || c.is_control());
    if bad {
        Err(format!(
            "{what} `{name}` cannot be a chunk of a Zenoh key (no `/`, `*`, `$`, `?`, `#`, not empty, not starting with `@`)"
        ))
    } else {
        Ok(())
    }
}

/// The kind of a coordination message, the last chunk of its key.
pub fn coord_kind(transition: &str) -> &'static str {
    if transition == mcl_runtime::multi::ENDED {
        "ended"
    } else if transition.starts_with("coord.request.") {
        "request"
    } else if transition.starts_with("coord.lend.") {
        "grant"
    } else if transition.starts_with("coord.return.") {
        "return"
    } else {
        "firing"
    }
}

/// Where `from` publishes its messages for `to`.
pub fn coord_msg(fleet: &str, to: &str, from: &str, kind: &str) -> String {
    format!("mcl/{fleet}/{to}/coord/in/{from}/{kind}")
}

/// What `to` subscribes to: every message for it.
pub fn coord_inbox(fleet: &str, to: &str) -> String {
    format!("mcl/{fleet}/{to}/coord/in/*/*")
}

/// Where `to` acknowledges the messages of `from`.
pub fn coord_ack(fleet: &str, from: &str, to: &str) -> String {
    format!("mcl/{fleet}/{from}/coord/ack/{to}")
}

/// What `from` subscribes to: the acknowledgements of its messages.
pub fn coord_acks(fleet: &str, from: &str) -> String {
    format!("mcl/{fleet}/{from}/coord/ack/*")
}

/// Where the player publishes AAC message `ty` for `vehicle`.
pub fn aac_player(vehicle: &str, ty: &str) -> String {
    format!("mcl/{vehicle}/aac/player/{ty}")
}

/// Where the AAC of `vehicle` publishes message `ty`.
pub fn aac_vehicle(vehicle: &str, ty: &str) -> String {
    format!("mcl/{vehicle}/aac/vehicle/{ty}")
}

/// Where `vehicle`'s mission state is published.
pub fn status(vehicle: &str) -> String {
    format!("mcl/{vehicle}/status")
}

/// The chunks of `key` after `prefix/`, if it starts so.
pub fn tail<'a>(key: &'a str, prefix: &str) -> Option<Vec<&'a str>> {
    key.strip_prefix(prefix)?.strip_prefix('/').map(|t| t.split('/').collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_that_would_reshape_a_key_are_refused() {
        assert!(check_chunk("vehicle", "auv").is_ok());
        for bad in ["", "a/b", "a*", "$x", "q?", "h#", "@admin"] {
            assert!(check_chunk("vehicle", bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn keys_and_kinds() {
        assert_eq!(coord_msg("f", "asc", "auv", coord_kind("call3.ok")), "mcl/f/asc/coord/in/auv/firing");
        assert_eq!(coord_kind("coord.request.coord.mutex1"), "request");
        assert_eq!(coord_kind("coord.lend.coord.mutex1.auv"), "grant");
        assert_eq!(coord_kind("coord.return.coord.mutex1"), "return");
        assert_eq!(coord_kind("coord.ended"), "ended");
        assert_eq!(tail("mcl/f/asc/coord/in/auv/firing", "mcl/f/asc/coord/in"), Some(vec!["auv", "firing"]));
        assert_eq!(tail("mcl/g/x", "mcl/f"), None);
        assert_eq!(aac_vehicle("auv", "event"), "mcl/auv/aac/vehicle/event");
        assert_eq!(status("auv"), "mcl/auv/status");
    }
}
