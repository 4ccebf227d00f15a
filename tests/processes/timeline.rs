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

fn admm_ta(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_admm-ta"))
        .args(args)
        .output()
        .expect("admm-ta runs")
}

/// The `ph: X` events of `phase` per agent, as round numbers.
fn rounds_of(trace: &serde_json::Value, phase: &str, agent: u64) -> Vec<u64> {
    trace["traceEvents"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["name"] == phase && e["pid"] == agent)
        .map(|e| e["args"]["round"].as_u64().unwrap())
        .collect()
}

#[test]
fn bench_rounds_writes_a_trace_and_a_critical_path_per_case() {
    let dir = tempfile::tempdir().unwrap();
    let (out_dir, traces) = (dir.path().join("out"), dir.path().join("traces"));
    let out = admm_ta(&[
        "bench",
        "rounds",
        "--agents",
        "5",
        "--topologies",
        "ring",
        "--transports",
        "threads,ipc",
        "--rounds",
        "60",
        "--warmup",
        "10",
        "--out",
        out_dir.to_str().unwrap(),
        "--timeline",
        traces.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("Critical path"), "{stdout}");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("rounds.json")).unwrap()).unwrap();
    let results = report["results"].as_array().unwrap();
    assert_eq!(results.len(), 2);
    for r in results {
        let transport = r["transport"].as_str().unwrap();
        let slug = format!("5-ring-10x10-{transport}-auto-neighbour");
        assert_eq!(
            r["trace"].as_str().unwrap(),
            traces.join(format!("{slug}.json")).to_str().unwrap()
        );
        let trace: serde_json::Value =
            serde_json::from_slice(&std::fs::read(traces.join(format!("{slug}.json"))).unwrap())
                .unwrap();
        // The trace has every round, the warm-up included.
        for agent in 0..5 {
            assert_eq!(
                rounds_of(&trace, "wait", agent),
                (0..70).collect::<Vec<_>>()
            );
        }
        // The critical path covers the recorded rounds only.
        let path = &r["critical_path"];
        assert_eq!(path["rounds"].as_array().unwrap().len(), 59, "{path}");
        let by_agent: Vec<f64> = path["by_agent"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(by_agent.len(), 5);
        let total = path["waiting_share"].as_f64().unwrap();
        assert!(
            (by_agent.iter().sum::<f64>() - total).abs() < 1e-9,
            "{path}"
        );
        assert!(out_dir.join(format!("critical-{slug}.svg")).exists());
    }
    // Without --timeline: no critical path, no trace.
    let out = admm_ta(&[
        "bench",
        "rounds",
        "--agents",
        "3",
        "--transports",
        "threads",
        "--rounds",
        "20",
        "--warmup",
        "0",
        "--out",
        out_dir.to_str().unwrap(),
        "--json",
    ]);
    assert!(out.status.success());
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(report["results"][0].get("critical_path").is_none());
    assert!(report["results"][0].get("trace").is_none());
}

#[test]
fn bench_rounds_refuses_a_timeline_it_cannot_write_before_measuring() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a-file");
    std::fs::write(&file, "").unwrap();
    for args in [
        vec!["--timeline", file.to_str().unwrap()],
        vec!["--timeline", "x", "--timeline-overhead"],
    ] {
        let out = admm_ta(
            &[
                &[
                    "bench",
                    "rounds",
                    "--agents",
                    "2",
                    "--transports",
                    "threads",
                ][..],
                &["--out", dir.path().to_str().unwrap()],
                &args[..],
            ]
            .concat(),
        );
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    }
}

#[test]
fn the_surveillance_experiment_records_every_episode_s_rounds() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("s.json");
    let out = admm_ta(&[
        "experiment",
        "surveillance",
        "--episodes",
        "6",
        "--transport",
        "threads",
        "--out",
        dir.path().to_str().unwrap(),
        "--timeline",
        file.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("critical path:"));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("surveillance.json")).unwrap())
            .unwrap();
    let rounds: u64 = report["per_episode"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["rounds_warm"].as_u64().unwrap())
        .sum();
    let trace: serde_json::Value = serde_json::from_slice(&std::fs::read(&file).unwrap()).unwrap();
    let robots = report["robots"].as_u64().unwrap();
    for agent in 0..robots {
        assert_eq!(
            rounds_of(&trace, "wait", agent),
            (0..rounds).collect::<Vec<_>>()
        );
    }
    assert!(report["critical_path"]["waiting_share"].as_f64().is_some());
}
