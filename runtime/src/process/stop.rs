//! How a launcher's run ends without a failure, and the evidence it reads from its
//! children: a termination signal stops the team (the stop request on the board, the signal
//! forwarded to each agent, a grace period, then SIGKILL and reaping), an agent's exit code
//! says whether a signal stopped it, and `/proc` says whether one is stopped (SIGSTOP).

use crate::board::Board;
use crate::liveness::process_state;
use crate::signals;
use std::process::Child;
use std::time::Duration;

/// How long agents have to leave by themselves after a stop request (termination signal)
/// before they are killed; they notice within a 20 ms wait slice.
pub(crate) const STOP_GRACE: Duration = Duration::from_millis(500);

/// Stops every agent after termination signal `signal` (sent to agent `by`, or to the
/// launcher): the request on the board (and the signal forwarded to each child, for agents
/// that do not read the board), a grace period to leave cleanly (cut short by a second
/// termination signal), then SIGKILL. Every child is reaped; returns how many left by
/// themselves (or had already ended) and how many were killed.
pub(crate) fn stop_children(
    children: &mut [Option<Child>],
    board: Option<&Board>,
    signal: i32,
    by: Option<usize>,
) -> (usize, usize) {
    signals::record(signal);
    if let Some(board) = board {
        let _ = board.request_stop(signal, by);
    }
    let signals_before = signals::count();
    for child in children.iter().flatten() {
        // SAFETY: signalling our own unreaped child (its pid cannot be reused yet).
        unsafe { libc::kill(child.id() as libc::pid_t, signal) };
    }
    let grace_ends = std::time::Instant::now() + STOP_GRACE;
    // Agents that ended before the request count as stopped.
    let mut stopped = children.iter().filter(|c| c.is_none()).count();
    let mut killed = 0;
    loop {
        for slot in children.iter_mut() {
            if let Some(child) = slot
                && !matches!(child.try_wait(), Ok(None))
            {
                *slot = None;
                stopped += 1;
            }
        }
        if children.iter().all(Option::is_none) {
            break;
        }
        let second = signals::count() > signals_before.max(1);
        if std::time::Instant::now() >= grace_ends || second {
            for slot in children.iter_mut() {
                if let Some(mut child) = slot.take() {
                    let _ = child.kill();
                    let _ = child.wait();
                    killed += 1;
                }
            }
            break;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    (stopped, killed)
}

/// The agent whose process is stopped (SIGSTOP or a debugger: state `T` or `t`), if any.
pub(crate) fn stopped_agent(children: &[Option<Child>]) -> Option<usize> {
    children.iter().position(|c| {
        c.as_ref()
            .is_some_and(|c| matches!(process_state(c.id()), Some('T' | 't')))
    })
}

/// The termination signal in an agent's exit description (`exit code 143`), if any.
pub(crate) fn stopped_by_signal(how: &str) -> Option<i32> {
    how.strip_prefix("exit code ")
        .and_then(|c| c.parse().ok())
        .and_then(signals::stopped_by_exit_code)
}
