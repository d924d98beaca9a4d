//! A thin layer over `mcl_net::NetBuilder` for generating blocks: places and
//! transitions by id, interfaces as place quadruples, and the provenance that
//! every node created next receives.
//!
//! A mission compiles to hundreds of thousands of nodes, so node creation
//! allocates as little as possible: the provenance is one shared record per
//! structure or call, and ids are assembled from [`Part`]s (no `format!`)
//! into a text shared by the next few hundred nodes ([`SharedText`]): the
//! ids of a text read as empty until it is complete ([`Builder::finish`]
//! completes the last one).

use std::sync::Arc;

use mcl_net::{
    Delay, Name, NetBuilder, Place, PlaceId, Provenance, SharedText, Transition, TransitionId, TransitionKind,
};

/// The four places of an interface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Iface {
    pub begin: PlaceId,
    pub abort: PlaceId,
    pub ok: PlaceId,
    pub fail: PlaceId,
}

/// A piece of a node id: text or a decimal number.
#[derive(Clone, Copy, Debug)]
pub enum Part<'a> {
    S(&'a str),
    N(usize),
}

/// Size of a shared id text.
const CHUNK: usize = 16 * 1024;

/// Generates nodes into a net under construction.
pub struct Builder {
    pub net: NetBuilder,
    /// Provenance given to the nodes created next (shared by all of them).
    pub provenance: Arc<Provenance>,
    /// The text of the ids cut from `text`, not complete yet.
    buf: String,
    text: SharedText,
    /// Transitions through which the mission leaves its nominal path
    /// (a catch starts, a monitor's condition ended), for
    /// [`mcl_net::HANDLERS_PROPERTY`].
    pub handlers: Vec<(TransitionId, mcl_net::HandlerKind)>,
}

impl Builder {
    pub fn new(id: &str) -> Self {
        Builder::from_net(NetBuilder::new(id))
    }

    /// A builder that extends `net`.
    pub fn from_net(net: NetBuilder) -> Self {
        Builder {
            net,
            provenance: Provenance::none(),
            buf: String::new(),
            text: SharedText::new(),
            handlers: Vec::new(),
        }
    }

    /// The net, every node with its id.
    pub fn finish(mut self) -> NetBuilder {
        self.flush();
        self.net
    }

    /// Completes the current text: its ids read as written.
    fn flush(&mut self) {
        if !self.buf.is_empty() {
            self.text.set(&self.buf);
            self.text = SharedText::new();
            self.buf.clear();
        }
    }

    /// The id made of `parts`, concatenated (it reads as empty until the
    /// builder completes its text).
    pub fn id(&mut self, parts: &[Part<'_>]) -> Name {
        if self.buf.len() >= CHUNK {
            self.flush();
        }
        if self.buf.capacity() == 0 {
            self.buf.reserve(CHUNK + 256);
        }
        let start = self.buf.len();
        for part in parts {
            match *part {
                Part::S(s) => self.buf.push_str(s),
                Part::N(n) => push_decimal(&mut self.buf, n),
            }
        }
        self.text.name(start..self.buf.len())
    }

    /// A place with `tokens` initial tokens, outside any interface.
    pub fn place(&mut self, id: impl Into<Name>, tokens: u32) -> PlaceId {
        self.add_place(id.into(), tokens, mcl_net::model::INTERFACE_NONE)
    }

    fn add_place(&mut self, name: Name, tokens: u32, interface: u32) -> PlaceId {
        self.net.add_place(Place {
            id: name.clone(),
            name,
            initial: tokens,
            interface,
            provenance: self.provenance.clone(),
        })
    }

    /// The places `prefix.begin`, `prefix.abort`, `prefix.ok`, `prefix.fail` on interface `interface`.
    pub fn iface(&mut self, prefix: &str, interface: u32) -> Iface {
        self.iface_parts(&[Part::S(prefix)], interface)
    }

    /// [`Builder::iface`] with a prefix made of parts (at most seven).
    pub fn iface_parts(&mut self, prefix: &[Part<'_>], interface: u32) -> Iface {
        let mut mk = |n: &str| {
            let mut parts: [Part<'_>; 8] = [Part::S(""); 8];
            parts[..prefix.len()].copy_from_slice(prefix);
            parts[prefix.len()] = Part::S(n);
            let id = self.id(&parts[..=prefix.len()]);
            self.add_place(id, 0, interface)
        };
        Iface { begin: mk(".begin"), abort: mk(".abort"), ok: mk(".ok"), fail: mk(".fail") }
    }

    /// A transition of any kind with unit-weight arcs.
    pub fn transition(
        &mut self,
        id: impl Into<Name>,
        kind: TransitionKind,
        inputs: &[PlaceId],
        outputs: &[PlaceId],
    ) -> TransitionId {
        let name = id.into();
        let t = self.net.add_transition(Transition {
            id: name.clone(),
            name,
            kind,
            actions: Vec::new(),
            priority: None,
            binding: None,
            provenance: self.provenance.clone(),
        });
        for &p in inputs {
            self.net.add_input(p, t, 1);
        }
        for &p in outputs {
            self.net.add_output(t, p, 1);
        }
        t
    }

    /// An immediate transition.
    pub fn imm(&mut self, id: impl Into<Name>, inputs: &[PlaceId], outputs: &[PlaceId]) -> TransitionId {
        self.transition(id, TransitionKind::Immediate, inputs, outputs)
    }

    /// A deferred transition: timed with delay 0, so it fires only in a
    /// tangible marking, after every immediate cascade has settled. Its
    /// priority is [`DEFERRED_PRIORITY`]: it fires before the release of a
    /// task's lock ([`Builder::deferred_last`]).
    pub fn deferred(&mut self, id: impl Into<Name>, inputs: &[PlaceId], outputs: &[PlaceId]) -> TransitionId {
        let t = self.transition(id, TransitionKind::Timed(Delay::Fixed(0.0)), inputs, outputs);
        if let Some(tr) = self.net.transition_mut(t) {
            tr.priority = Some(DEFERRED_PRIORITY);
        }
        t
    }

    /// A deferred transition of priority 0: it fires once no other deferred
    /// transition is ready (the release of a task by a call: every
    /// structure has aborted what it decided to abort before a waiting
    /// call can take the task).
    pub fn deferred_last(&mut self, id: impl Into<Name>, inputs: &[PlaceId], outputs: &[PlaceId]) -> TransitionId {
        self.transition(id, TransitionKind::Timed(Delay::Fixed(0.0)), inputs, outputs)
    }
}

/// Priority of the deferred transitions of the control structures (kills,
/// ends after kills, do-blocks); the release of a task's lock has 0.
pub const DEFERRED_PRIORITY: u32 = 1;

impl Builder {}

/// Appends `n` in decimal.
pub fn push_decimal(out: &mut String, mut n: usize) {
    let mut digits = [0u8; 20];
    let mut i = digits.len();
    loop {
        i -= 1;
        digits[i] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    out.push_str(std::str::from_utf8(&digits[i..]).unwrap_or_default());
}
