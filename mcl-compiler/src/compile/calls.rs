//! The nodes of each call adapter of a compiled mission, found again in the
//! net (used by multi-vehicle coordination, seed chapter 6 and SEED-NOTES
//! item 9).
//!
//! Every call site `N` of a mission compiles to an adapter block (see
//! [`super::compile_mission`] and `docs/blocks.md`):
//!
//! | node | meaning |
//! |---|---|
//! | `begin`: the place the parent marks to start the call | the call is *waiting*: its parent started it, it has not taken the task yet (the seed's `P^wait` of the PW-transformation) |
//! | transition `callN.start` | the call *starts*: takes the task's lock, binds its arguments, starts the task |
//! | place `callN.run` | the call *runs* (its task works for it) |
//! | transitions `callN.ok` / `callN.fail` | the call *completes* with that outcome: `run` → `stopping` |
//! | transition `callN.abort` | the parent aborts the running call: `run` → `stopping` |
//! | place `callN.stopping` | the task is going back to rest (its last immediate transitions, e.g. the disable of its primitive, still use this call's binding); the call still holds the lock |
//! | transition `callN.release` | the call gives the lock back (deferred: the task is at rest); the call has *ended* |
//! | transition `callN.cancel` | the parent aborts the call while it waits: it never starts |
//!
//! [`call_nodes`] returns these nodes for every call site, read from the
//! binding of the `start` transition (task, call site, label) and from the
//! adapter's arcs, so it does not depend on ids other than the `callN.`
//! prefix of the adapter's own nodes.

use mcl_net::{Net, PlaceId, TransitionId};

/// The nodes of one call adapter.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CallNodes {
    /// Call site id (unique in the mission; `N` of `callN`).
    pub call_site: u32,
    /// Task called.
    pub task: String,
    /// The call's label (`Task( ... ) : label`), if any.
    pub label: Option<String>,
    /// Where the call sits, when that changes what a mock vehicle answers
    /// by default (`monitor_condition`, `while_condition`,
    /// `negated_while_condition`; [`mcl_net::CallBinding::role`]).
    pub role: Option<String>,
    /// Where the parent puts the token that starts the call (the waiting place).
    pub begin: PlaceId,
    /// Where the parent puts the token that aborts the call.
    pub abort_place: PlaceId,
    /// `callN.run`.
    pub run: PlaceId,
    /// `callN.stopping`.
    pub stopping: PlaceId,
    /// `callN.start`.
    pub start: TransitionId,
    /// `callN.ok`.
    pub ok: TransitionId,
    /// `callN.fail`.
    pub fail: TransitionId,
    /// `callN.cancel`.
    pub cancel: TransitionId,
    /// `callN.abort`.
    pub abort: TransitionId,
    /// `callN.release`.
    pub release: TransitionId,
}

impl CallNodes {
    /// The places in which the call holds its task: `run` and `stopping`.
    pub fn running(&self) -> [PlaceId; 2] {
        [self.run, self.stopping]
    }

    /// The transitions after which the call no longer holds its task:
    /// `release` (a call that completes or is aborted goes through
    /// `stopping` and gives its lock back exactly once, there).
    pub fn ended(&self) -> [TransitionId; 1] {
        [self.release]
    }

    /// The transitions that put the call into its waiting place (the
    /// producers of `begin` in `net`).
    pub fn arrived<'n>(&self, net: &'n Net) -> &'n [TransitionId] {
        net.producers(self.begin)
    }
}

/// The adapter nodes of every call site of a compiled mission, by call site.
/// Call sites whose adapter is incomplete (not produced by this compiler) are
/// skipped.
pub fn call_nodes(net: &Net) -> Vec<CallNodes> {
    let mut out = Vec::new();
    for t in net.transition_ids() {
        let Some(tr) = net.transition(t) else { continue };
        let Some(b) = &tr.binding else { continue };
        let p = format!("call{}", b.call_site);
        if tr.id != format!("{p}.start") {
            continue;
        }
        let tid = |s: &str| net.transition_by_id(&format!("{p}.{s}"));
        let pid = |s: &str| net.place_by_id(&format!("{p}.{s}"));
        let (Some(run), Some(stopping)) = (pid("run"), pid("stopping")) else { continue };
        let (Some(ok), Some(fail), Some(cancel), Some(abort), Some(release)) =
            (tid("ok"), tid("fail"), tid("cancel"), tid("abort"), tid("release"))
        else {
            continue;
        };
        // `cancel` consumes exactly the call's abort and begin places; `start`
        // consumes begin and the task's lock.
        let cancel_in: Vec<PlaceId> = net.pre(cancel).iter().map(|&(q, _)| q).collect();
        let Some(&(begin, _)) = net.pre(t).iter().find(|(q, _)| cancel_in.contains(q)) else { continue };
        let Some(&abort_place) = cancel_in.iter().find(|&&q| q != begin) else { continue };
        out.push(CallNodes {
            call_site: b.call_site,
            task: b.task.clone(),
            label: b.label.clone(),
            role: b.role.clone(),
            begin,
            abort_place,
            run,
            stopping,
            start: t,
            ok,
            fail,
            cancel,
            abort,
            release,
        });
    }
    out.sort_by_key(|c| c.call_site);
    out
}
