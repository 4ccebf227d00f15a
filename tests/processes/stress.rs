//! Stress on real processes, sized for a 2-core CI runner: 100 agent processes for 1000
//! rounds, 50 agents on a complete graph, two identical runs at once. Every run must succeed
//! and leave nothing in `/dev/shm` or the run directory. Longer soaks are `#[ignore]`d
//! (`cargo test --release --test stress -- --ignored`).

use crate::common;

use common::leftovers_of;
use std::process::{Child, Command, Stdio};

fn spawn_solve(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_admm-ta"))
        .arg("solve")
        .args(args)
        .args([
            "--json",
            "--startup-timeout",
            "300",
            "--round-timeout",
            "120",
        ])
        .env_remove("ADMM_TA_FAULT")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the admm-ta binary runs")
}

/// Waits for a run and returns its JSON report; panics with its stderr if it failed or left
/// files behind.
fn finish(child: Child) -> serde_json::Value {
    let pid = child.id();
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "run failed: {stderr}");
    let leftovers = leftovers_of(pid);
    assert!(leftovers.is_empty(), "left behind: {leftovers:?}");
    serde_json::from_slice(&output.stdout).expect("stdout is one JSON object")
}

fn rounds(topology: &str, robots: usize, rounds: usize) -> serde_json::Value {
    let (robots, rounds) = (robots.to_string(), rounds.to_string());
    let args = [
        "--robots",
        &robots,
        "--tasks",
        "4",
        "--topology",
        topology,
        "--transport",
        "ipc",
        "--stop",
        "max-iters",
        "--max-iters",
        &rounds,
    ];
    finish(spawn_solve(&args))
}

#[test]
fn hundred_agent_processes_run_a_thousand_rounds_on_a_ring() {
    let report = rounds("ring", 100, 1000);
    assert_eq!(report["iterations"], 1000);
    assert_eq!(report["robots"], 100);
}

#[test]
fn hundred_agent_processes_run_a_thousand_rounds_on_a_random_graph() {
    let report = rounds("random:0.05", 100, 1000);
    assert_eq!(report["iterations"], 1000);
}

#[test]
fn fifty_agents_on_a_complete_graph_reach_the_optimum() {
    let report = finish(spawn_solve(&[
        "--robots",
        "50",
        "--tasks",
        "50",
        "--transport",
        "ipc",
        "--check",
    ]));
    assert_eq!(report["converged"], true);
    assert_eq!(report["check"]["optimal"], true);
}

#[test]
fn two_identical_runs_at_the_same_time_both_succeed() {
    let args = [
        "--robots",
        "12",
        "--tasks",
        "12",
        "--topology",
        "ring",
        "--transport",
        "ipc",
        "--check",
    ];
    let (a, b) = (spawn_solve(&args), spawn_solve(&args));
    let (a, b) = (finish(a), finish(b));
    assert_eq!(a["assignment"], b["assignment"]);
    assert_eq!(a["iterations"], b["iterations"]);
    assert_eq!(a["check"]["optimal"], true);
}

#[test]
#[ignore = "soak: minutes on 2 cores"]
fn soak_hundred_agents_ten_thousand_rounds() {
    for topology in ["ring", "random:0.05", "chain"] {
        let report = rounds(topology, 100, 10_000);
        assert_eq!(report["iterations"], 10_000);
    }
}

#[test]
fn the_stress_command_runs_forty_ten_agent_teams_four_at_a_time_without_a_failure() {
    let output = Command::new(env!("CARGO_BIN_EXE_admm-ta"))
        .args([
            "stress",
            "--runs",
            "40",
            "--concurrency",
            "4",
            "--robots",
            "10",
        ])
        .args(["--transport", "ipc", "--quiet"])
        .env_remove("ADMM_TA_FAULT")
        .output()
        .expect("the admm-ta binary runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    eprintln!("{stdout}");
    assert!(output.status.success(), "{stdout}{stderr}");
    assert!(
        stdout.contains("40 runs of 10 agents") && stdout.contains(": 0 failed, 0 left behind"),
        "{stdout}"
    );
}
