//! The sans-IO part of a reliable coordination link: sequence numbers,
//! cumulative acknowledgements and re-sends, whatever carries the bytes
//! (the TCP link of [`crate::coord_link`], the Zenoh transport of
//! `mcl-zenoh`).
//!
//! A sender numbers its messages to one receiver from 1 and keeps each in
//! its [`SendWindow`] until the receiver acknowledges it; a receiver takes
//! the numbers in order, once, through its [`RecvWindow`], and acknowledges
//! (cumulatively) only what its vehicle has made durable. Together with
//! re-sends of whatever is unacknowledged, nothing is lost and nothing is
//! applied twice, across a restart of either side (the receiver starts
//! again from its journal: [`RecvWindow::resumed`]).

use std::collections::VecDeque;
use std::time::Duration;

/// Unacknowledged messages are sent again after this long.
pub const RESEND_AFTER: Duration = Duration::from_secs(1);

/// The messages one sender has sent to one receiver and not yet had
/// acknowledged, in order.
#[derive(Clone, Debug, Default)]
pub struct SendWindow<T> {
    outbox: VecDeque<(u64, T)>,
}

impl<T> SendWindow<T> {
    /// An empty window.
    pub fn new() -> SendWindow<T> {
        SendWindow { outbox: VecDeque::new() }
    }

    /// Keeps message `seq` until it is acknowledged.
    pub fn push(&mut self, seq: u64, msg: T) {
        self.outbox.push_back((seq, msg));
    }

    /// The receiver made everything up to `seq` durable: forgets those
    /// messages and returns how many.
    pub fn acked(&mut self, seq: u64) -> usize {
        let mut n = 0;
        while self.outbox.front().is_some_and(|(s, _)| *s <= seq) {
            self.outbox.pop_front();
            n += 1;
        }
        n
    }

    /// The unacknowledged messages, oldest first (to send again).
    pub fn pending(&self) -> impl Iterator<Item = &(u64, T)> {
        self.outbox.iter()
    }

    /// How many are unacknowledged.
    pub fn len(&self) -> usize {
        self.outbox.len()
    }

    /// Nothing is unacknowledged.
    pub fn is_empty(&self) -> bool {
        self.outbox.is_empty()
    }
}

/// What a receiver does with a message numbered `seq` ([`RecvWindow::offer`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Offer {
    /// The next one: deliver it (once).
    Deliver,
    /// Delivered before and durable: drop it, and acknowledge again (the
    /// sender missed the acknowledgement).
    Durable,
    /// Delivered before, not yet durable: drop it (its acknowledgement
    /// follows once it is).
    Delivered,
    /// After a gap: drop it; it comes again with the re-sends, after the
    /// missing ones.
    Gap,
}

/// The receiving side of one link: the next number to deliver and the last
/// one made durable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RecvWindow {
    next: u64,
    durable: u64,
}

impl Default for RecvWindow {
    fn default() -> RecvWindow {
        RecvWindow::resumed(0)
    }
}

impl RecvWindow {
    /// A receiver that already holds (from its journal) every message up
    /// to `seq`: it neither takes those again nor waits for them.
    pub fn resumed(seq: u64) -> RecvWindow {
        RecvWindow { next: seq + 1, durable: seq }
    }

    /// What to do with message `seq`; [`Offer::Deliver`] moves the window on.
    pub fn offer(&mut self, seq: u64) -> Offer {
        if seq == self.next {
            self.next += 1;
            Offer::Deliver
        } else if seq <= self.durable {
            Offer::Durable
        } else if seq < self.next {
            Offer::Delivered
        } else {
            Offer::Gap
        }
    }

    /// The receiver made message `seq` durable (journaled). Returns whether
    /// the cumulative acknowledgement moved on.
    pub fn made_durable(&mut self, seq: u64) -> bool {
        let moved = seq > self.durable;
        self.durable = self.durable.max(seq).min(self.next.saturating_sub(1));
        moved
    }

    /// The acknowledgement to send: every message up to it is durable
    /// (`None` before the first).
    pub fn ack(&self) -> Option<u64> {
        (self.durable > 0).then_some(self.durable)
    }

    /// The next number to deliver.
    pub fn next(&self) -> u64 {
        self.next
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_receiver_delivers_in_order_once() {
        let mut w = RecvWindow::default();
        assert_eq!(w.ack(), None);
        assert_eq!(w.offer(2), Offer::Gap);
        assert_eq!(w.offer(1), Offer::Deliver);
        assert_eq!(w.offer(1), Offer::Delivered);
        assert!(w.made_durable(1));
        assert_eq!(w.offer(1), Offer::Durable);
        assert_eq!(w.offer(2), Offer::Deliver);
        assert_eq!(w.ack(), Some(1));
        // Durable never passes what was delivered.
        assert!(w.made_durable(9));
        assert_eq!((w.ack(), w.next()), (Some(2), 3));
        assert!(!w.made_durable(2));
    }

    #[test]
    fn a_resumed_receiver_neither_takes_nor_waits_for_what_it_holds() {
        let mut w = RecvWindow::resumed(4);
        assert_eq!(w.ack(), Some(4));
        assert_eq!(w.offer(3), Offer::Durable);
        assert_eq!(w.offer(5), Offer::Deliver);
    }

    #[test]
    fn a_sender_forgets_what_is_acknowledged() {
        let mut s = SendWindow::new();
        for i in 1..=4 {
            s.push(i, format!("m{i}"));
        }
        assert_eq!(s.acked(2), 2);
        assert_eq!(s.acked(1), 0);
        assert_eq!(s.pending().map(|(n, _)| *n).collect::<Vec<_>>(), [3, 4]);
        assert_eq!(s.acked(10), 2);
        assert!(s.is_empty());
        assert_eq!(s.len(), 0);
    }
}
