//! Agent failures with real processes (ipc, and shm where both are listed): `kill -9` of an
//! agent from outside, and every fault the hidden `ADMM_TA_FAULT` switch injects (exit,
//! abort, hang, NaN payload, wrong round, wrong size). Each run must end with a non-zero exit and one line naming the failed agent, every
//! other agent stopped, every child reaped and nothing of the run left in `/dev/shm` or the
//! run directory.

use crate::common;

use common::{children_of, leftovers_of, wait_with_deadline};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// `admm-ta solve --transport ipc ARGS` (whitespace-separated) with an optional fault.
fn solve(args: &str, fault: Option<&str>) -> Child {
    solve_on("ipc", args, fault)
}

/// `admm-ta solve --transport TRANSPORT ARGS` with an optional fault.
fn solve_on(transport: &str, args: &str, fault: Option<&str>) -> Child {
    let mut command = Command::new(env!("CARGO_BIN_EXE_admm-ta"));
    command
        .args(["solve", "--transport", transport])
        .args(args.split_whitespace())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    match fault {
        Some(fault) => command.env("ADMM_TA_FAULT", fault),
        None => command.env_remove("ADMM_TA_FAULT"),
    };
    command.spawn().expect("the admm-ta binary runs")
}

fn stderr_of(child: &mut Child) -> String {
    use std::io::Read;
    let mut text = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut text)
        .unwrap();
    text
}

fn assert_failure_line(stderr: &str, needles: &[&str]) {
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "not one line: {stderr}"
    );
    for needle in needles {
        assert!(stderr.contains(needle), "'{needle}' not in: {stderr}");
    }
}

/// Long-running 20-agent team (runs until the round limit unless something fails).
const LONG_RUN: &str =
    "--robots 20 --tasks 20 --stop max-iters --max-iters 1000000 --round-timeout 5";

#[test]
fn kill_9_of_an_agent_ends_the_run_within_a_second_and_leaves_nothing() {
    for transport in ["ipc", "shm", "uds"] {
        kill_9_of_agent_7(transport, "");
    }
    if cfg!(feature = "zenoh") {
        kill_9_of_agent_7("zenoh", "");
    }
    // Agents waiting at the global barrier watch for failures as in a round's wait.
    for transport in ["ipc", "shm"] {
        kill_9_of_agent_7(transport, " --global-barrier --method dual");
    }
}

fn kill_9_of_agent_7(transport: &str, extra: &str) {
    let mut launcher = solve_on(transport, &format!("{LONG_RUN}{extra}"), None);
    let pid = launcher.id();
    // Wait until all 20 agents run and have done some rounds.
    let started = Instant::now();
    let victim = loop {
        let agents = children_of(pid);
        if agents.len() == 20
            && let Some((victim, _)) = agents.iter().find(|(_, c)| c.contains("--robot 7 "))
        {
            break *victim;
        }
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "agents never started"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    std::thread::sleep(Duration::from_millis(800));
    let killed = Instant::now();
    let status = Command::new("kill")
        .args(["-9", &victim.to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let exit = wait_with_deadline(&mut launcher, Duration::from_secs(30));
    let detection = killed.elapsed();
    eprintln!("{transport}{extra}: kill -9 of agent 7 of 20 → launcher exit in {detection:?}");
    assert!(!exit.success());
    let stderr = stderr_of(&mut launcher);
    assert_failure_line(
        &stderr,
        &[
            "agent 7 failed",
            "killed by signal 9",
            "19 other agent(s) stopped cleanly, 0 had to be killed",
        ],
    );
    if transport != "ipc" {
        // Only iceoryx2's agents have nodes to clean up.
        assert!(!stderr.contains("iceoryx2"), "{stderr}");
    }
    if transport == "zenoh" {
        // Zenoh's agents record no rounds on the board: no round is claimed.
        assert!(!stderr.contains("after publishing round"), "{stderr}");
    }
    assert!(children_of(pid).is_empty(), "unreaped children");
    assert!(leftovers_of(pid).is_empty(), "{:?}", leftovers_of(pid));
    // Not a timing assertion on a noisy machine: the bound is 30× the target; the
    // measured figure is printed above and in the issue note.
    assert!(detection < Duration::from_secs(30));
}

#[test]
fn every_injected_fault_is_reported_with_the_failed_agent() {
    let cases = [
        ("exit", vec!["agent 3 failed (exit code 3)"]),
        ("abort", vec!["agent 3 failed (killed by signal 6)"]),
        (
            "hang",
            vec![
                "agent 3 failed",
                "after publishing round 10",
                "message from neighbour",
            ],
        ),
        ("nan", vec!["agent 3 failed", "neighbour 3", "NaN"]),
        (
            "wrong-round",
            vec!["agent 3 failed", "neighbour 3, got round 1012"],
        ),
        (
            "wrong-size",
            vec![
                "agent 3 failed",
                "neighbour 3 sent a payload of 63 values, expected 64",
            ],
        ),
    ];
    // Zenoh on one machine: its checks at receipt (round, sender, length) name the agent too.
    // (Its coded messages, in teams of hosts, are refused alike: `zenoh_net::wire`'s tests.)
    let zenoh = cases[3..]
        .iter()
        .map(|case| (case, "zenoh"))
        .filter(|_| cfg!(feature = "zenoh"));
    for ((kind, needles), transport) in cases
        .iter()
        .flat_map(|case| ["ipc", "shm"].map(|t| (case, t)))
        .chain(zenoh)
    {
        let args = "--robots 8 --tasks 8 --topology ring --stop max-iters --max-iters 1000 --round-timeout 1";
        let mut launcher = solve_on(transport, args, Some(&format!("3:10:{kind}")));
        let pid = launcher.id();
        let exit = wait_with_deadline(&mut launcher, Duration::from_secs(60));
        assert!(!exit.success(), "{transport} {kind}: the run succeeded");
        assert_eq!(
            exit.code(),
            Some(4),
            "{transport} {kind}: an agent failure exits 4"
        );
        let stderr = stderr_of(&mut launcher);
        assert_failure_line(&stderr, needles);
        assert!(
            leftovers_of(pid).is_empty(),
            "{kind}: {:?}",
            leftovers_of(pid)
        );
    }
}

#[test]
fn a_fault_switch_for_another_agent_changes_nothing() {
    let args = "--robots 6 --tasks 6 --check --json";
    let mut launcher = solve(args, Some("99:1:exit"));
    let exit = wait_with_deadline(&mut launcher, Duration::from_secs(60));
    assert!(exit.success(), "{}", stderr_of(&mut launcher));
}

#[test]
fn on_failure_continue_resolves_without_the_failed_robot_or_says_why_not() {
    // Case 2 on a ring: the survivors (a chain) re-solve to their own optimum.
    let args = "--robots 12 --tasks 8 --topology ring --on-failure continue --check --json --round-timeout 1";
    for kind in ["exit", "nan", "hang"] {
        let mut launcher = solve(args, Some(&format!("3:10:{kind}")));
        let pid = launcher.id();
        let exit = wait_with_deadline(&mut launcher, Duration::from_secs(60));
        let stderr = stderr_of(&mut launcher);
        assert!(exit.success(), "{kind}: {stderr}");
        let mut stdout = String::new();
        std::io::Read::read_to_string(&mut launcher.stdout.take().unwrap(), &mut stdout).unwrap();
        let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
        let degraded = &report["degraded"];
        assert_eq!(degraded["failed_robot"], 3, "{kind}");
        assert_eq!(degraded["survivors"].as_array().unwrap().len(), 11);
        // The user's robot numbers: robot 3 has no task, the others keep their places.
        assert_eq!(report["robots"], 12);
        let assignment = report["assignment"].as_array().unwrap();
        assert_eq!(assignment.len(), 12, "{kind}: {report}");
        assert!(assignment[3].is_null(), "{kind}: {report}");
        assert!(
            assignment
                .iter()
                .enumerate()
                .all(|(r, t)| r == 3 || t.as_u64().is_some_and(|t| t < 8)),
            "{kind}: {report}"
        );
        assert_eq!(report["check"]["optimal"], true, "{kind}");
        assert!(
            leftovers_of(pid).is_empty(),
            "{kind}: {:?}",
            leftovers_of(pid)
        );
    }
    // Case 1 cannot lose a robot; a chain cannot lose an inner one.
    for (args, needle) in [
        ("--robots 8 --tasks 8", "cannot cover the 8 tasks"),
        ("--robots 9 --tasks 8 --topology chain", "disconnected"),
    ] {
        let args = format!("{args} --on-failure continue");
        // Early: the default (fast) primal certifies an 8×8 complete team within 5 rounds.
        let mut launcher = solve(&args, Some("3:2:exit"));
        let exit = wait_with_deadline(&mut launcher, Duration::from_secs(60));
        assert!(!exit.success());
        assert_failure_line(&stderr_of(&mut launcher), &["agent 3 failed", needle]);
    }
}

#[test]
fn an_agent_with_another_team_shape_is_refused_and_the_team_runs_on() {
    let args = "--robots 6 --tasks 6 --topology ring --stop max-iters --max-iters 100000000 --round-timeout 5";
    let mut launcher = solve(args, None);
    let pid = launcher.id();
    // Whatever happens below, end the team through the launcher (so it cleans up).
    struct EndTeam(u32);
    impl Drop for EndTeam {
        fn drop(&mut self) {
            for (agent, _) in children_of(self.0) {
                let _ = Command::new("kill")
                    .args(["-9", &agent.to_string()])
                    .status();
            }
        }
    }
    let _end_team = EndTeam(pid);
    let runs = admm_ta::runtime::process::namespace::runs_dir();
    let started = Instant::now();
    let scenario_path = loop {
        let found = std::fs::read_dir(&runs).ok().and_then(|d| {
            d.flatten()
                .find(|e| {
                    e.file_name()
                        .to_string_lossy()
                        .starts_with(&format!("{pid:x}"))
                })
                .map(|e| e.path().join("scenario.json"))
                .filter(|p| p.exists())
        });
        if let Some(path) = found
            && children_of(pid).len() == 6
        {
            break path;
        }
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "the team never started"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut scenario: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&scenario_path).unwrap()).unwrap();
    let run_id = scenario["run_id"].as_str().unwrap().to_string();
    // Same run and problem, another method: another payload (n + m values, not n·m).
    scenario["method"] = "dual".into();
    let dir = tempfile::tempdir().unwrap();
    let rogue_path = dir.path().join("scenario.json");
    let text = scenario.to_string();
    admm_ta::runtime::process::private_dir::write_private_file(&rogue_path, text.as_bytes())
        .unwrap();
    let digest = admm_ta::runtime::process::private_dir::sha256_hex(text.as_bytes());
    let rogue = Command::new(env!("CARGO_BIN_EXE_admm-ta"))
        .args(["agent", "--run", &run_id, "--robot", "2", "--scenario"])
        .arg(&rogue_path)
        .args(["--scenario-digest", &digest])
        .output()
        .unwrap();
    assert!(!rogue.status.success());
    assert_failure_line(
        &String::from_utf8_lossy(&rogue.stderr),
        &[
            "agent 2's team file differs from the running team's (digest",
            ": method and parameters differ",
        ],
    );
    // The team was not disturbed; end it by killing one of its agents.
    assert!(launcher.try_wait().unwrap().is_none(), "the team stopped");
    let (victim, _) = children_of(pid).into_iter().next().unwrap();
    Command::new("kill")
        .args(["-9", &victim.to_string()])
        .status()
        .unwrap();
    let exit = wait_with_deadline(&mut launcher, Duration::from_secs(30));
    assert!(!exit.success());
    assert_failure_line(&stderr_of(&mut launcher), &["killed by signal 9"]);
    assert!(leftovers_of(pid).is_empty(), "{:?}", leftovers_of(pid));
}
