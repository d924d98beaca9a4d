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
use crate::operator::{self, Command};

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

    /// Takes an operator's command for participant `who` (the index of the
    /// receiver it came on, [`run_operated`]) at `t`: traces and journals
    /// it; `abort` and `answer` become inputs. The loop itself pauses and
    /// resumes. A driver that takes no commands ignores them.
    fn operator(&mut self, t: f64, who: usize, c: Command) -> impl Future<Output = Result<(), String>> {
        let _ = (t, who, c);
        std::future::ready(Ok(()))
    }
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
    run_operated(d, limits, pace, Vec::new()).await
}

/// [`run_paced`] taking an operator's commands from `commands` while it
/// waits for the clock (`mcl run --sim --operator-token`, docs/monitor.md):
/// `pause` stops the loop and mission time until `resume` (the clock then
/// goes on from the instant of the pause; a `pause` while paused and a
/// `resume` while running are ignored); `abort` and `answer` become inputs
/// at the clock's mission time ([`Discrete::operator`]), between the last
/// input and the next. The run ends when it is over even while paused.
pub async fn run_operated<D: Discrete>(
    d: &mut D,
    limits: &Limits,
    mut pace: Option<Clock>,
    commands: Vec<operator::Receiver>,
) -> Result<Stop, String> {
    let mut commands: Vec<Option<operator::Receiver>> = commands.into_iter().map(Some).collect();
    let mut same = SameInstant::default();
    let mut next = Vec::new();
    // The time of the last input; the instant of the pause while paused.
    let mut last = 0.0_f64;
    let mut paused: Option<f64> = None;
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
        if paused.is_none() {
            let Some((t, _)) = earliest else {
                return Ok(Stop::Quiescent);
            };
            if let Some(limit) = limits.time_limit {
                if t > limit {
                    return Ok(Stop::TimeLimit(limit));
                }
            }
        }
        // Until the clock reaches the next input (never while paused).
        let at = match (paused, earliest) {
            (None, Some((t, _))) => pace.map(|c| c.instant_at(t)),
            _ => None,
        };
        let wait = async move {
            match (paused, at) {
                (Some(_), _) => std::future::pending::<()>().await,
                // Behind the clock (the timer's resolution is a millisecond): no wait.
                (None, Some(at)) if at > tokio::time::Instant::now() => tokio::time::sleep_until(at).await,
                _ => {}
            }
        };
        let command = if commands.iter().all(Option::is_none) {
            wait.await;
            None
        } else {
            tokio::select! {
                biased;
                c = next_command(&mut commands) => Some(c),
                _ = wait => None,
            }
        };
        if let Some((who, c)) = command {
            let next_t = earliest.map_or(f64::INFINITY, |(t, _)| t);
            let now = paused.unwrap_or_else(|| pace.map_or(last, |k| k.now()).max(last).min(next_t));
            match &c {
                Command::Pause if paused.is_some() => continue,
                Command::Resume if paused.is_none() => continue,
                Command::Pause => paused = Some(now),
                Command::Resume => {
                    paused = None;
                    pace = pace.map(|k| Clock::new(k.speed(), now));
                }
                Command::Abort | Command::Answer { .. } => last = now,
            }
            d.operator(now, who, c).await?;
            continue;
        }
        let Some((t, source)) = earliest else { continue };
        if same.tick(t) {
            return Ok(Stop::ZeroTimeLoop(t));
        }
        last = t;
        d.step(t, source).await?;
    }
}

/// The next command on any of `commands`, with the index of its receiver
/// (a closed one is dropped; none left: never ready).
async fn next_command(commands: &mut [Option<operator::Receiver>]) -> (usize, Command) {
    std::future::poll_fn(|cx| {
        for (i, slot) in commands.iter_mut().enumerate() {
            if let Some(rx) = slot {
                match rx.poll_recv(cx) {
                    Poll::Ready(Some(c)) => return Poll::Ready((i, c)),
                    Poll::Ready(None) => *slot = None,
                    Poll::Pending => {}
                }
            }
        }
        Poll::Pending
    })
    .await
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
