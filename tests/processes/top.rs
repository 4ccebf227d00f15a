//! `admm-ta top`: a snapshot of a running 20-agent team (`--once --json`), the live view in
//! a real terminal (tmux), and its refusals.

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn admm_ta() -> Command {
    Command::new(env!("CARGO_BIN_EXE_admm-ta"))
}

/// A 20-agent ipc team that runs until stopped.
fn long_team() -> Child {
    admm_ta()
        .args([
            "solve",
            "--robots",
            "20",
            "--tasks",
            "20",
            "--transport",
            "ipc",
        ])
        .args([
            "--topology",
            "ring",
            "--stop",
            "max-iters",
            "--max-iters",
            "1000000000",
        ])
        .args(["--round-timeout", "30"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("admm-ta runs")
}

/// This team's snapshot (its launcher is `launcher`), once all 20 agents run.
fn snapshot_of(launcher: u32) -> serde_json::Value {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let out = admm_ta()
            .args(["top", "--once", "--json", "--interval", "100"])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let snapshot: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let team = snapshot["teams"]
            .as_array()
            .unwrap()
            .iter()
            .find(|t| t["launcher_pid"] == launcher)
            .cloned();
        if let Some(team) = team
            && team["agents"]
                .as_array()
                .unwrap()
                .iter()
                .all(|a| a["round"].as_u64().unwrap() > 2)
        {
            return team;
        }
        assert!(
            Instant::now() < deadline,
            "the team never showed: {snapshot}"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}

fn stop(mut team: Child) {
    // SAFETY: signalling our own child.
    unsafe { libc::kill(team.id() as i32, libc::SIGINT) };
    let _ = team.wait();
}

#[test]
fn a_snapshot_shows_every_agent_of_a_running_team_and_its_round() {
    let team = long_team();
    let view = snapshot_of(team.id());
    let agents = view["agents"].as_array().unwrap();
    assert_eq!(view["robots"], 20);
    assert_eq!(view["kind"], "launcher");
    assert_eq!(agents.len(), 20);
    for (i, a) in agents.iter().enumerate() {
        assert_eq!(a["agent"], i);
        assert!(a["pid"].as_u64().is_some(), "{a}");
        let state = a["state"].as_str().unwrap();
        assert!(["computing", "waiting"].contains(&state), "{a}");
        for j in a["waiting_for"].as_array().into_iter().flatten() {
            let j = j.as_u64().unwrap() as usize;
            assert!(
                j == (i + 1) % 20 || j == (i + 19) % 20,
                "ring neighbours: {a}"
            );
        }
    }
    // Rounds advance, and nobody is more than a round or two apart on a ring.
    let rounds: Vec<u64> = agents
        .iter()
        .map(|a| a["round"].as_u64().unwrap())
        .collect();
    let later = snapshot_of(team.id());
    let later_rounds: Vec<u64> = later["agents"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a["round"].as_u64().unwrap())
        .collect();
    assert!(later_rounds.iter().zip(&rounds).all(|(l, r)| l >= r));
    assert!(later_rounds.iter().max().unwrap() - later_rounds.iter().min().unwrap() <= 20);
    stop(team);
}

#[test]
fn the_live_view_runs_in_a_terminal_and_quits_on_q() {
    if Command::new("tmux").arg("-V").output().is_err() {
        assert!(
            std::env::var("CI").is_err(),
            "tmux is needed to test the live view"
        );
        eprintln!("skipped: no tmux");
        return;
    }
    let team = long_team();
    let view = snapshot_of(team.id());
    let socket = format!("admm-ta-top-{}", std::process::id());
    let tmux = |args: &[&str]| {
        Command::new("tmux")
            .args(["-L", &socket])
            .args(args)
            .output()
            .unwrap()
    };
    let top = format!("{} top --interval 200", env!("CARGO_BIN_EXE_admm-ta"));
    let started = tmux(&["new-session", "-d", "-x", "120", "-y", "40", &top]);
    assert!(started.status.success(), "{started:?}");
    let run = view["run"].as_str().unwrap().to_string();
    let deadline = Instant::now() + Duration::from_secs(20);
    let screen = loop {
        let pane = tmux(&["capture-pane", "-p"]);
        let text = String::from_utf8_lossy(&pane.stdout).into_owned();
        if text.contains(&run) && text.contains("agents") && text.contains("waiting") {
            break text;
        }
        assert!(
            Instant::now() < deadline,
            "the view never showed the team:\n{text}"
        );
        std::thread::sleep(Duration::from_millis(200));
    };
    assert!(
        screen.contains("round") && screen.contains("ms/round"),
        "{screen}"
    );
    tmux(&["send-keys", "q"]);
    let deadline = Instant::now() + Duration::from_secs(10);
    while tmux(&["has-session"]).status.success() {
        assert!(Instant::now() < deadline, "q did not quit");
        std::thread::sleep(Duration::from_millis(100));
    }
    stop(team);
}

#[test]
fn without_a_terminal_top_says_so_and_once_works_with_nothing_running() {
    let out = admm_ta().arg("top").output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--once"));
    let out = admm_ta()
        .args(["top", "no-such-run", "--once", "--interval", "50"])
        .output()
        .unwrap();
    assert!(out.status.success());
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim(),
        "no running team"
    );
}
