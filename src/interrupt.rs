//! SIGINT and SIGTERM during `mcl run`: the trace is flushed, then the
//! process exits with 128 + the signal's number (130 after SIGINT, 143 after
//! SIGTERM), so that an interrupted run leaves every record it made.
//!
//! [`install`] blocks both signals in the calling thread, which every thread
//! started afterwards inherits, and starts one thread that waits for them
//! with `sigwait`: the work on a signal runs on an ordinary thread, not in a
//! signal handler. Call it before any other thread starts.

use std::sync::Mutex;

type Hook = Box<dyn Fn() + Send>;

/// What to do on a signal before exiting.
static HOOKS: Mutex<Vec<Hook>> = Mutex::new(Vec::new());

/// The exit status after SIGINT.
pub const EXIT_SIGINT: i32 = 128 + 2;
/// The exit status after SIGTERM.
pub const EXIT_SIGTERM: i32 = 128 + 15;

/// Blocks SIGINT and SIGTERM and starts the thread that handles them.
#[cfg(unix)]
pub fn install() {
    // SAFETY: plain libc calls on a signal set owned by this frame; the mask
    // is changed before other threads start (see the module's comment).
    let set = unsafe {
        let mut set: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut set);
        libc::sigaddset(&mut set, libc::SIGINT);
        libc::sigaddset(&mut set, libc::SIGTERM);
        if libc::pthread_sigmask(libc::SIG_BLOCK, &set, std::ptr::null_mut()) != 0 {
            return;
        }
        set
    };
    let waiter = std::thread::Builder::new().name("signals".into()).spawn(move || loop {
        let mut sig: libc::c_int = 0;
        // SAFETY: `set` is a valid signal set and `sig` a valid place.
        if unsafe { libc::sigwait(&set, &mut sig) } != 0 {
            continue;
        }
        for hook in HOOKS.lock().unwrap_or_else(|e| e.into_inner()).iter() {
            hook();
        }
        let (name, code) = if sig == libc::SIGINT { ("SIGINT", EXIT_SIGINT) } else { ("SIGTERM", EXIT_SIGTERM) };
        eprintln!("interrupted by {name}");
        std::process::exit(code);
    });
    if waiter.is_err() {
        // Without the waiter the signals must not stay blocked.
        // SAFETY: as above.
        unsafe {
            libc::pthread_sigmask(libc::SIG_UNBLOCK, &set, std::ptr::null_mut());
        }
    }
}

/// Without Unix signals, nothing to install.
#[cfg(not(unix))]
pub fn install() {}

/// Runs `hook` on SIGINT or SIGTERM, before the process exits.
pub fn on_signal(hook: impl Fn() + Send + 'static) {
    HOOKS.lock().unwrap_or_else(|e| e.into_inner()).push(Box::new(hook));
}
