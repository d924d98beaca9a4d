//! What DDS discovery has found of the other participants: which remote
//! readers and writers there are, by topic and type name. A service call or
//! a goal goes out only once its server's endpoints are found with the
//! right types ([`Discovered::ready`]); a goal fails when its server's
//! endpoints disappear ([`Discovered::has_writer`]); a publisher of another
//! type on a topic the bridge reads is named ([`Discovered::foreign_writers`]),
//! since DDS never delivers its messages.

use ros2_client::dds::rustdds::DomainParticipant;
use std::collections::{BTreeMap, BTreeSet};
use std::time::{Duration, Instant};

/// How often the discovered endpoints are read again.
const REDISCOVER: Duration = Duration::from_millis(100);
/// How long a server's endpoints must have been found before a request
/// goes out. Finding the server's endpoints does not tell that the server
/// has found ours: a volatile reader drops what a writer it does not know
/// yet sends, so a request sent at once can be lost (and a reply to a
/// reader the server does not know yet). ros2-client does not tell when a
/// remote reader has acknowledged a client's writer; this margin stands
/// for it.
const GRACE: Duration = Duration::from_millis(1000);

/// The DDS request and reply topics of a service, with their type names.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct Endpoints {
    pub request: String,
    pub request_type: String,
    pub reply: String,
    pub reply_type: String,
}

/// Remote readers and writers by topic, with the type names found on it,
/// read again at most every [`REDISCOVER`].
pub(crate) struct Discovered {
    dp: DomainParticipant,
    readers: BTreeMap<String, BTreeSet<String>>,
    writers: BTreeMap<String, BTreeSet<String>>,
    read_at: Option<Instant>,
    /// Since when each (topic, type) has had a remote reader, or writer.
    readers_since: BTreeMap<(String, String), Instant>,
    writers_since: BTreeMap<(String, String), Instant>,
}

impl Discovered {
    pub(crate) fn new(dp: DomainParticipant) -> Discovered {
        Discovered {
            dp,
            readers: BTreeMap::new(),
            writers: BTreeMap::new(),
            read_at: None,
            readers_since: BTreeMap::new(),
            writers_since: BTreeMap::new(),
        }
    }

    /// Reads the discovered endpoints again if [`REDISCOVER`] has passed
    /// (the node calls it on each round, so that the time since an
    /// endpoint was found counts from when it was, not from when a
    /// request first asked).
    pub(crate) fn refresh(&mut self, now: Instant) {
        if self.read_at.is_some_and(|t| now.duration_since(t) < REDISCOVER) {
            return;
        }
        self.read_at = Some(now);
        self.readers.clear();
        for r in self.dp.discovered_readers() {
            let t = &r.subscription_topic_data;
            self.readers.entry(t.topic_name().clone()).or_default().insert(t.type_name().clone());
        }
        self.writers.clear();
        for w in self.dp.discovered_writers() {
            let t = w.publication_topic_data;
            self.writers.entry(t.topic_name).or_default().insert(t.type_name);
        }
        since(&mut self.readers_since, &self.readers, now);
        since(&mut self.writers_since, &self.writers, now);
    }

    /// Whether a server of `e` (its request reader and reply writer, of the
    /// right types) was found at least [`GRACE`] ago.
    pub(crate) fn ready(&mut self, e: &Endpoints, now: Instant) -> bool {
        self.refresh(now);
        let reader = self.readers_since.get(&(e.request.clone(), e.request_type.clone()));
        let writer = self.writers_since.get(&(e.reply.clone(), e.reply_type.clone()));
        match (reader, writer) {
            (Some(r), Some(w)) => now.duration_since(*r.max(w)) >= GRACE,
            _ => false,
        }
    }

    /// Why no server of `e` was ready within `timeout`: none found, or
    /// one whose requests are of other types.
    pub(crate) fn why_not(&mut self, e: &Endpoints, timeout: Duration, now: Instant) -> String {
        self.refresh(now);
        let others: BTreeSet<&String> =
            self.readers.get(&e.request).into_iter().flatten().filter(|t| **t != e.request_type).collect();
        let within = format!("no server was found within {:.1} s", timeout.as_secs_f64());
        if others.is_empty() {
            within
        } else {
            let others: Vec<&str> = others.into_iter().map(String::as_str).collect();
            format!("{within}: one reads requests of type {}, not {}", others.join(", "), e.request_type)
        }
    }

    /// Whether some participant writes `topic` as `ty`.
    pub(crate) fn has_writer(&mut self, topic: &str, ty: &str, now: Instant) -> bool {
        self.refresh(now);
        self.writers.get(topic).is_some_and(|t| t.contains(ty))
    }

    /// The types other than `ty` that participants write `topic` as.
    pub(crate) fn foreign_writers(&mut self, topic: &str, ty: &str, now: Instant) -> Vec<String> {
        self.refresh(now);
        self.writers.get(topic).into_iter().flatten().filter(|t| *t != ty).cloned().collect()
    }
}

/// Keeps in `since` when each (topic, type) of `found` was first seen in a
/// row of reads (one that disappears starts again when it comes back).
fn since(since: &mut BTreeMap<(String, String), Instant>, found: &BTreeMap<String, BTreeSet<String>>, now: Instant) {
    since.retain(|(topic, ty), _| found.get(topic).is_some_and(|t| t.contains(ty)));
    for (topic, types) in found {
        for ty in types {
            since.entry((topic.clone(), ty.clone())).or_insert(now);
        }
    }
}
