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
            format!("--costs {}", file("inf.csv", "1,-inf\n2,3\n")),
            "-inf",
        ),
        (
            format!("--costs {} --maximize", file("pinf.csv", "1,inf\n2,3\n")),
            "inf",
        ),
        (
            format!(
                "--robots 2 --tasks 2 --forbidden {}",
                file("forbid.txt", "0,5\n")
            ),
            "outside",
        ),
        (
            "--robots 2 --tasks 2 --forbidden /dev/zero".into(),
            "not a text file",
        ),
        ("--costs /dev/zero".into(), "not a text file"),
        ("--costs /tmp".into(), "directory"),
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
            format!("--costs {}", file("typo.csv", "1,2x\n1,2\n")),
            "line 1, column 2: '2x' is not a number",
        ),
        (
            format!("--costs {}", file("comma.csv", "1;2,5\n3;4\n")),
            "decimal comma",
        ),
        (
            format!("--costs {} --case 2", file("wide2.csv", "1,2,3\n4,5,6\n")),
            "--case idle",
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
            format!(
                "--robots 3 --tasks 3 --topology {}",
                file("three.toml", "robots = 3\nedges = [[0, 1, 2]]\n")
            ),
            "exactly two robots",
        ),
        (
            "--robots 3 --tasks 3 --topology /dev/zero.toml".into(),
            "cannot read",
        ),
        (
            "--robots 3 --tasks 3 --topology hypercube".into(),
            "unknown topology",
        ),
        ("--robots 0 --tasks 0".into(), "zero"),
        ("--robots 5000 --tasks 5000".into(), "GiB"),
        ("--robots 3 --tasks 3 --rho -1".into(), "ρ"),
        ("--robots 3 --tasks 3 --rho fast".into(), "auto"),
        ("--robots 3 --tasks 3 --method simplex".into(), "simplex"),
        (
            "--robots 3 --tasks 3 --method market --adaptive-rho".into(),
            "--adaptive-rho does not apply to --method market",
        ),
        (
            "--robots 3 --tasks 3 --method dual --gamma-factor 0.3".into(),
            "--gamma-factor 0.3 does not apply to --method dual",
        ),
        (
            "--robots 3 --tasks 3 --method dual --projection qp".into(),
            "--projection qp does not apply to --method dual",
        ),
        (
            "--robots 3 --tasks 3 --method cbaa --primal-variant paper".into(),
            "--primal-variant paper does not apply to --method cbaa",
        ),
        (
            "--robots 3 --tasks 3 --method inexact-dual --gamma-factor 0".into(),
            "γ",
        ),
        (
            "--robots 3 --tasks 3 --method dual --stop agreement".into(),
            "--method primal",
        ),
        (
            "--robots 3 --tasks 3 --transport threads --stop oracle".into(),
            "sim",
        ),
        (
            "--robots 3 --tasks 3 --method hungarian --transport ipc".into(),
            "centralized",
        ),
        ("--robots 3 --tasks 3 --perturb x".into(), "perturb"),
        ("--robots 5 --tasks 3 --case 1".into(), "Case 1"),
        (String::new(), "--costs"),
        (
            format!(
                "--robots 3 --tasks 3 --topology {}",
                file("dup.toml", "robots = 3\nedges = [[0, 1], [1, 0], [1, 2]]\n")
            ),
            "more than once",
        ),
        (
            format!(
                "--robots 3 --tasks 3 --topology {}",
                file("range.toml", "robots = 3\nedges = [[0, 1], [1, 5]]\n")
            ),
            "names robot 5, but there are 3 robots, numbered from 0",
        ),
        (
            format!(
                "--robots 3 --tasks 3 --topology {}",
                file("junk.toml", "robots = \"three\"\n")
            ),
            "junk.toml",
        ),
        ("--robots 0 --tasks 3".into(), "zero robots"),
        ("--robots 3 --tasks 0".into(), "zero tasks"),
        ("--robots 100000 --tasks 2".into(), "robot pairs"),
        ("--robots 100000 --tasks 2 --topology chain".into(), "GiB"),
        ("--robots 3 --tasks 3 --transport pigeon".into(), "pigeon"),
        (
            format!(
                "--costs {} --transport ipc",
                file("nan-ipc.csv", "1,2\nnan,3\n")
            ),
            "NaN",
        ),
        (
            format!("--costs {}", file("crlf.csv", "1,2\r\n3,x\r\n")),
            "not a number",
        ),
    ];
    for (args, needle) in &cases {
        // Temporary paths contain no spaces, so splitting on whitespace is exact.
        let all: Vec<&str> = std::iter::once("solve")
            .chain(args.split_whitespace())
            .collect();
        let output = admm_ta(&all);
        assert_clear_error(&output, needle);
        assert_eq!(output.status.code(), Some(2), "bad input exits 2: {args}");
    }
    eprintln!("bad-input corpus: {} cases", cases.len());
}

#[test]
fn bad_options_of_every_other_command_exit_2_with_one_line() {
    let max = "18446744073709551615";
    let cases: [(&[&str], &str); 26] = [
        (&["bench", "rounds", "--agents", "0"], "--agents"),
        (&["bench", "rounds", "--rounds", max], "--rounds"),
        (&["bench", "rounds", "--warmup", max], "--warmup"),
        (&["bench", "rounds", "--payloads", "0x0"], "--payloads"),
        (&["bench", "rounds", "--out", "/proc/nope"], "/proc/nope"),
        (&["bench", "rounds", "--topologies", "random:0"], "random:0"),
        (
            &[
                "bench",
                "rounds",
                "--barriers",
                "global",
                "--transports",
                "uds",
            ],
            "shm",
        ),
        (
            &[
                "experiment",
                "compare",
                "--robots",
                "2",
                "--seeds",
                "1",
                "--topology",
                "random:0",
            ],
            "random:0",
        ),
        (
            &[
                "experiment",
                "compare",
                "--robots",
                "2",
                "--topology",
                "/nonexistent/t.toml",
            ],
            "t.toml",
        ),
        (
            &[
                "experiment",
                "compare",
                "--methods",
                "hungarian",
                "--transports",
                "ipc",
            ],
            "hungarian",
        ),
        (
            &["experiment", "surveillance", "--mission", "/etc/hostname"],
            "/etc/hostname",
        ),
        (
            &[
                "experiment",
                "surveillance",
                "--scenario",
                "/nonexistent.toml",
            ],
            "/nonexistent.toml",
        ),
        (&["stress", "--seed", max, "--runs", "2"], "--seed"),
        (&["stress", "--robots", "0"], "zero robots"),
        (&["stress", "--method", "hungarian"], "hungarian"),
        (&["stress", "--topology", "random:0"], "random:0"),
        (&["stress", "--startup-timeout", "0"], "--startup-timeout"),
        (&["stress", "--round-timeout", "0"], "--round-timeout"),
        (&["bench", "rounds", "--repeat", "0"], "--repeat"),
        (&["bench", "rounds", "--rounds", "0"], "--rounds"),
        (&["experiment", "compare", "--robots", "0"], "--robots"),
        (&["experiment", "rounds-anatomy", "--seeds", "0"], "--seeds"),
        (&["experiment", "ipc-scaling", "--sizes", "1"], "--sizes"),
        (&["stress", "--runs", "0"], "--runs"),
        (&["stress", "--transport", "threads"], "agent processes"),
        (&["agent", "--id", "0"], "--team"),
    ];
    for (args, needle) in cases {
        let output = admm_ta(args);
        assert_clear_error(&output, needle);
        assert_eq!(output.status.code(), Some(2), "bad input exits 2: {args:?}");
    }
}

/// Output that cannot be written: a full device is one line and exit 1; a reader that
/// closed the pipe ends the program quietly, as a Unix tool.
#[test]
fn output_errors_are_one_line_and_a_closed_pipe_ends_quietly() {
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .expect("/dev/full opens");
    let output = Command::new(env!("CARGO_BIN_EXE_admm-ta"))
        .args(["topology", "--robots", "3"])
        .stdout(full)
        .output()
        .expect("the admm-ta binary runs");
    assert_clear_error(&output, "cannot write the output");
    assert_eq!(output.status.code(), Some(1));

    let mut child = Command::new(env!("CARGO_BIN_EXE_admm-ta"))
        .args(["topology", "--robots", "300"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the admm-ta binary runs");
    // Read one line, then close the pipe: the rest (far more than a pipe buffer) meets EPIPE.
    let mut stdout = std::io::BufReader::new(child.stdout.take().expect("piped"));
    let mut first = String::new();
    std::io::BufRead::read_line(&mut stdout, &mut first).expect("a first line");
    drop(stdout);
    let output = child.wait_with_output().expect("admm-ta ends");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.is_empty(), "not quiet: {stderr}");
    assert_eq!(output.status.code(), Some(0));
}

#[test]
fn a_one_by_one_problem_solves_on_every_transport() {
    let dir = tempfile::tempdir().unwrap();
    let one = write(dir.path(), "one.csv", "0.5\n");
    for transport in ["sim", "threads", "ipc", "uds"] {
        let report = json(&admm_ta(&[
            "solve",
            "--costs",
            &one,
            "--transport",
            transport,
            "--check",
            "--json",
        ]));
        assert_eq!(report["assignment"], serde_json::json!([0]), "{transport}");
        assert_eq!(report["check"]["optimal"], true);
    }
}

#[test]
fn every_method_solves_from_the_command_line_and_the_oracle_stop_is_the_papers_criterion() {
    for method in ["primal", "dual", "inexact-dual"] {
        let out = admm_ta(&[
            "solve", "--robots", "12", "--tasks", "12", "--seed", "4", "--method", method,
            "--check", "--json",
        ]);
        let v = json(&out);
        assert_eq!(v["method"], method);
        assert_eq!(v["check"]["optimal"], true, "{method}");
        assert_eq!(v["converged"], true, "{method}");
        let oracle = json(&admm_ta(&[
            "solve", "--robots", "12", "--tasks", "12", "--seed", "4", "--method", method,
            "--stop", "oracle", "--check", "--json",
        ]));
        // The fast primal variant's criterion is on the robots' decisions (its relaxed
        // columns stay near the polytope's centre).
        let criterion = if method == "primal" {
            "rounds_decisions_within_0_1pct"
        } else {
            "rounds_within_0_1pct"
        };
        assert_eq!(
            oracle["iterations"], oracle["check"][criterion],
            "{method}: the oracle stop ends at the first round within 0.1%"
        );
    }
    let paper = json(&admm_ta(&[
        "solve",
        "--robots",
        "12",
        "--tasks",
        "12",
        "--seed",
        "4",
        "--primal-variant",
        "paper",
        "--stop",
        "oracle",
        "--check",
        "--json",
    ]));
    assert_eq!(paper["iterations"], paper["check"]["rounds_within_0_1pct"]);
    // --adaptive-rho is the paper variant's (the fast dual grows its ρ itself).
    assert_clear_error(
        &admm_ta(&["solve", "--robots", "4", "--tasks", "4", "--adaptive-rho"]),
        "--primal-variant paper",
    );
    assert_clear_error(
        &admm_ta(&[
            "solve",
            "--robots",
            "4",
            "--tasks",
            "4",
            "--method",
            "dual",
            "--adaptive-rho",
        ]),
        "--dual-variant paper",
    );
    // An explicit ρ is used as given; --adaptive-rho changes the run.
    let run = |extra: &[&str]| {
        let mut args = vec!["solve", "--robots", "8", "--tasks", "8", "--rho", "0.002"];
        args.extend_from_slice(&["--primal-variant", "paper"]);
        args.extend_from_slice(&["--stop", "oracle", "--json"]);
        args.extend_from_slice(extra);
        json(&admm_ta(&args))
    };
    let (fixed, adaptive) = (run(&[]), run(&["--adaptive-rho"]));
    assert_eq!(fixed["rho"], 0.002);
    assert_ne!(fixed["iterations"], adaptive["iterations"]);
}

/// Runs `admm-ta experiment ARGS --out DIR` and returns its printed table and the JSON file
/// `file` it wrote.
fn experiment(args: &[&str], file: &str) -> (String, serde_json::Value) {
    let dir = tempfile::tempdir().unwrap();
    let mut all = vec!["experiment"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--out", dir.path().to_str().unwrap()]);
    let out = admm_ta(&all);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.path().join(file)).unwrap();
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        serde_json::from_str(&text).unwrap(),
    )
}

#[test]
fn table1_experiment_writes_its_json() {
    let (table, v) = experiment(&["table1", "--trials", "2"], "table1.json");
    let needles = [
        "primal paper",
        "primal fast*",
        "dual",
        "inexact-dual",
        "159",
        "387",
        "[1,2)",
    ];
    for needle in needles {
        assert!(table.contains(needle), "{needle} not in:\n{table}");
    }
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 12);
    for row in rows {
        assert_eq!(row["wrong_stops"], 0);
        assert_eq!(row["trials"].as_array().unwrap().len(), 2);
        assert_eq!(row["within_0_1pct"]["reached"], 2);
    }
}

#[test]
fn baselines_report_rounds_messages_and_bytes() {
    let hungarian = json(&admm_ta(&[
        "solve",
        "--robots",
        "10",
        "--tasks",
        "10",
        "--method",
        "hungarian",
        "--check",
        "--json",
    ]));
    assert_eq!(hungarian["iterations"], 1);
    assert_eq!(hungarian["check"]["optimal"], true);
    assert_eq!(hungarian["messages_per_agent"], 0);
    let cbaa = json(&admm_ta(&[
        "solve", "--robots", "10", "--tasks", "10", "--method", "cbaa", "--json",
    ]));
    assert_eq!(cbaa["converged"], true);
    assert_eq!(cbaa["repaired"], false);
    let rounds = cbaa["iterations"].as_u64().unwrap();
    assert_eq!(cbaa["messages_per_agent"].as_u64().unwrap(), rounds);
    // 2m f64 lists plus the round header.
    let bytes = cbaa["message_bytes"].as_u64().unwrap();
    assert!(bytes > 8 * 20, "{bytes}");
    assert_eq!(cbaa["bytes_per_agent"].as_u64().unwrap(), rounds * bytes);
    let primal = json(&admm_ta(&[
        "solve", "--robots", "10", "--tasks", "10", "--json",
    ]));
    assert_eq!(
        primal["message_bytes"].as_u64().unwrap() - bytes,
        8 * (100 - 20),
        "the primal sends the m×n matrix, CBAA 2m values"
    );
    let market = json(&admm_ta(&[
        "solve",
        "--robots",
        "10",
        "--tasks",
        "10",
        "--method",
        "market",
        "--topology",
        "chain",
        "--check",
        "--json",
    ]));
    assert_eq!(market["converged"], true);
    assert_eq!(market["check"]["optimal"], true);
    // n row flags, n packed demand words, one price increment: 21 values against 20.
    assert_eq!(
        market["message_bytes"].as_u64().unwrap() - bytes,
        8,
        "the market sends demand bits, not costs"
    );
}

#[test]
fn compare_experiment_prints_a_row_per_method_and_transport() {
    let args = [
        "compare",
        "--robots",
        "4",
        "--seeds",
        "1",
        "--transports",
        "sim,threads",
    ];
    let (table, v) = experiment(&args, "compare.json");
    // 6 distributed methods × 2 transports + the centralized row.
    assert_eq!(
        table.lines().filter(|l| l.starts_with("| 4 |")).count(),
        13,
        "{table}"
    );
    for row in v.as_array().unwrap() {
        if row["method"] != "cbaa" {
            assert_eq!(row["optimal_runs"], 1, "{row}");
        }
    }
}

#[test]
fn bench_rounds_measures_every_transport_and_writes_json_csv_and_plots() {
    let dir = tempfile::tempdir().unwrap();
    let out = admm_ta(&[
        "bench",
        "rounds",
        "--agents",
        "2,4",
        "--payloads",
        "1x1,20x20,100x100",
        "--rounds",
        "30",
        "--warmup",
        "5",
        "--repeat",
        "2",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let table = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "| threads |",
        "| shm |",
        "| ipc |",
        "| uds |",
        "ipc / threads p50",
        "uds / threads p50",
        "start-up ms ipc",
        "CPU µs/sample",
        "p99.9",
    ] {
        assert!(table.contains(needle), "{needle} not in:\n{table}");
    }
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("rounds.json")).unwrap())
            .unwrap();
    let results = v["results"].as_array().unwrap();
    assert_eq!(results.len(), 2 * 3 * 4, "agents × payloads × transports");
    assert!(v["failures"].as_array().unwrap().is_empty());
    for r in results {
        let agents = r["agents"].as_u64().unwrap();
        assert_eq!(r["recorded"].as_u64().unwrap(), agents * 30);
        let round = &r["round_us"];
        for (lo, hi) in [
            ("p50", "p90"),
            ("p90", "p99"),
            ("p99", "p999"),
            ("p999", "max"),
        ] {
            assert!(
                round[lo].as_f64().unwrap() <= round[hi].as_f64().unwrap(),
                "{r}"
            );
        }
        assert!(r["overhead_us"]["p50"].as_f64().unwrap() <= round["p50"].as_f64().unwrap());
        assert!(r["cpu_us_per_round"].as_f64().unwrap() > 0.0);
        // Per received sample: the agent-round's CPU over the (mean) degree.
        let per_sample = r["cpu_us_per_sample"].as_f64().unwrap();
        assert!(
            per_sample > 0.0 && per_sample <= r["cpu_us_per_round"].as_f64().unwrap(),
            "{r}"
        );
        // The median of two repetitions, with their spread.
        assert_eq!(r["repeats"], 2);
        let range = r["round_p50_range_us"].as_array().unwrap();
        let (lo, hi) = (range[0].as_f64().unwrap(), range[1].as_f64().unwrap());
        let p50 = round["p50"].as_f64().unwrap();
        assert!(lo <= p50 && p50 <= hi, "{r}");
    }
    let csv = std::fs::read_to_string(dir.path().join("rounds.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + results.len());
    for svg in ["rounds-payload-2-agents.svg", "rounds-payload-4-agents.svg"] {
        let text = std::fs::read_to_string(dir.path().join(svg)).unwrap();
        assert!(text.contains("<svg") && text.contains("uds p50"), "{svg}");
    }
    // The wrong settings are refused with one line.
    for (args, needle) in [
        (vec!["--payloads", "0x3"], "1…2000"),
        (
            vec!["--transports", "sim"],
            "threads, shm, ipc, uds or zenoh",
        ),
        (
            vec!["--transports", "uds", "--barriers", "global"],
            "no case",
        ),
        (vec!["--topologies", "moebius"], "moebius"),
        (vec!["--agents", "0"], "at least 1 agent"),
        (vec!["--repeat", "0"], "--repeat"),
    ] {
        let mut all = vec!["bench", "rounds", "--rounds", "5"];
        all.extend(args);
        all.extend(["--out", dir.path().to_str().unwrap()]);
        assert_clear_error(&admm_ta(&all), needle);
    }
}

#[test]
fn figure_experiments_write_json_and_svg() {
    let (table, v) = experiment(
        &["fig2-scaling", "--sizes", "6,10", "--trials", "1"],
        "fig2-scaling.json",
    );
    assert!(
        table.contains("market") && table.contains("distributed Hungarian"),
        "{table}"
    );
    let points = v["points"].as_array().unwrap();
    // 4 complete-graph series with 2 sizes each, ADMM's two stops; 3 on random graphs; and
    // on both, the other ADMM methods and variants (fast primal, both duals' two variants).
    assert_eq!(points.len(), 5 * 2 + 3 * 2 + 2 * 5 * 2);
    let labels: Vec<&str> = points
        .iter()
        .map(|p| p["series"].as_str().unwrap())
        .collect();
    for label in [
        "primal (fast) (decentralized stop)",
        "dual (fast) (decentralized stop)",
        "inexact-dual (paper) (decentralized stop)",
    ] {
        assert!(labels.contains(&label), "{label} not in {labels:?}");
    }
    for p in points {
        let series = p["series"].as_str().unwrap();
        if !series.starts_with("CBAA") {
            assert_eq!(p["optimal_runs"], 1, "{p}");
        }
        assert!(p["mean_iterations"].as_f64().unwrap() >= 1.0);
        if series == "distributed Hungarian" && p["topology"] == "complete" {
            // Flooding takes one round on the complete graph, plus the stop protocol.
            assert!(p["mean_iterations"].as_f64().unwrap() <= 6.0, "{p}");
        }
    }
    let (table, v) = experiment(
        &["fig1-topologies", "--trials", "1"],
        "fig1-topologies.json",
    );
    assert!(table.contains("chain"), "{table}");
    for run in v["runs"].as_array().unwrap() {
        assert_eq!(run["optimal"], true);
        let trace = run["trace"].as_array().unwrap();
        assert_eq!(trace.len() as u64, run["stop_round"].as_u64().unwrap());
    }
}

#[test]
fn surveillance_episodes_are_optimal_warm_started_and_the_same_on_threads_and_ipc() {
    let dir = tempfile::tempdir().unwrap();
    let run = |transport: &str| {
        let out = admm_ta(&[
            "experiment",
            "surveillance",
            "--episodes",
            "80",
            "--transport",
            transport,
            "--json",
            "--out",
            dir.path().to_str().unwrap(),
        ]);
        json(&out)
    };
    let (ipc, threads) = (run("ipc"), run("threads"));
    for v in [&ipc, &threads] {
        assert_eq!(v["episodes"], 80);
        assert_eq!(v["optimal_episodes"], 80, "{:?}", v["misses"]);
        assert_eq!(v["battery_violations"], 0);
        let (warm, cold) = (
            v["mean_iterations_warm"].as_f64().unwrap(),
            v["mean_iterations_cold"].as_f64().unwrap(),
        );
        assert!(warm >= 5.0 && cold >= 5.0, "{warm} {cold}");
    }
    // One team, the same iterates on both transports.
    assert_eq!(ipc["mean_iterations_warm"], threads["mean_iterations_warm"]);
    for svg in ["surveillance-cost.svg", "surveillance-battery.svg"] {
        assert!(dir.path().join(svg).exists(), "{svg}");
    }
    let detail: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("surveillance.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(detail["per_episode"].as_array().unwrap().len(), 80);
    // A scenario that cannot run is refused with one line.
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "robots = 3\n").unwrap();
    assert_clear_error(
        &admm_ta(&[
            "experiment",
            "surveillance",
            "--scenario",
            bad.to_str().unwrap(),
        ]),
        "cannot cover",
    );
}

/// Exit status of `admm-ta solve ARGS` (whitespace-separated).
fn solve_code(args: &str) -> (Option<i32>, String, String) {
    let all: Vec<&str> = std::iter::once("solve")
        .chain(args.split_whitespace())
        .collect();
    let output = admm_ta(&all);
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stdout).into_owned(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

#[test]
fn exit_codes_follow_the_documented_outcomes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // 0: certified, or a baseline that finished.
    assert_eq!(solve_code("--robots 6 --tasks 6").0, Some(0));
    assert_eq!(solve_code("--robots 6 --tasks 6 --method cbaa").0, Some(0));
    // 2: bad input or options (clap's usage errors too).
    assert_eq!(solve_code("--robots 6 --tasks 6 --rho x").0, Some(2));
    assert_eq!(solve_code("--robots 6 --tasks 6 --no-such-flag").0, Some(2));
    // 3: infeasible, with a blocking set.
    let infeasible = write(d, "infeasible.csv", "1,inf,inf\n2,inf,inf\n3,4,5\n");
    let (code, _, stderr) = solve_code(&format!("--costs {infeasible}"));
    assert_eq!(code, Some(3));
    assert_clear_error_text(
        &stderr,
        "infeasible: tasks 1, 2 can only be done by robot 2",
    );
    let (code, _, stderr) = solve_code(&format!("--costs {infeasible} --method hungarian"));
    assert_eq!(code, Some(3), "{stderr}");
    // 5: the round limit without a certificate: the best assignment, marked.
    let (code, stdout, _) = solve_code("--robots 12 --tasks 12 --max-iters 2 --json");
    assert_eq!(code, Some(5));
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(report["certified"], false);
    assert_eq!(report["converged"], false);
    let (code, stdout, _) = solve_code("--robots 12 --tasks 12 --max-iters 2");
    assert_eq!(code, Some(5));
    assert!(stdout.contains("NOT certified"), "{stdout}");
    // 6: --check found the result not optimal (CBAA on a seed where it is not).
    let (code, stdout, _) = solve_code("--robots 10 --tasks 10 --method cbaa --check");
    assert_eq!(code, Some(6));
    assert!(stdout.contains("NOT optimal"), "{stdout}");
    // (4, agent failure, is asserted by tests/processes/faults.rs; 1 is for internal errors.)
}

fn assert_clear_error_text(stderr: &str, needle: &str) {
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "not one line: {stderr}"
    );
    assert!(stderr.contains(needle), "'{needle}' not in: {stderr}");
}

#[test]
fn a_byte_order_mark_before_costs_and_forbidden_pairs_is_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let costs = write(d, "bom.csv", "\u{feff}1,0\n0,1\n");
    let pairs = write(d, "bom.txt", "\u{feff}0,1\n");
    let report = json(&admm_ta(&[
        "solve",
        "--costs",
        &costs,
        "--forbidden",
        &pairs,
        "--method",
        "hungarian",
        "--transport",
        "sim",
        "--json",
    ]));
    // Robot 0 may not take task 1, so it takes task 0 at cost 1.
    assert_eq!(report["assignment"], serde_json::json!([0, 1]));
    assert_eq!(report["cost"], 2.0);
}

#[test]
fn clap_errors_name_the_missing_arguments_and_timeouts_their_range() {
    let cases: [(&[&str], &str); 4] = [
        (&["solve", "--robots", "3"], "not provided: --tasks"),
        (&["topology"], "not provided: --robots"),
        (
            &[
                "solve",
                "--robots",
                "3",
                "--tasks",
                "3",
                "--round-timeout",
                "1e300",
            ],
            "below 1000000, got 1e300",
        ),
        (
            &[
                "solve",
                "--robots",
                "3",
                "--tasks",
                "3",
                "--round-timeout",
                "1e9",
            ],
            "below 1000000, got 1e9",
        ),
    ];
    for (args, needle) in cases {
        let output = admm_ta(args);
        assert_clear_error(&output, needle);
        assert_eq!(output.status.code(), Some(2), "{args:?}");
    }
}

/// Every method that reaches the optimum (CBAA, a heuristic, is left out).
const OPTIMAL_METHODS: [&str; 6] = [
    "primal",
    "dual",
    "inexact-dual",
    "market",
    "dist-hungarian",
    "hungarian",
];

#[test]
fn forbidden_pairs_maximize_and_idle_robots_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // scipy: [[inf, 1], [2, inf]] → rows 0, 1 to columns 1, 0, cost 3.
    let costs = write(d, "inf.csv", "inf,1\n2,inf\n");
    for method in OPTIMAL_METHODS {
        let report = json(&admm_ta(&[
            "solve", "--costs", &costs, "--method", method, "--check", "--json",
        ]));
        assert_eq!(report["assignment"], serde_json::json!([1, 0]), "{method}");
        assert_eq!(report["cost"], 3.0, "{method}");
        assert_eq!(report["certified"], true, "{method}");
    }
    // The same pairs from --forbidden.
    let plain = write(d, "plain.csv", "0,1\n2,0\n");
    let pairs = write(d, "pairs.txt", "# robot,task\n0,0\n1,1\n");
    let report = json(&admm_ta(&[
        "solve",
        "--costs",
        &plain,
        "--forbidden",
        &pairs,
        "--json",
    ]));
    assert_eq!(report["assignment"], serde_json::json!([1, 0]));
    // Profits: the largest total, reported as the user's numbers.
    let profits = write(d, "profits.csv", "1,5\n4,2\n");
    let report = json(&admm_ta(&[
        "solve",
        "--costs",
        &profits,
        "--maximize",
        "--check",
        "--json",
    ]));
    assert_eq!(report["assignment"], serde_json::json!([1, 0]));
    assert_eq!(report["cost"], 9.0);
    assert_eq!(report["maximize"], true);
    assert_eq!(report["check"]["optimal"], true);
    // The optimum is a profit, and says so (the key of earlier reports stays).
    assert_eq!(report["check"]["optimal_profit"], 9.0);
    assert_eq!(report["check"]["optimal_cost"], 9.0);
    let text = admm_ta(&["solve", "--costs", &profits, "--maximize", "--check"]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(
        text.contains("optimal profit 9.000000 (centralized)"),
        "{text}"
    );
    assert!(!text.contains("cost"), "{text}");
    // Idle robots: scipy's rectangular meaning, null in the JSON.
    let tall = write(d, "tall.csv", "1,9\n9,1\n0.5,0.5\n");
    let report = json(&admm_ta(&[
        "solve", "--costs", &tall, "--case", "idle", "--method", "dual", "--check", "--json",
    ]));
    assert_eq!(report["assignment"], serde_json::json!([null, 1, 0]));
    assert_eq!(report["idle_robots"], serde_json::json!([0]));
    assert_eq!(report["case"], "idle");
    assert_eq!(report["cost"], 1.5);
    // Unserved tasks (more tasks than robots): every optimal method (CBAA, a heuristic,
    // may pick another feasible assignment and exit 6 under --check).
    let wide = write(d, "wide.csv", "1,9,3\n9,1,3\n");
    for method in OPTIMAL_METHODS {
        let report = json(&admm_ta(&[
            "solve", "--costs", &wide, "--method", method, "--check", "--json",
        ]));
        assert_eq!(report["assignment"], serde_json::json!([0, 1]), "{method}");
        assert_eq!(report["unserved_tasks"], serde_json::json!([2]), "{method}");
    }
}

#[test]
fn rounds_anatomy_quick_writes_its_table_json_and_charts() {
    let (table, json) = experiment(
        &["rounds-anatomy", "--quick", "--seeds", "1"],
        "rounds_anatomy.json",
    );
    assert!(
        table.contains("| primal (fast) | uniform | complete |"),
        "{table}"
    );
    assert!(table.contains("| cbaa | geometric | chain |"), "{table}");
    let cells = json["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 9 * 2 * 5);
    for cell in cells.iter().filter(|c| c["contender"]["method"] != "cbaa") {
        assert_eq!(cell["wrong_stops"], 0, "{}", cell["name"]);
    }
}

#[test]
fn size_sweep_checks_every_run_certified_and_optimal() {
    let (table, json) = experiment(
        &[
            "size-sweep",
            "--sizes",
            "5,8",
            "--seeds",
            "1",
            "--topologies",
            "chain,complete",
        ],
        "size_sweep.json",
    );
    assert!(
        table.contains("| 8 | geometric | chain | 1/1 | 1/1 |"),
        "{table}"
    );
    assert!(
        table.contains("Every run certified the optimal assignment."),
        "{table}"
    );
    assert_eq!(json["points"].as_array().unwrap().len(), 2 * 2 * 2);
}

#[test]
fn one_robot_with_many_tasks_is_solved_or_refused_without_quadratic_memory() {
    use std::os::unix::process::CommandExt;
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("wide.csv");
    let row: Vec<String> = (0..20_000)
        .map(|k| format!("{}", 1.0 + ((k * 7919) % 20_011) as f64 / 20_011.0))
        .collect();
    std::fs::write(&csv, row.join(",") + "\n").unwrap();
    // 2 GiB of address space: the tasks' complete graph (2·10⁸ edges) would need 7 GiB.
    for (method, code) in [("hungarian", 0), ("primal", 2), ("market", 2)] {
        let mut command = Command::new(env!("CARGO_BIN_EXE_admm-ta"));
        command
            .args(["solve", "--json", "--method", method, "--costs"])
            .arg(&csv);
        // SAFETY: setrlimit only, between fork and exec.
        unsafe {
            command.pre_exec(|| {
                let limit = libc::rlimit {
                    rlim_cur: 2 << 30,
                    rlim_max: 2 << 30,
                };
                if libc::setrlimit(libc::RLIMIT_AS, &limit) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
        let out = command.output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{method}: {err}");
        if code == 0 {
            let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
            // The cheapest task: k = 0 has cost 1.0, every other is above it.
            assert_eq!(report["assignment"][0], 0, "{report}");
        } else {
            assert!(err.contains("GiB of"), "{method}: {err}");
        }
    }
}

/// A size refusal names the user's robots × tasks and says what is too large, also when the
/// method solves the problem transposed (one agent per task) or the centralized solver
/// holds a larger normalised matrix.
#[test]
fn size_refusals_name_the_users_shape() {
    for (args, shape, detail) in [
        (
            "--robots 1 --tasks 300000",
            "1 robot × 300000 tasks is too large for the primal method",
            "solved transposed, as 300000 × 2",
        ),
        (
            "--robots 1 --tasks 300000 --method market",
            "1 robot × 300000 tasks is too large for the market method",
            "one row per task",
        ),
        (
            "--robots 1 --tasks 300000 --method hungarian",
            "1 robot × 300000 tasks is too large for the hungarian method",
            "GiB of working memory",
        ),
        (
            "--robots 5000 --tasks 5000",
            "5000 robots × 5000 tasks is too large for the primal method",
            "GiB of agent state",
        ),
        (
            "--robots 1 --tasks 3000000000",
            "1 robot × 3000000000 tasks is too large",
            "50000000",
        ),
    ] {
        let all: Vec<&str> = std::iter::once("solve")
            .chain(args.split_whitespace())
            .collect();
        let output = admm_ta(&all);
        assert_clear_error(&output, shape);
        assert_clear_error(&output, detail);
        assert_eq!(output.status.code(), Some(2), "{args}");
    }
}

/// An option the run never reads is refused (exit 2, one line naming it), never silently
/// ignored; the same options where they are read, and every default, still run.
#[test]
fn options_the_run_never_reads_are_refused_and_the_same_options_where_read_run() {
    let refused = [
        (
            "--method market --rho 3",
            "--rho 3 does not apply to --method market",
        ),
        (
            "--method cbaa --rho 3",
            "--rho 3 does not apply to --method cbaa",
        ),
        (
            "--method dist-hungarian --rho 3",
            "--rho 3 does not apply to --method dist-hungarian",
        ),
        (
            "--method hungarian --rho 3",
            "--rho 3 does not apply to --method hungarian",
        ),
        (
            "--stop-rounds 5",
            "--stop-rounds 5 does not apply to --stop local",
        ),
        (
            "--check --trace --transport threads",
            "--trace does not apply to --transport threads",
        ),
        (
            "--check --trace --method hungarian",
            "--trace does not apply to --method hungarian",
        ),
        (
            "--method hungarian --perturb 0.1",
            "--perturb 0.1 does not apply to --method hungarian",
        ),
        (
            "--method hungarian --max-iters 10",
            "--max-iters 10 does not apply to --method hungarian",
        ),
        (
            "--round-timeout 5",
            "--round-timeout 5 does not apply to --transport sim",
        ),
        (
            "--wait spin",
            "--wait spin does not apply to --transport sim",
        ),
        (
            "--transport threads --startup-timeout 5",
            "--startup-timeout 5 does not apply to --transport threads",
        ),
    ];
    for (args, needle) in refused {
        let all: Vec<&str> = ["solve", "--robots", "5", "--tasks", "5"]
            .into_iter()
            .chain(args.split_whitespace())
            .collect();
        let output = admm_ta(&all);
        assert_clear_error(&output, needle);
        assert_eq!(output.status.code(), Some(2), "{args}");
    }
    for args in [
        "--method primal --rho 3",
        "--method dual --dual-variant paper --rho 3 --adaptive-rho",
        "--method market",
        "--method hungarian",
        "--primal-variant paper --stop agreement --stop-rounds 3",
        "--check --trace",
        "--transport threads --round-timeout 5 --wait block",
        "--transport uds --startup-timeout 20 --round-timeout 20",
    ] {
        let all: Vec<&str> = ["solve", "--robots", "5", "--tasks", "5", "--json"]
            .into_iter()
            .chain(args.split_whitespace())
            .collect();
        json(&admm_ta(&all));
    }
}
