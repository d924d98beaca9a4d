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
/// goes out (the matching settles on both sides just after).
const GRACE: Duration = Duration::from_millis(300);

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
    /// Services whose endpoints were found, since.
    since: BTreeMap<Endpoints, Instant>,
}

impl Discovered {
    pub(crate) fn new(dp: DomainParticipant) -> Discovered {
        Discovered { dp, readers: BTreeMap::new(), writers: BTreeMap::new(), read_at: None, since: BTreeMap::new() }
    }

    fn refresh(&mut self, now: Instant) {
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
    }

    fn found(&self, e: &Endpoints) -> bool {
        self.readers.get(&e.request).is_some_and(|t| t.contains(&e.request_type))
            && self.writers.get(&e.reply).is_some_and(|t| t.contains(&e.reply_type))
    }

    /// Whether a server of `e` (its request reader and reply writer, of the
    /// right types) was found at least [`GRACE`] ago.
    pub(crate) fn ready(&mut self, e: &Endpoints, now: Instant) -> bool {
        self.refresh(now);
        if self.found(e) {
            let since = *self.since.entry(e.clone()).or_insert(now);
            now.duration_since(since) >= GRACE
        } else {
            self.since.remove(e);
            false
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
