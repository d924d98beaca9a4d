//! Cooperative interruption of long analyses.
//!
//! The deadlock analysis of a large set of constraints can explore millions
//! of markings. In the language server it runs inside a salsa query, and an
//! edit must not wait for it: salsa cancels a stale query by unwinding from
//! `Database::unwind_if_revision_cancelled`. [`interruptible`] runs the
//! analysis on a worker thread while the calling thread calls that check
//! every few milliseconds; when the check unwinds, the worker is told to
//! stop, and stops at its next [`poll`] (the exploration loops call it every
//! few thousand states). Without [`interruptible`], [`poll`] does nothing.

use std::cell::RefCell;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

thread_local! {
    static STOP: RefCell<Option<Arc<AtomicBool>>> = const { RefCell::new(None) };
}

/// The payload a stopped worker unwinds with.
struct Interrupted;

/// Sets the stop flag when dropped: also when the caller's check unwinds.
struct StopOnDrop<'a>(&'a AtomicBool);

impl Drop for StopOnDrop<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Release);
    }
}

/// Runs `work` on a worker thread and calls `check` on this thread until it
/// ends. `check` interrupts by unwinding (as salsa's cancellation does): the
/// worker then stops at its next [`poll`], and the unwinding goes on once it
/// has. A panic of `work` is resumed on this thread.
pub fn interruptible<R: Send>(check: impl Fn(), work: impl FnOnce() -> R + Send) -> R {
    let stop = Arc::new(AtomicBool::new(false));
    let caller = std::thread::current();
    std::thread::scope(|s| {
        let flag = stop.clone();
        let worker = s.spawn(move || {
            STOP.with(|st| *st.borrow_mut() = Some(flag));
            let r = catch_unwind(AssertUnwindSafe(work));
            caller.unpark();
            r
        });
        let _stop = StopOnDrop(&stop);
        while !worker.is_finished() {
            check();
            std::thread::park_timeout(Duration::from_millis(5));
        }
        match worker.join() {
            Ok(Ok(r)) => r,
            Ok(Err(payload)) | Err(payload) => resume_unwind(payload),
        }
    })
}

/// Stops the current analysis if [`interruptible`] was told to (by
/// unwinding to it); otherwise does nothing.
#[inline]
pub fn poll() {
    let stopped = STOP.with(|st| st.borrow().as_ref().is_some_and(|f| f.load(Ordering::Acquire)));
    if stopped {
        resume_unwind(Box::new(Interrupted));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    #[test]
    fn the_result_comes_back() {
        assert_eq!(interruptible(|| {}, || 6 * 7), 42);
        poll(); // no flag on this thread
    }

    #[test]
    fn an_unwinding_check_stops_the_worker() {
        let polls = Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let seen = polls.clone();
        let calls = Cell::new(0);
        let r = catch_unwind(AssertUnwindSafe(|| {
            interruptible(
                || {
                    calls.set(calls.get() + 1);
                    if calls.get() == 3 {
                        resume_unwind(Box::new("cancelled"));
                    }
                },
                move || loop {
                    seen.fetch_add(1, Ordering::Relaxed);
                    poll();
                    std::thread::sleep(Duration::from_millis(1));
                },
            )
        }));
        let payload = r.expect_err("the check's unwinding goes on");
        assert_eq!(payload.downcast_ref::<&str>(), Some(&"cancelled"));
        assert!(polls.load(Ordering::Relaxed) > 0);
    }

    #[test]
    fn a_panic_of_the_work_is_resumed() {
        let r = catch_unwind(|| interruptible(|| {}, || resume_unwind(Box::new(7u8))));
        assert_eq!(r.unwrap_err().downcast_ref::<u8>(), Some(&7));
    }
}
