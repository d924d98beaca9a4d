//! A thin layer over `mcl_net::NetBuilder` for generating blocks: places and
//! transitions by id, interfaces as place quadruples, and the provenance that
//! every node created next receives.

use mcl_net::{Delay, NetBuilder, Place, PlaceId, Provenance, Transition, TransitionId, TransitionKind};

/// The four places of an interface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Iface {
    pub begin: PlaceId,
    pub abort: PlaceId,
    pub ok: PlaceId,
    pub fail: PlaceId,
}

/// Generates nodes into a net under construction.
pub struct Builder {
    pub net: NetBuilder,
    /// Provenance given to the nodes created next.
    pub provenance: Provenance,
}

impl Builder {
    pub fn new(id: &str) -> Self {
        Builder { net: NetBuilder::new(id), provenance: Provenance::default() }
    }

    /// A place with `tokens` initial tokens, outside any interface.
    pub fn place(&mut self, id: &str, tokens: u32) -> PlaceId {
        self.net.add_place(Place::new(id).with_tokens(tokens).with_provenance(self.provenance.clone()))
    }

    /// The places `prefix.begin`, `prefix.abort`, `prefix.ok`, `prefix.fail` on interface `interface`.
    pub fn iface(&mut self, prefix: &str, interface: u32) -> Iface {
        let mut mk = |n: &str| {
            self.net.add_place(
                Place::new(format!("{prefix}.{n}")).with_interface(interface).with_provenance(self.provenance.clone()),
            )
        };
        Iface { begin: mk("begin"), abort: mk("abort"), ok: mk("ok"), fail: mk("fail") }
    }

    /// A transition of any kind with unit-weight arcs.
    pub fn transition(
        &mut self,
        id: &str,
        kind: TransitionKind,
        inputs: &[PlaceId],
        outputs: &[PlaceId],
    ) -> TransitionId {
        let t = self.net.add_transition(Transition::new(id).with_kind(kind).with_provenance(self.provenance.clone()));
        for &p in inputs {
            self.net.add_input(p, t, 1);
        }
        for &p in outputs {
            self.net.add_output(t, p, 1);
        }
        t
    }

    /// An immediate transition.
    pub fn imm(&mut self, id: &str, inputs: &[PlaceId], outputs: &[PlaceId]) -> TransitionId {
        self.transition(id, TransitionKind::Immediate, inputs, outputs)
    }

    /// A deferred transition: timed with delay 0, so it fires only in a
    /// tangible marking, after every immediate cascade has settled.
    pub fn deferred(&mut self, id: &str, inputs: &[PlaceId], outputs: &[PlaceId]) -> TransitionId {
        self.transition(id, TransitionKind::Timed(Delay::Fixed(0.0)), inputs, outputs)
    }
}
