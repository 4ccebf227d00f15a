//! Structured logs: quiet by default; `RUST_LOG` or `--log` gives one line per event on
//! standard error from the launcher and from every agent process (their lines reach the
//! launcher's standard error), tagged with the run and the agent; rounds only at `trace`.

use std::process::{Command, Output};

fn solve(env: Option<&str>, args: &[&str]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_admm-ta"));
    command
        .args(["solve", "--robots", "4", "--tasks", "4", "--seed", "3"])
        .args(args)
        .env_remove("RUST_LOG");
    if let Some(filter) = env {
        command.env("RUST_LOG", filter);
    }
    command.output().expect("admm-ta runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn quiet_by_default_and_the_report_is_the_same_with_logs() {
    for transport in ["sim", "threads", "ipc"] {
        let quiet = solve(None, &["--transport", transport, "--json"]);
        assert!(quiet.status.success(), "{}", text(&quiet.stderr));
        assert_eq!(
            text(&quiet.stderr),
            "",
            "{transport}: nothing on stderr by default"
        );
        let logged = solve(Some("debug"), &["--transport", transport, "--json"]);
        assert!(logged.status.success());
        let assignment = |o: &Output| {
            let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
            report["assignment"].clone()
        };
        assert_eq!(assignment(&quiet), assignment(&logged), "{transport}");
    }
}

#[test]
fn every_agent_process_and_the_launcher_log_tagged_lines() {
    for logged in [
        solve(Some("debug"), &["--transport", "ipc"]),
        solve(None, &["--transport", "ipc", "--log", "debug"]),
        solve(Some("off"), &["--transport", "ipc", "--log", "debug"]),
    ] {
        assert!(logged.status.success());
        let err = text(&logged.stderr);
        let lines: Vec<&str> = err.lines().collect();
        assert!(lines.iter().any(|l| l.contains("launcher{run=")), "{err}");
        for agent in 0..4 {
            let tag = format!("agent={agent}}}");
            assert!(
                lines
                    .iter()
                    .any(|l| l.contains(&tag) && l.contains("connected")),
                "agent {agent}'s start-up: {err}"
            );
            assert!(
                lines
                    .iter()
                    .any(|l| l.contains(&tag) && l.contains("certified")),
                "agent {agent}'s stop protocol: {err}"
            );
        }
        // One event per line, each with its level, no round lines below trace.
        for line in &lines {
            assert!(
                [" DEBUG ", " INFO ", " WARN ", " ERROR "]
                    .iter()
                    .any(|l| line.contains(l)),
                "{line}"
            );
            assert!(!line.contains(": round "), "{line}");
        }
    }
}

#[test]
fn trace_shows_every_round_of_every_agent() {
    let logged = solve(Some("trace"), &["--transport", "ipc", "--topology", "ring"]);
    assert!(logged.status.success());
    let err = text(&logged.stderr);
    for agent in 0..4 {
        let tag = format!("agent={agent}}}");
        assert!(
            err.lines()
                .any(|l| l.contains(&tag) && l.contains("round round=0") && l.contains("wait_us=")),
            "{err}"
        );
    }
}

#[test]
fn a_failed_agent_is_logged_by_the_launcher() {
    let mut command = Command::new(env!("CARGO_BIN_EXE_admm-ta"));
    let out = command
        .args([
            "solve",
            "--robots",
            "4",
            "--tasks",
            "4",
            "--transport",
            "ipc",
        ])
        .args(["--round-timeout", "2", "--log", "info"])
        .env("ADMM_TA_FAULT", "2:1:exit")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(4));
    let err = text(&out.stderr);
    assert!(
        err.lines()
            .any(|l| l.contains("WARN") && l.contains("launcher{") && l.contains("agent 2 failed")),
        "{err}"
    );
    // The command line's one error line is still the last one.
    assert!(
        err.trim_end()
            .lines()
            .last()
            .unwrap()
            .starts_with("error: "),
        "{err}"
    );
}

#[test]
fn a_bad_filter_is_refused_in_one_line() {
    let out = solve(None, &["--log", "=["]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("log filter"), "{err}");
}
