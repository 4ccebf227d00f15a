//! Blame from evidence, per process transport × fault: the launcher must name the agent
//! that actually failed (by its own index), whatever its neighbours saw, and stop the team
//! in bounded time. Faults: SIGKILL and SIGSTOP from outside, an agent that never starts
//! (with a round deadline shorter than the start-up deadline), one that exits early, one
//! that sends a garbage (NaN) payload. (An agent of another team is refused before it joins:
//! `tests/processes/faults.rs` and `tests/teams/team.rs`.) The measured times to stop are printed; the bound
//! is generous (a loaded 2-core CI machine), the name is exact.

use crate::common;

use common::{children_of, leftovers_of, wait_with_deadline};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

#[derive(Debug, Clone, Copy)]
enum Fault {
    Kill,
    Stop,
    NeverStarts,
    ExitsEarly,
    Garbage,
}

const VICTIM: usize = 5;

/// Runs a long 8-agent ring on `transport` with `fault` striking agent 5; returns the
/// launcher's one line and the time from the fault to the launcher's exit.
fn run(transport: &str, fault: Fault) -> (String, Duration) {
    let env = match fault {
        Fault::NeverStarts => Some(format!("{VICTIM}:0:never-start")),
        Fault::ExitsEarly => Some(format!("{VICTIM}:20:exit")),
        Fault::Garbage => Some(format!("{VICTIM}:20:nan")),
        Fault::Kill | Fault::Stop => None,
    };
    let mut command = Command::new(env!("CARGO_BIN_EXE_admm-ta"));
    command
        .args([
            "solve",
            "--transport",
            transport,
            "--robots",
            "8",
            "--tasks",
            "8",
        ])
        .args([
            "--topology",
            "ring",
            "--stop",
            "max-iters",
            "--max-iters",
            "100000000",
        ])
        .args(["--round-timeout", "2", "--startup-timeout", "5"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    match &env {
        Some(fault) => command.env("ADMM_TA_FAULT", fault),
        None => command.env_remove("ADMM_TA_FAULT"),
    };
    let spawned = Instant::now();
    let mut launcher = command.spawn().expect("the admm-ta binary runs");
    let pid = launcher.id();
    let struck = match fault {
        Fault::Kill | Fault::Stop => {
            let victim = loop {
                let agents = children_of(pid);
                let needle = format!("--robot {VICTIM} ");
                if agents.len() == 8
                    && let Some((victim, _)) = agents.iter().find(|(_, c)| c.contains(&needle))
                {
                    break *victim;
                }
                assert!(
                    spawned.elapsed() < Duration::from_secs(60),
                    "agents never started"
                );
                std::thread::sleep(Duration::from_millis(10));
            };
            std::thread::sleep(Duration::from_millis(500));
            let signal = if matches!(fault, Fault::Kill) {
                libc::SIGKILL
            } else {
                libc::SIGSTOP
            };
            // SAFETY: signalling an agent process of this test's run.
            assert_eq!(unsafe { libc::kill(victim as i32, signal) }, 0);
            Instant::now()
        }
        _ => spawned,
    };
    let status = wait_with_deadline(&mut launcher, Duration::from_secs(60));
    let took = struck.elapsed();
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut launcher.stderr.take().unwrap(), &mut stderr).unwrap();
    let what = format!("{transport} × {fault:?}");
    assert!(!status.success(), "{what}: the run succeeded");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{what}: {stderr}");
    assert!(children_of(pid).is_empty(), "{what}: unreaped agents");
    assert!(
        leftovers_of(pid).is_empty(),
        "{what}: {:?}",
        leftovers_of(pid)
    );
    eprintln!(
        "{what}: stopped {took:.2?} after the fault: {}",
        stderr.trim()
    );
    (stderr, took)
}

fn table(transport: &str, faults: &[Fault]) {
    for &fault in faults {
        let (line, took) = run(transport, fault);
        assert!(
            line.contains(&format!("agent {VICTIM} failed")),
            "{transport} × {fault:?} blamed another agent: {line}"
        );
        // Generous: a round deadline (2 s) or a start-up deadline (5 s) plus a loaded machine.
        assert!(
            took < Duration::from_secs(30),
            "{transport} × {fault:?}: {took:?}"
        );
        if matches!(fault, Fault::Stop) {
            assert!(line.contains("state T in /proc"), "{line}");
            // A stopped agent reports nothing: it is never named as its own reporter.
            assert!(
                !line.contains(&format!("reported by agent {VICTIM}")),
                "{transport}: the stopped agent named as its own reporter: {line}"
            );
        }
        if matches!(fault, Fault::NeverStarts) {
            assert!(
                line.contains(&format!("missing: agent(s) [{VICTIM}]")),
                "{line}"
            );
        }
    }
}

#[test]
fn ipc_names_the_agent_that_failed() {
    use Fault::*;
    table("ipc", &[Kill, Stop, NeverStarts, ExitsEarly, Garbage]);
}

#[test]
fn shm_names_the_agent_that_failed() {
    use Fault::*;
    table("shm", &[Kill, Stop, NeverStarts, ExitsEarly, Garbage]);
}

#[test]
fn uds_names_the_agent_that_failed() {
    // uds carries no payload faults (its capabilities say so): the process faults only.
    use Fault::*;
    table("uds", &[Kill, Stop, NeverStarts]);
}

#[cfg(feature = "zenoh")]
#[test]
fn zenoh_names_the_agent_that_failed() {
    use Fault::*;
    table("zenoh", &[Kill, Stop, ExitsEarly, Garbage]);
}
