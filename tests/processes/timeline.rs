//! `solve --timeline FILE`: every agent's rounds as Chrome trace-event JSON, and the
//! critical path in the report.

use std::process::Command;

fn solve(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_admm-ta"))
        .args(["solve", "--tasks", "20", "--seed", "4", "--json"])
        .args(args)
        .output()
        .expect("admm-ta runs")
}

#[test]
fn twenty_agent_processes_give_a_valid_trace_and_the_critical_path() {
    for transport in ["ipc", "threads"] {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("t.json");
        let out = solve(&[
            "--robots",
            "20",
            "--transport",
            transport,
            "--topology",
            "ring",
            "--timeline",
            file.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let rounds = report["iterations"].as_u64().unwrap();
        let trace: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&file).unwrap()).unwrap();
        let events = trace["traceEvents"].as_array().unwrap();
        for agent in 0..20u64 {
            let named = events.iter().any(|e| {
                e["ph"] == "M" && e["pid"] == agent && e["args"]["name"] == format!("agent {agent}")
            });
            assert!(named, "{transport}: agent {agent} has a named track");
            let waits: Vec<u64> = events
                .iter()
                .filter(|e| e["name"] == "wait" && e["pid"] == agent)
                .map(|e| e["args"]["round"].as_u64().unwrap())
                .collect();
            // Every computed round.
            assert_eq!(waits, (0..rounds).collect::<Vec<_>>(), "{transport}");
        }
        for e in events.iter().filter(|e| e["ph"] == "X") {
            assert!(e["ts"].as_f64().unwrap() >= 0.0 && e["dur"].as_f64().unwrap() >= 0.0);
        }
        // Flows start at a neighbour's publish and end in the waiting agent's track.
        let starts = events.iter().filter(|e| e["ph"] == "s").count();
        let ends = events.iter().filter(|e| e["ph"] == "f").count();
        assert_eq!(starts, ends);
        for e in events.iter().filter(|e| e["ph"] == "s") {
            let (from, to) = (
                e["args"]["from"].as_i64().unwrap(),
                e["args"]["to"].as_i64().unwrap(),
            );
            assert_eq!(
                (from - to).rem_euclid(20) % 18,
                1,
                "ring neighbours {from} {to}"
            );
        }
        let path = &report["critical_path"];
        let share = path["waiting_share"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&share), "{path}");
        assert_eq!(path["rounds"].as_array().unwrap().len() as u64, rounds - 1);
        assert!(!path["top"].as_array().unwrap().is_empty());
    }
}

#[test]
fn the_timeline_is_refused_on_the_simulation_and_off_by_default() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.json");
    let out = solve(&["--robots", "4", "--timeline", file.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(!file.exists(), "nothing written for a refused run");
    let out = solve(&["--robots", "4", "--transport", "threads"]);
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(report.get("critical_path").is_none());
}
