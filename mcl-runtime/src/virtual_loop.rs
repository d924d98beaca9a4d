//! The one discrete-event loop of virtual time.
//!
//! A single run ([`crate::driver::run_virtual`]: a player and its vehicle),
//! a coordinated run ([`crate::multi::run_virtual`]: players, vehicles and
//! the messages between them) and plan execution (`mcl-plan`'s `run.rs`:
//! each step's mission against the vehicle) all go through [`run`]: each
//! says what its participants will do next ([`Discrete::deadlines`]) and
//! takes one input ([`Discrete::step`]); the loop alone decides which input
//! comes next (the earliest; at equal times the first listed), when the run
//! is stuck (nothing is scheduled), when the time limit has passed, and
//! when mission time no longer advances ([`ZERO_TIME_INPUTS`] inputs at one
//! instant: a loop whose tasks answer at once).

use std::future::Future;
use std::pin::pin;
use std::task::{Context, Poll, Waker};

use crate::clock::Clock;
use crate::driver::Limits;

/// Inputs in a row at one instant of virtual time after which a run is
/// stopped as a zero-time loop (tasks that answer at once, in a loop).
pub const ZERO_TIME_INPUTS: u64 = 10_000;

/// What the virtual-time loop drives.
pub trait Discrete {
    /// Names one source of inputs (a player's timers, a vehicle's messages).
    type Source: Copy;

    /// True once the run is over (every mission it plays has ended).
    fn is_over(&mut self) -> bool;

    /// Appends to `out` the time of the next input of each source that has
    /// one, in the order that breaks ties (the first listed goes first).
    fn deadlines(&self, out: &mut Vec<(f64, Self::Source)>);

    /// Takes the input of `source` due at `t`, and settles what it causes
    /// at that instant. The future of a driver without transport (a single
    /// run, a plan) is ready at once.
    fn step(&mut self, t: f64, source: Self::Source) -> impl Future<Output = Result<(), String>>;
}

/// How [`run`] ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stop {
    /// [`Discrete::is_over`] said so.
    Over,
    /// Nothing is scheduled: no source has a next input (stuck).
    Quiescent,
    /// The next input is after the time limit (the limit).
    TimeLimit(f64),
    /// Too many inputs at one instant (that instant).
    ZeroTimeLoop(f64),
}

/// Steps `d` input after input until it is over, stuck, past the time limit
/// of `limits`, or looping in zero time.
pub async fn run<D: Discrete>(d: &mut D, limits: &Limits) -> Result<Stop, String> {
    run_paced(d, limits, None).await
}

/// [`run`], each input taken no earlier than the instant `pace` gives its
/// time (`mcl run --sim --speed X`: the simulated run stepped against the
/// wall clock scaled by X). The inputs, their order and their times are
/// those of [`run`]: only when they happen changes.
pub async fn run_paced<D: Discrete>(d: &mut D, limits: &Limits, pace: Option<Clock>) -> Result<Stop, String> {
    let mut same = SameInstant::default();
    let mut next = Vec::new();
    loop {
        if d.is_over() {
            return Ok(Stop::Over);
        }
        next.clear();
        d.deadlines(&mut next);
        let mut earliest: Option<(f64, D::Source)> = None;
        for &(t, source) in &next {
            if earliest.is_none_or(|(e, _)| t < e) {
                earliest = Some((t, source));
            }
        }
        let Some((t, source)) = earliest else {
            return Ok(Stop::Quiescent);
        };
        if let Some(limit) = limits.time_limit {
            if t > limit {
                return Ok(Stop::TimeLimit(limit));
            }
        }
        if same.tick(t) {
            return Ok(Stop::ZeroTimeLoop(t));
        }
        if let Some(at) = pace.map(|c| c.instant_at(t)) {
            // Behind the clock (the timer's resolution is a millisecond): no wait.
            if at > tokio::time::Instant::now() {
                tokio::time::sleep_until(at).await;
            }
        }
        d.step(t, source).await?;
    }
}

/// [`run`] for a driver whose steps never wait (no transport): a single run,
/// a plan's step.
pub fn run_now<D: Discrete>(d: &mut D, limits: &Limits) -> Result<Stop, String> {
    let mut fut = pin!(run(d, limits));
    match fut.as_mut().poll(&mut Context::from_waker(Waker::noop())) {
        Poll::Ready(r) => r,
        Poll::Pending => Err("a virtual-time step waited for something outside the run".to_string()),
    }
}

/// The message of a zero-time loop at `t`.
pub fn zero_time_message(t: f64) -> String {
    format!(
        "zero-time loop: {ZERO_TIME_INPUTS} inputs at t={t} s without mission time advancing (a loop whose tasks answer at once?)"
    )
}

/// Counts the inputs of a virtual-time run at one instant.
#[derive(Debug, Default)]
struct SameInstant {
    t: f64,
    n: u64,
}

impl SameInstant {
    /// One more input at `t`; true when there were too many at that instant.
    fn tick(&mut self, t: f64) -> bool {
        if t > self.t {
            self.t = t;
            self.n = 0;
        }
        self.n += 1;
        self.n > ZERO_TIME_INPUTS
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sources that each fire at fixed times; `over` after `stop_after` steps.
    struct Script {
        times: Vec<Vec<f64>>,
        taken: Vec<(f64, usize)>,
        stop_after: usize,
    }

    impl Discrete for Script {
        type Source = usize;
        fn is_over(&mut self) -> bool {
            self.taken.len() >= self.stop_after
        }
        fn deadlines(&self, out: &mut Vec<(f64, usize)>) {
            for (i, ts) in self.times.iter().enumerate() {
                if let Some(&t) = ts.first() {
                    out.push((t, i));
                }
            }
        }
        async fn step(&mut self, t: f64, source: usize) -> Result<(), String> {
            self.times[source].remove(0);
            self.taken.push((t, source));
            Ok(())
        }
    }

    fn limits(t: Option<f64>) -> Limits {
        Limits { time_limit: t, default_limit: false, connect_timeout: None }
    }

    #[test]
    fn earliest_first_ties_to_the_first_listed() {
        let mut s = Script { times: vec![vec![2.0, 5.0], vec![1.0, 2.0]], taken: Vec::new(), stop_after: 10 };
        assert_eq!(run_now(&mut s, &limits(None)), Ok(Stop::Quiescent));
        assert_eq!(s.taken, [(1.0, 1), (2.0, 0), (2.0, 1), (5.0, 0)]);
    }

    #[test]
    fn over_time_limit_and_zero_time_loop() {
        let mut s = Script { times: vec![vec![1.0, 2.0, 3.0]], taken: Vec::new(), stop_after: 2 };
        assert_eq!(run_now(&mut s, &limits(None)), Ok(Stop::Over));
        let mut s = Script { times: vec![vec![1.0, 20.0]], taken: Vec::new(), stop_after: 9 };
        assert_eq!(run_now(&mut s, &limits(Some(10.0))), Ok(Stop::TimeLimit(10.0)));
        assert_eq!(s.taken, [(1.0, 0)]);
        let n = ZERO_TIME_INPUTS as usize;
        let mut s = Script { times: vec![vec![4.0; n + 5]], taken: Vec::new(), stop_after: usize::MAX };
        assert_eq!(run_now(&mut s, &limits(None)), Ok(Stop::ZeroTimeLoop(4.0)));
        assert_eq!(s.taken.len(), n);
    }
}
