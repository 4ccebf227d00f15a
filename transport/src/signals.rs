//! Termination signals (SIGINT, SIGTERM, SIGHUP) for the processes of a team: the launcher,
//! `admm-ta host`, and every agent process.
//!
//! A handler only stores the signal number in an atomic (async-signal-safe); whoever waits
//! looks at [`received`] at every wait slice (20 ms at most) and stops cleanly, so every
//! `Drop` runs and iceoryx2 releases its shared memory. The handlers are installed without
//! `SA_RESTART`, so a sleep in `poll(2)` or `nanosleep` returns early.
//!
//! iceoryx2 installs handlers of its own for these signals the first time it zeroes shared
//! memory (and its nodes may look at them in `Node::wait`); [`install`] lets it do so first
//! and then replaces them, and our nodes are built with `SignalHandlingMode::Disabled`. Its
//! handler also captures job-control and user signals (SIGTSTP, SIGCONT, SIGQUIT, SIGUSR1,
//! …), which it only records: [`install`] gives them back their default actions.
//!
//! [`install`] returns a guard; the handlers stay while a guard lives (the launcher's run,
//! or the whole life of an agent or host process), then the process's own actions come back
//! (those from before the first guard, not iceoryx2's), for every signal touched.

use std::sync::Mutex;
use std::sync::atomic::{AtomicI32, AtomicU32, AtomicUsize, Ordering};

/// The first termination signal received since the handlers were installed (0: none).
static RECEIVED: AtomicI32 = AtomicI32::new(0);
/// How many termination signals arrived (a second Ctrl-C force-kills).
static COUNT: AtomicU32 = AtomicU32::new(0);
/// Live guards ([`install`]), readable without the lock.
static GUARDS: AtomicUsize = AtomicUsize::new(0);

/// The signals that stop a team.
pub const TERMINATION: [i32; 3] = [libc::SIGINT, libc::SIGTERM, libc::SIGHUP];

/// Signals iceoryx2's signal handler captures (only recording them) besides the termination
/// ones: their default actions come back, so that the processes of a team behave as any
/// Unix program — Ctrl-Z (SIGTSTP) suspends, SIGCONT resumes, Ctrl-\\ (SIGQUIT) and SIGUSR1
/// end the process (an agent ended so is a failed agent, named by the launcher).
const DEFAULT_ACTION: [i32; 10] = [
    libc::SIGQUIT,
    libc::SIGTSTP,
    libc::SIGCONT,
    libc::SIGTTIN,
    libc::SIGTTOU,
    libc::SIGUSR1,
    libc::SIGUSR2,
    libc::SIGPROF,
    libc::SIGURG,
    libc::SIGVTALRM,
];

extern "C" fn on_signal(signal: libc::c_int) {
    let _ = RECEIVED.compare_exchange(0, signal, Ordering::AcqRel, Ordering::Acquire);
    COUNT.fetch_add(1, Ordering::AcqRel);
}

/// Live guards and the actions they replaced.
struct Installed {
    guards: usize,
    previous: Vec<(i32, libc::sigaction)>,
}

static INSTALLED: Mutex<Installed> = Mutex::new(Installed {
    guards: 0,
    previous: Vec::new(),
});

/// While it lives, SIGINT, SIGTERM and SIGHUP are recorded instead of ending the process.
#[must_use = "the handlers are removed when the guard drops"]
pub struct SignalGuard(());

/// Installs the handlers (the first live guard installs them and forgets any signal of an
/// earlier run; later ones share them).
pub fn install() -> SignalGuard {
    let mut installed = INSTALLED.lock().unwrap_or_else(|e| e.into_inner());
    if installed.guards == 0 {
        // The actions the last guard gives back: the process's own, saved before iceoryx2
        // can register its handlers — a host that runs teams inside its process (the
        // Python package) gets its handlers back (Python's SIGINT handler raises
        // `KeyboardInterrupt`), not iceoryx2's.
        installed.previous.clear();
        for signal in TERMINATION.into_iter().chain(DEFAULT_ACTION) {
            // SAFETY: reading a signal's action into a zeroed sigaction.
            unsafe {
                let mut old: libc::sigaction = std::mem::zeroed();
                if libc::sigaction(signal, std::ptr::null(), &mut old) == 0 {
                    installed.previous.push((signal, old));
                }
            }
        }
        // iceoryx2 registers its own handlers lazily, once per process: let it do so now,
        // so that it cannot replace ours later.
        let _ = iceoryx2_bb_posix::signal::SignalHandler::last_signal();
        for signal in DEFAULT_ACTION {
            // SAFETY: restoring a signal's default action.
            unsafe { libc::signal(signal, libc::SIG_DFL) };
        }
        RECEIVED.store(0, Ordering::Release);
        COUNT.store(0, Ordering::Release);
        for signal in TERMINATION {
            // SAFETY: a zeroed sigaction is valid; the handler only touches atomics.
            unsafe {
                let mut action: libc::sigaction = std::mem::zeroed();
                action.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as usize;
                action.sa_flags = 0;
                libc::sigemptyset(&mut action.sa_mask);
                libc::sigaction(signal, &action, std::ptr::null_mut());
            }
        }
    }
    installed.guards += 1;
    GUARDS.store(installed.guards, Ordering::Release);
    SignalGuard(())
}

impl Drop for SignalGuard {
    fn drop(&mut self) {
        let mut installed = INSTALLED.lock().unwrap_or_else(|e| e.into_inner());
        installed.guards -= 1;
        GUARDS.store(installed.guards, Ordering::Release);
        if installed.guards == 0 {
            for (signal, old) in installed.previous.drain(..) {
                // SAFETY: restoring the action `sigaction` gave us.
                unsafe { libc::sigaction(signal, &old, std::ptr::null_mut()) };
            }
        }
    }
}

/// The termination signal received, if any (since the handlers were installed).
pub fn received() -> Option<i32> {
    match RECEIVED.load(Ordering::Acquire) {
        0 => None,
        signal => Some(signal),
    }
}

/// The termination signal received while a guard lives: a team running inside this process
/// (the lockstep simulation, threads) stops at its next round or wait slice. `None` when no
/// guard lives, so a signal of an earlier run never stops a later one.
pub fn stop_requested() -> Option<i32> {
    if GUARDS.load(Ordering::Acquire) == 0 {
        return None;
    }
    received()
}

/// How many termination signals arrived.
pub fn count() -> u32 {
    COUNT.load(Ordering::Acquire)
}

/// Records that the team was stopped by `signal` although this process did not get it (an
/// agent of the team got it): the process then ends as if it had.
pub fn record(signal: i32) {
    let _ = RECEIVED.compare_exchange(0, signal, Ordering::AcqRel, Ordering::Acquire);
}

/// The conventional exit code of a process stopped by `signal` (130 for SIGINT, 143 for
/// SIGTERM, 129 for SIGHUP).
pub fn exit_code(signal: i32) -> u8 {
    (128 + signal.clamp(0, 127)) as u8
}

/// Whether an exit code is that of a process stopped by a termination signal; the signal.
pub fn stopped_by_exit_code(code: i32) -> Option<i32> {
    TERMINATION.into_iter().find(|&s| code == 128 + s)
}

/// `SIGINT`, `SIGTERM`, `SIGHUP`, or `signal N`.
pub fn name(signal: i32) -> String {
    match signal {
        libc::SIGINT => "SIGINT".into(),
        libc::SIGTERM => "SIGTERM".into(),
        libc::SIGHUP => "SIGHUP".into(),
        libc::SIGKILL => "SIGKILL".into(),
        libc::SIGSTOP => "SIGSTOP".into(),
        libc::SIGSEGV => "SIGSEGV".into(),
        libc::SIGABRT => "SIGABRT".into(),
        other => format!("signal {other}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_signal_is_recorded_not_fatal_while_the_guard_lives() {
        let guard = install();
        assert_eq!(received(), None);
        // SAFETY: signalling ourselves; the handler records it.
        unsafe { libc::raise(libc::SIGHUP) };
        assert_eq!(received(), Some(libc::SIGHUP));
        assert_eq!(exit_code(libc::SIGHUP), 129);
        assert_eq!(stopped_by_exit_code(143), Some(libc::SIGTERM));
        assert_eq!(stopped_by_exit_code(1), None);
        drop(guard);
    }
}
