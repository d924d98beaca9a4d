//! A message body that [`crate::cdr`] encoded, carried through serde: the
//! way to give dynamic messages to a CDR serde serializer (`cdr-encoding`,
//! which `rustdds` and `ros2-client` use for their typed publishers,
//! subscriptions, services and actions).
//!
//! [`RawCdr`] serializes as a tuple of octets, which a CDR serializer
//! writes as they are (an octet needs no alignment), so the stream holds
//! exactly the codec's bytes. It deserializes by reading octets until the
//! input ends, so it must be the last thing of what is read. Alignment in
//! such a stream counts from its start: a body that does not start at
//! offset 0 (inside a wrapper ros2-client builds, after its own fields)
//! is encoded and decoded with that offset ([`crate::cdr::encode_body`],
//! [`crate::cdr::decode_body`]).

use serde::de::{SeqAccess, Visitor};
use serde::ser::SerializeTuple;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// An encoded message body (no encapsulation header).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RawCdr(pub Vec<u8>);

impl Serialize for RawCdr {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut t = s.serialize_tuple(self.0.len())?;
        for b in &self.0 {
            t.serialize_element(b)?;
        }
        t.end()
    }
}

impl<'de> Deserialize<'de> for RawCdr {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<RawCdr, D::Error> {
        struct Octets;
        impl<'de> Visitor<'de> for Octets {
            type Value = RawCdr;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("the octets of a CDR message body")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<RawCdr, A::Error> {
                let mut out = Vec::new();
                // The end of the input is the end of the body.
                while let Ok(Some(b)) = seq.next_element::<u8>() {
                    out.push(b);
                }
                Ok(RawCdr(out))
            }
        }
        d.deserialize_tuple(usize::MAX, Octets)
    }
}

/// A body can be a service's request or response and an action's goal,
/// result or feedback (`ros2-client`'s message bound).
impl ros2_client::Message for RawCdr {}
