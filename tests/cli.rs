//! The `admm-ta` binary end to end: the demo, JSON output, and bad input that must give
//! one clear line and a non-zero exit, never a panic.

use std::path::Path;
use std::process::{Command, Output};

fn admm_ta(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_admm-ta"))
        .args(args)
        .output()
        .expect("the admm-ta binary runs")
}

fn json(output: &Output) -> serde_json::Value {
    assert!(
        output.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).expect("stdout is one JSON object")
}

/// Exit code ≠ 0 and exactly one line on stderr that mentions `needle`.
fn assert_clear_error(output: &Output, needle: &str) {
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "expected failure, got success");
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "not one line: {stderr}"
    );
    assert!(
        stderr.to_lowercase().contains(&needle.to_lowercase()),
        "'{needle}' not in: {stderr}"
    );
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn demo_solves_its_default_problem_optimally() {
    let report = json(&admm_ta(&["demo", "--json"]));
    assert_eq!(report["robots"], 20);
    assert_eq!(report["tasks"], 20);
    assert_eq!(report["transport"], "ipc");
    assert_eq!(report["check"]["optimal"], true);
    assert_eq!(report["converged"], true);
    let human = admm_ta(&["demo"]);
    assert!(human.status.success());
    let text = String::from_utf8_lossy(&human.stdout);
    assert!(text.contains("optimal cost"), "{text}");
    assert!(text.contains("round latency (µs): p50"), "{text}");
    assert!(text.contains("20 agent processes connected"), "{text}");
}

#[test]
fn ipc_solve_reports_round_latency_and_start_up() {
    let solve = |flags: &str| {
        let args: Vec<&str> = "solve --robots 20 --tasks 20 --json"
            .split_whitespace()
            .chain(flags.split_whitespace())
            .collect();
        json(&admm_ta(&args))
    };
    let report = solve("--transport ipc --check");
    assert_eq!(report["check"]["optimal"], true);
    assert_eq!(report["stop"], "local");
    for component in ["round", "wait", "compute", "publish"] {
        let p = &report["round_latency_us"][component];
        assert!(p["p50"].as_f64().unwrap() > 0.0, "{component}: {p}");
        assert!(p["p99"].as_f64().unwrap() >= p["p50"].as_f64().unwrap());
        assert!(p["max"].as_f64().unwrap() >= p["p99"].as_f64().unwrap());
    }
    assert!(report["startup_ms"].as_f64().unwrap() > 0.0);
    let sim = solve("--transport sim");
    assert_eq!(sim["iterations"], report["iterations"]);
    assert_eq!(sim["assignment"], report["assignment"]);
}

#[test]
fn solve_json_has_the_documented_fields() {
    let report = json(&admm_ta(&[
        "solve",
        "--robots",
        "8",
        "--tasks",
        "5",
        "--seed",
        "3",
        "--topology",
        "ring",
        "--json",
        "--check",
    ]));
    for key in [
        "assignment",
        "cost",
        "iterations",
        "converged",
        "repaired",
        "method",
        "transport",
    ] {
        assert!(report.get(key).is_some(), "missing {key}");
    }
    assert_eq!(report["method"], "primal");
    assert_eq!(report["transport"], "sim");
    assert_eq!(report["case"], 2);
    assert_eq!(report["assignment"].as_array().unwrap().len(), 8);
    assert!(report["check"]["gap"].as_f64().unwrap().abs() < 1e-9);
    assert!(report["check"]["optimal_cost"].as_f64().is_some());
}

#[test]
fn every_topology_kind_and_a_topology_file_work() {
    let dir = tempfile::tempdir().unwrap();
    let file = write(
        dir.path(),
        "net.toml",
        "robots = 4\nedges = [[0, 1], [1, 2], [2, 3]]\n",
    );
    for topology in [
        "complete",
        "chain",
        "ring",
        "star",
        "grid",
        "random:0.5",
        "geometric:0.8",
        &file,
    ] {
        let report = json(&admm_ta(&[
            "solve",
            "--robots",
            "4",
            "--tasks",
            "4",
            "--topology",
            topology,
            "--json",
            "--check",
        ]));
        assert_eq!(report["check"]["optimal"], true, "{topology}");
    }
    let printed = admm_ta(&["topology", "--kind", "grid", "--robots", "6"]);
    assert!(String::from_utf8_lossy(&printed.stdout).contains("robots = 6"));
}

#[test]
fn costs_in_metres_or_in_unit_interval_give_the_same_run() {
    let dir = tempfile::tempdir().unwrap();
    let unit = admm_ta_agents::problem::CostMatrix::uniform(10, 10, 5).unwrap();
    let metres = admm_ta_agents::problem::CostMatrix::new(
        10,
        10,
        unit.values().iter().map(|c| 350.0 * c + 20.0).collect(),
    )
    .unwrap();
    let a = json(&admm_ta(&[
        "solve",
        "--costs",
        &write(dir.path(), "unit.csv", &unit.to_csv()),
        "--json",
    ]));
    let b = json(&admm_ta(&[
        "solve",
        "--costs",
        &write(dir.path(), "m.csv", &metres.to_csv()),
        "--json",
    ]));
    assert_eq!(a["assignment"], b["assignment"]);
    assert_eq!(a["iterations"], b["iterations"]);
}

#[test]
fn bad_input_gives_one_clear_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = |name: &str, text: &str| write(d, name, text);
    let missing = d.join("missing.csv").to_string_lossy().into_owned();
    let cases: Vec<(String, &str)> = vec![
        (
            format!("--costs {}", file("nan.csv", "1,2\nNaN,3\n")),
            "NaN",
        ),
        (
            format!("--costs {}", file("inf.csv", "1,inf\n2,3\n")),
            "inf",
        ),
        (format!("--costs {}", file("empty.csv", "")), "empty"),
        (
            format!("--costs {}", file("ragged.csv", "1,2\n3\n")),
            "ragged",
        ),
        (
            format!("--costs {}", file("text.csv", "1,x\n2,3\n")),
            "not a number",
        ),
        (
            format!("--costs {}", file("header.csv", "a,b\n1,2\n3,4\n")),
            "no header",
        ),
        (
            format!("--costs {}", file("wide.csv", "1,2,3\n4,5,6\n")),
            "n ≥ m",
        ),
        (format!("--costs {missing}"), "cannot read"),
        (
            format!(
                "--robots 4 --tasks 4 --topology {}",
                file("split.toml", "robots = 4\nedges = [[0, 1], [2, 3]]\n")
            ),
            "disconnected",
        ),
        (
            format!(
                "--robots 5 --tasks 4 --topology {}",
                file(
                    "small.toml",
                    "robots = 4\nedges = [[0, 1], [1, 2], [2, 3]]\n"
                )
            ),
            "4 robots",
        ),
        (
            format!(
                "--robots 3 --tasks 3 --topology {}",
                file("loop.toml", "robots = 3\nedges = [[0, 0]]\n")
            ),
            "self-loop",
        ),
        (
            "--robots 3 --tasks 3 --topology hypercube".into(),
            "unknown topology",
        ),
        ("--robots 0 --tasks 0".into(), "zero"),
        ("--robots 5000 --tasks 5000".into(), "GiB"),
        ("--robots 3 --tasks 3 --rho -1".into(), "ρ"),
        ("--robots 3 --tasks 3 --perturb x".into(), "perturb"),
        ("--robots 5 --tasks 3 --case 1".into(), "Case 1"),
        (String::new(), "--costs"),
    ];
    for (args, needle) in &cases {
        // Temporary paths contain no spaces, so splitting on whitespace is exact.
        let all: Vec<&str> = std::iter::once("solve")
            .chain(args.split_whitespace())
            .collect();
        assert_clear_error(&admm_ta(&all), needle);
    }
}
