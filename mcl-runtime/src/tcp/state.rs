//! The served vehicle's state: the actions each session executed, saved in
//! a state file before they are acknowledged and read back at start.

use std::io;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use serde::{Deserialize, Serialize};

use crate::link::Action;

use super::*;

/// An action executed by a vehicle, as saved in a state file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Executed {
    /// Mission time of execution.
    pub t: f64,
    /// How many messages the vehicle had sent in the session before it
    /// executed the action (absent in older state files: then every
    /// message due at `t` was).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sent_before: Option<u64>,
    pub action: Action,
}

/// One session of a state file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SavedSession {
    pub mission: String,
    pub run: String,
    /// Session id (sent in `welcome`).
    pub session: String,
    /// Wall-clock time (seconds since 1970) of mission time 0.
    pub epoch_unix: f64,
    pub speed: f64,
    /// Every action executed, in order.
    pub executed: Vec<Executed>,
}

impl SavedSession {
    /// Highest seq executed.
    pub fn last_seq(&self) -> u64 {
        self.executed.iter().map(|e| e.action.seq).max().unwrap_or(0)
    }

    pub(super) fn key(&self) -> SessionKey {
        SessionKey { mission: self.mission.clone(), run: self.run.clone() }
    }
}

/// The content of a `--state` file.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StateFile {
    pub version: u32,
    pub sessions: Vec<SavedSession>,
}

impl StateFile {
    /// Reads a state file; a missing file is an empty state.
    pub fn load(path: &std::path::Path) -> io::Result<StateFile> {
        use mcl_net::input::{read_source, Reason};
        match read_source(path) {
            Ok(text) => serde_json::from_str(&text).map_err(|e| {
                io::Error::new(io::ErrorKind::InvalidData, format!("{}: not a state file: {e}", path.display()))
            }),
            Err(e) if e.reason == Reason::NotFound => Ok(StateFile { version: 1, sessions: Vec::new() }),
            Err(e) => Err(io::Error::other(e.to_string())),
        }
    }

    /// Writes a state file atomically (a temporary file renamed over it).
    pub fn save(&self, path: &std::path::Path) -> io::Result<()> {
        let text = serde_json::to_string(self).map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e))?;
        let mut tmp = path.as_os_str().to_owned();
        tmp.push(".tmp");
        let tmp = PathBuf::from(tmp);
        std::fs::write(&tmp, text)?;
        std::fs::rename(&tmp, path)
    }
}

/// The state file shared by the sessions of one process.
#[derive(Clone)]
pub(super) struct Store {
    pub path: PathBuf,
    pub max: usize,
    pub state: Arc<Mutex<StateFile>>,
}

impl Store {
    pub fn put(&self, s: &SavedSession) -> io::Result<()> {
        let mut g = lock(&self.state);
        match g.sessions.iter_mut().find(|x| x.mission == s.mission && x.run == s.run) {
            Some(x) => *x = s.clone(),
            None => g.sessions.push(s.clone()),
        }
        if g.sessions.len() > self.max {
            // Forget the oldest runs.
            g.sessions.sort_by(|a, b| a.epoch_unix.total_cmp(&b.epoch_unix));
            let excess = g.sessions.len() - self.max;
            g.sessions.drain(..excess);
        }
        g.save(&self.path)
    }
}
