//! Termination signals on real processes: SIGINT, SIGTERM and SIGHUP to the launcher alone
//! (at start-up and mid-run), to the whole process group (a terminal's Ctrl-C), to one
//! agent, and to an independently started agent; SIGKILL of the launcher. Each must stop
//! the whole team, exit with 128 + the signal and one line saying what stopped it, reap
//! every agent and leave nothing of the run behind (the launcher's SIGKILL leaves its
//! files to the next run's sweep, but no agent may outlive it by more than a second).
//!
//! Deadlines for "finishes" are generous (a loaded 2-core CI machine); the assertions on
//! what happened are exact. The measured times are printed.

use crate::common;

use common::{children_of, leftovers_of, wait_with_deadline};
use std::os::unix::process::CommandExt;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A team that runs until stopped: `robots` agents on `transport`, a million rounds.
fn long_run(robots: usize, transport: &str) -> Child {
    let robots = robots.to_string();
    Command::new(env!("CARGO_BIN_EXE_admm-ta"))
        .args(["solve", "--transport", transport, "--robots", &robots])
        .args(["--tasks", &robots, "--stop", "max-iters", "--max-iters"])
        .args([
            "1000000",
            "--round-timeout",
            "20",
            "--startup-timeout",
            "60",
        ])
        .env_remove("ADMM_TA_FAULT")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        // Its own process group, as a terminal gives a job: a "Ctrl-C" reaches all of it.
        .process_group(0)
        .spawn()
        .expect("the admm-ta binary runs")
}

fn kill(pid: i32, signal: i32) {
    // SAFETY: signalling a process (or group) this test started.
    assert_eq!(unsafe { libc::kill(pid, signal) }, 0, "kill {pid} {signal}");
}

/// Waits until `pid` has `robots` agent children, then `settle` more.
fn wait_for_agents(pid: u32, robots: usize, settle: Duration) {
    let started = Instant::now();
    while children_of(pid).len() < robots {
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "agents never started"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(settle);
}

fn stderr_of(child: &mut Child) -> String {
    let mut text = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut text).unwrap();
    text
}

/// Stops a `robots`-agent run with `signal` sent to `target` (`None`: the launcher) after
/// `settle`; checks exit code, message, reaping and cleanup; returns the time to stop.
fn stop_with(
    robots: usize,
    transport: &str,
    signal: i32,
    group: bool,
    settle: Duration,
    agent: Option<usize>,
) -> (Duration, String) {
    let mut launcher = long_run(robots, transport);
    let pid = launcher.id();
    if settle > Duration::ZERO || agent.is_some() {
        wait_for_agents(pid, robots, settle);
    } else {
        // At start-up: once the launcher spawns its agents (a signal before it installed its
        // handlers ends it by the default action, with no agent yet to leave behind).
        wait_for_agents(pid, 1, Duration::ZERO);
    }
    let target = match agent {
        Some(k) => {
            let needle = format!("--robot {k} ");
            children_of(pid)
                .into_iter()
                .find(|(_, c)| c.contains(&needle))
                .expect("the agent runs")
                .0 as i32
        }
        None if group => -(pid as i32),
        None => pid as i32,
    };
    let sent = Instant::now();
    kill(target, signal);
    let status = wait_with_deadline(&mut launcher, Duration::from_secs(30));
    let took = sent.elapsed();
    let stderr = stderr_of(&mut launcher);
    let what =
        format!("{transport} {robots} agents, signal {signal}, group {group}, agent {agent:?}");
    assert_eq!(status.code(), Some(128 + signal), "{what}: {stderr}");
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "{what}: not one line: {stderr}"
    );
    assert!(stderr.contains("stopped by SIG"), "{what}: {stderr}");
    assert!(stderr.contains("run files removed"), "{what}: {stderr}");
    assert!(
        !stderr.contains("failed"),
        "{what}: blamed somebody: {stderr}"
    );
    assert!(children_of(pid).is_empty(), "{what}: unreaped agents");
    assert!(
        leftovers_of(pid).is_empty(),
        "{what}: {:?}",
        leftovers_of(pid)
    );
    eprintln!("{what}: stopped in {took:?}: {}", stderr.trim());
    (took, stderr)
}

#[test]
fn each_signal_to_the_launcher_mid_run_stops_the_team_and_cleans_up() {
    for (signal, name) in [
        (libc::SIGINT, "SIGINT"),
        (libc::SIGTERM, "SIGTERM"),
        (libc::SIGHUP, "SIGHUP"),
    ] {
        let (_, line) = stop_with(10, "ipc", signal, false, Duration::from_millis(500), None);
        assert!(
            line.contains(&format!("stopped by {name}: 10 agent(s) stopped")),
            "{line}"
        );
    }
}

#[test]
fn twenty_agents_stop_on_a_signal_to_the_launcher_or_to_the_whole_group() {
    stop_with(
        20,
        "ipc",
        libc::SIGTERM,
        false,
        Duration::from_secs(1),
        None,
    );
    // A terminal's Ctrl-C: the launcher and every agent get it at once; one line, no
    // cascade of agent failures.
    let (_, line) = stop_with(20, "ipc", libc::SIGINT, true, Duration::from_secs(1), None);
    assert!(line.contains("stopped by SIGINT"), "{line}");
}

#[test]
fn a_signal_during_start_up_stops_the_team() {
    for transport in ["shm", "ipc", "uds"] {
        stop_with(12, transport, libc::SIGTERM, false, Duration::ZERO, None);
        stop_with(12, transport, libc::SIGINT, true, Duration::ZERO, None);
    }
}

#[test]
fn a_signal_to_one_agent_stops_the_team_naming_it() {
    let transports: &[&str] = if cfg!(feature = "zenoh") {
        &["shm", "ipc", "uds", "zenoh"]
    } else {
        &["shm", "ipc", "uds"]
    };
    for &transport in transports {
        let (_, line) = stop_with(
            8,
            transport,
            libc::SIGTERM,
            false,
            Duration::from_millis(300),
            Some(5),
        );
        assert!(line.contains("stopped by SIGTERM to agent 5"), "{line}");
    }
}

#[test]
fn agents_do_not_outlive_a_launcher_killed_with_sigkill() {
    let mut launcher = long_run(10, "ipc");
    let pid = launcher.id();
    wait_for_agents(pid, 10, Duration::from_millis(300));
    let agents: Vec<u32> = children_of(pid).into_iter().map(|(p, _)| p).collect();
    kill(pid as i32, libc::SIGKILL);
    let _ = launcher.wait();
    let killed = Instant::now();
    // The agents are re-parented (to init or a subreaper, which reaps them): gone or zombie.
    while agents
        .iter()
        .any(|&a| admm_ta::transport::liveness::process_alive(a))
    {
        assert!(
            killed.elapsed() < Duration::from_secs(10),
            "agents outlived their launcher"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    eprintln!(
        "launcher SIGKILL: all 10 agents gone {:?} later",
        killed.elapsed()
    );
    // Its files are swept by the next run (any launcher's).
    let mut next = long_run(3, "ipc");
    wait_for_agents(next.id(), 3, Duration::ZERO);
    kill(next.id() as i32, libc::SIGTERM);
    wait_with_deadline(&mut next, Duration::from_secs(30));
    assert!(leftovers_of(pid).is_empty(), "{:?}", leftovers_of(pid));
}

/// `admm-ta` with `args`, stdout and stderr piped, in process group `group` (0: its own).
fn admm_ta(args: &[&str], group: i32) -> Child {
    Command::new(env!("CARGO_BIN_EXE_admm-ta"))
        .args(args)
        .env_remove("ADMM_TA_FAULT")
        .process_group(group)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the admm-ta binary runs")
}

fn shm_with_prefix(prefix: &str) -> Vec<String> {
    std::fs::read_dir("/dev/shm")
        .map(|d| {
            d.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.starts_with(prefix))
                .collect()
        })
        .unwrap_or_default()
}

/// Every child ends with 128 + `signal` and one line, within the deadline.
fn all_stop_with(children: Vec<(String, Child)>, signal: i32, sent: Instant) {
    for (who, mut child) in children {
        let status = wait_with_deadline(&mut child, Duration::from_secs(30));
        let stderr = stderr_of(&mut child);
        assert_eq!(status.code(), Some(128 + signal), "{who}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{who}: {stderr}");
        assert!(stderr.contains("stopped by SIG"), "{who}: {stderr}");
        assert!(!stderr.contains("failed"), "{who}: {stderr}");
    }
    eprintln!(
        "every process stopped {:?} after the signal",
        sent.elapsed()
    );
}

#[test]
fn a_signal_to_one_independently_started_agent_stops_its_team() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("sig{}", std::process::id());
    let team = dir.path().join("team.toml");
    // Agents 0..4 of 6 start; 4 and 5 never come, so the others wait at start-up.
    std::fs::write(
        &team,
        format!("run = \"{run}\"\nrobots = 6\ncosts = \"random\"\ntasks = 4\ntopology = \"ring\"\nstartup_timeout = 60.0\n"),
    )
    .unwrap();
    let team = team.to_str().unwrap();
    let agents: Vec<(String, Child)> = (0..4)
        .map(|id| {
            let id = id.to_string();
            (
                format!("agent {id}"),
                admm_ta(&["agent", "--team", team, "--robot", &id], 0),
            )
        })
        .collect();
    std::thread::sleep(Duration::from_millis(1500));
    let sent = Instant::now();
    kill(agents[1].1.id() as i32, libc::SIGTERM);
    all_stop_with(agents, libc::SIGTERM, sent);
    let left = shm_with_prefix(&format!("adtat{}-{run}_", common::euid()));
    assert!(left.is_empty(), "{left:?}");
}

#[cfg(feature = "zenoh")]
#[test]
fn a_signal_to_a_zenoh_launcher_or_host_stops_the_team() {
    stop_with(
        6,
        "zenoh",
        libc::SIGTERM,
        false,
        Duration::from_millis(1500),
        None,
    );
    let dir = tempfile::tempdir().unwrap();
    let run = format!("sigz{}", std::process::id());
    let team = dir.path().join("team.toml");
    std::fs::write(
        &team,
        format!(
            "run = \"{run}\"\nrobots = 4\ncosts = \"random\"\ntasks = 4\ntopology = \"ring\"\nstartup_timeout = 60.0\ntransport = \"zenoh\"\n\n[[hosts]]\nname = \"alpha\"\nagents = [0, 1]\nendpoint = \"tcp/127.0.0.1:{}\"\n\n[[hosts]]\nname = \"beta\"\nagents = [2, 3]\nendpoint = \"tcp/127.0.0.1:{}\"\n",
            common::loopback_port(),
            common::loopback_port()
        ),
    )
    .unwrap();
    let team = team.to_str().unwrap();
    let alpha = admm_ta(&["host", "--team", team, "--name", "alpha"], 0);
    let group = alpha.id() as i32;
    let beta = admm_ta(&["host", "--team", team, "--name", "beta"], 0);
    // Agents 0 and 1 start; 2 and 3 never do: the team waits at start-up.
    let mut children = vec![
        ("host alpha".to_string(), alpha),
        ("host beta".to_string(), beta),
    ];
    for id in ["0", "1"] {
        children.push((
            format!("agent {id}"),
            admm_ta(&["agent", "--team", team, "--robot", id], group),
        ));
    }
    std::thread::sleep(Duration::from_secs(3));
    let sent = Instant::now();
    kill(group as i32, libc::SIGTERM);
    all_stop_with(children, libc::SIGTERM, sent);
}

/// The state letter of process `pid` (`T`: stopped), if it exists.
fn state_of(pid: u32) -> Option<char> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    stat[stat.rfind(')')? + 1..].trim_start().chars().next()
}

/// Waits (10 s at most) until `done` holds for every process of `pids`.
fn wait_for_states(pids: &[u32], done: impl Fn(Option<char>) -> bool, what: &str) {
    let started = Instant::now();
    while !pids.iter().all(|&p| done(state_of(p))) {
        assert!(started.elapsed() < Duration::from_secs(10), "never {what}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn job_control_and_user_signals_keep_their_unix_meaning() {
    // A terminal's Ctrl-Z (SIGTSTP to the job's group) suspends the whole team, SIGCONT
    // resumes it; a SIGUSR1 to an agent ends that agent and the launcher names it.
    let mut launcher = long_run(4, "ipc");
    let pid = launcher.id();
    wait_for_agents(pid, 4, Duration::from_millis(300));
    let agents: Vec<u32> = children_of(pid).into_iter().map(|(p, _)| p).collect();
    let team: Vec<u32> = agents.iter().copied().chain([pid]).collect();
    kill(-(pid as i32), libc::SIGTSTP);
    wait_for_states(&team, |s| s == Some('T'), "suspended");
    kill(-(pid as i32), libc::SIGCONT);
    wait_for_states(&team, |s| s != Some('T'), "resumed");
    kill(agents[1] as i32, libc::SIGUSR1);
    let status = wait_with_deadline(&mut launcher, Duration::from_secs(30));
    let stderr = stderr_of(&mut launcher);
    assert_eq!(status.code(), Some(4), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("failed (killed by signal 10)"), "{stderr}");
    assert!(children_of(pid).is_empty(), "unreaped children");
    assert!(leftovers_of(pid).is_empty(), "{:?}", leftovers_of(pid));
}
