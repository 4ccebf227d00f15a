//! How a launcher's run ends without a failure, and the evidence it reads from its
//! children: a termination signal stops the team (the stop request on the board, the signal
//! forwarded to each agent, a grace period, then SIGKILL and reaping), an agent's exit code
//! says whether a signal stopped it, `/proc` says whether one is stopped (SIGSTOP), and the
//! other agents' last lines say who saw the failure best.

use admm_ta_transport::board::Board;
use admm_ta_transport::liveness::process_state;
use admm_ta_transport::signals;
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

/// The agent whose error line best says what happened to `culprit`, among the agents that
/// failed (`lines`: index and last log line, in the order they failed): the first that says
/// what went wrong (not "stopped … because agent …"), else `culprit` itself (its exit says
/// how it ended). A `stopped` culprit (SIGSTOP) says nothing: it is never its own reporter
/// while another agent failed, and an agent that timed out waiting for it (the line of
/// [`admm_ta_transport::exchange::ExchangeError::Timeout`]) comes first, before agents that timed out on
/// a neighbour that was itself waiting.
pub(crate) fn reporter(culprit: usize, lines: &[(usize, String)], stopped: bool) -> usize {
    let others = || {
        lines
            .iter()
            .filter(move |(i, _)| !(stopped && *i == culprit))
    };
    others()
        .find(|(_, line)| stopped && waited_for(line, culprit))
        .or_else(|| others().find(|(_, line)| !line.contains("because agent")))
        .or_else(|| others().next().filter(|_| stopped))
        .map_or(culprit, |(i, _)| *i)
}

/// Whether an error line is a round timeout waiting for `culprit`: "… message from
/// neighbour(s) [3, 5] …".
fn waited_for(line: &str, culprit: usize) -> bool {
    line.split_once("from neighbour(s) [")
        .and_then(|(_, rest)| rest.split_once(']'))
        .is_some_and(|(list, _)| list.split(", ").any(|n| n.parse() == Ok(culprit)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(v: &[(usize, &str)]) -> Vec<(usize, String)> {
        v.iter().map(|&(i, l)| (i, l.to_string())).collect()
    }

    #[test]
    fn the_reporter_is_who_saw_the_culprit() {
        let timeout = |agent: usize, missing: &str| {
            format!("agent {agent}: no round-9 message from neighbour(s) {missing} within 2s")
        };
        // Agent 0 timed out on 7 (itself waiting), agent 4 on the stopped agent 5.
        let seen = lines(&[(0, &timeout(0, "[7]")), (4, &timeout(4, "[3, 5]")), (5, "")]);
        assert_eq!(reporter(5, &seen, true), 4);
        // Nobody waited for it: the first line that says what went wrong, never the culprit.
        let cascade = lines(&[
            (5, "no message"),
            (2, "agent 2: stopped at round 9 because agent 5 failed"),
            (0, &timeout(0, "[15]")),
        ]);
        assert_eq!(reporter(5, &cascade, true), 0);
        assert_eq!(
            reporter(5, &lines(&[(5, "x"), (2, "because agent 5")]), true),
            2
        );
        // A stopped culprit alone, or a culprit that reported its own failure.
        assert_eq!(reporter(5, &lines(&[(5, "x")]), true), 5);
        // A culprit that ended by itself first is its own best reporter.
        let own = lines(&[(5, "agent 5: bad input"), (4, &timeout(4, "[5]"))]);
        assert_eq!(reporter(5, &own, false), 5);
        assert_eq!(reporter(5, &own, true), 4);
        // Everybody else only stopped because of it: the culprit's own exit tells most.
        let echoes = lines(&[(2, "agent 2: stopped at round 9 because agent 5 failed")]);
        assert_eq!(reporter(5, &echoes, false), 5);
        assert_eq!(reporter(5, &echoes, true), 2);
        assert!(!waited_for(&timeout(1, "[15, 25]"), 5));
    }
}
