//! A standing team's faults and refusals, its robots started from row files, across hosts,
//! and the Python robot example.

use super::*;
use crate::common;
use admm_ta_topologies::rng::SeededRng;
use serde_json::Value;
use std::path::Path;
use std::process::Command;
use std::process::{Child, Stdio};
use std::time::Duration;

/// Bad rows get an error line and change nothing; a robot without a row by the deadline is
/// named by every robot; a robot whose program closes its input ends the team, cleanly.
#[test]
fn bad_rows_missing_rows_and_leaving() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("privfault-{}", std::process::id());
    let (n, m) = (4, 4);
    let team = team_file(
        dir.path(),
        &run,
        n,
        m,
        "topology = \"ring\"\nepisode_timeout = 3.0\n",
    );
    let mut team_of = start_team(&team, n);
    let mut rng = SeededRng::new(2);
    let rows = uniform(&mut rng, n, m, 1.0, 0.0);
    for bad in [
        "not json",
        "{\"costs\": [1, 2, 3, 4, 5]}",
        "{\"costs\": [1, 2, 3]}",
        "{\"costs\": [1, 2, 3], \"tasks\": 2}",
        "{\"costs\": []}",
        "{\"costs\": [1, 2, 3, 4], \"available\": false}",
        "{\"available\": true}",
        "{\"costs\": [1, 2, 3, 4], \"episode\": 5}",
        "{\"cost\": [1, 2, 3, 4]}",
        "{\"costs\": [1, 2, \"x\", 4]}",
        "[1, 2, 3, 4]",
    ] {
        team_of[2].send(bad);
        let error = team_of[2].next();
        let text = error["error"].as_str().unwrap_or_else(|| panic!("{error}"));
        assert!(!text.is_empty() && error["episode"] == 0, "{error}");
    }
    team_of[2].send_bytes(b"\xff\xfe not text\n");
    let error = team_of[2].next();
    assert!(
        error["error"].as_str().is_some_and(|e| e.contains("UTF-8")),
        "{error}"
    );
    assert_optimal(
        &episode(&mut team_of, &rows),
        &rows,
        false,
        "after bad rows",
    );
    // Robot 3's program gives no row in episode 1.
    let started = std::time::Instant::now();
    for s in &mut team_of[..3] {
        s.send_row(&rows[s.id]);
    }
    for s in &mut team_of {
        let a = s.next();
        assert_eq!(a["missing"], serde_json::json!([3]), "{a}");
        assert!(a["task"].is_null() && a["episode"] == 1, "{a}");
    }
    assert!(
        started.elapsed() >= Duration::from_secs(2),
        "the deadline is 3 s"
    );
    let rows = uniform(&mut rng, n, m, 1.0, 0.0);
    assert_optimal(
        &episode(&mut team_of, &rows),
        &rows,
        false,
        "after a missing row",
    );
    // Robot 1's program ends; the others learn it in the next episode's agreement.
    team_of[1].close();
    for s in team_of.iter_mut().filter(|s| s.id != 1) {
        s.send_row(&rows[s.id]);
    }
    for s in team_of.iter_mut().filter(|s| s.id != 1) {
        let a = s.next();
        assert_eq!(a["left"], serde_json::json!([1]), "{a}");
    }
    finish_all(team_of);
    assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));
}

#[test]
fn private_teams_refuse_what_they_cannot_do() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("", vec!["agent", "--id", "0"], "start them with --serve"),
        ("", vec!["collect"], "no results to collect"),
        (
            "method = \"dual\"\ndual_variant = \"paper\"\n",
            vec!["agent", "--id", "0", "--serve"],
            "cannot keep costs private",
        ),
        (
            "method = \"market\"\n",
            vec!["agent", "--id", "0", "--serve"],
            "cannot keep costs private",
        ),
        (
            "forbidden = \"pairs.txt\"\n",
            vec!["agent", "--id", "0", "--serve"],
            "null for a forbidden task",
        ),
    ];
    for (extra, args, expected) in cases {
        let team = team_file(dir.path(), "privrefuse", 4, 4, extra);
        let out = admm_ta()
            .args(&args[..1])
            .args(["--team", team.to_str().unwrap()])
            .args(&args[1..])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
    }
    // A team whose method's message is smaller than its agreements (3 robots, 1 task: 3
    // values of the primal, 4 for the opening) runs in messages made larger.
    let team = team_file(dir.path(), "privsmall", 3, 1, "");
    let mut team_of = start_team(&team, 3);
    let rows = vec![vec![Some(3.0)], vec![Some(1.0)], vec![Some(2.0)]];
    assert_optimal(&episode(&mut team_of, &rows), &rows, false, "3 × 1");
    finish_all(team_of);
}

/// The same standing team across two hosts (every agent on Zenoh, and iceoryx2 per host with
/// a bridge between them), on one machine over loopback: every episode optimal, and every
/// host ends once its robots have left.
#[cfg(feature = "zenoh")]
#[test]
fn a_private_team_across_two_hosts() {
    for transport in ["zenoh", "mixed"] {
        let dir = tempfile::tempdir().unwrap();
        let run = format!("privz{}-{}", &transport[..1], std::process::id());
        let (n, m) = (6, 5);
        let mut hosts_text = format!("topology = \"ring\"\ntransport = \"{transport}\"\n");
        for (name, agents) in [("alpha", "[0, 1, 2]"), ("beta", "[3, 4, 5]")] {
            hosts_text += &format!(
                "\n[[hosts]]\nname = \"{name}\"\nagents = {agents}\nendpoint = \"tcp/127.0.0.1:{}\"\n",
                common::loopback_port()
            );
        }
        let team = team_file(dir.path(), &run, n, m, &hosts_text);
        let mut hosts: Vec<Child> = ["alpha", "beta"]
            .iter()
            .map(|name| {
                admm_ta()
                    .args(["host", "--team", team.to_str().unwrap(), "--name", name])
                    .stdout(Stdio::null())
                    .stderr(Stdio::piped())
                    .spawn()
                    .unwrap()
            })
            .collect();
        let mut team_of = start_team(&team, n);
        let mut rng = SeededRng::new(21);
        for k in 0..4 {
            let rows = match k {
                0 => uniform(&mut rng, n, m, 1.0, 0.0),
                1 => distances(&mut rng, n, m),
                2 => forbidden(&mut rng, n, m, 0.4),
                _ => ties(&mut rng, n, m, 2),
            };
            let what = format!("{transport} episode {k}");
            assert_optimal(&episode(&mut team_of, &rows), &rows, false, &what);
        }
        finish_all(team_of);
        for host in &mut hosts {
            let status = common::wait_with_deadline(host, Duration::from_secs(60));
            assert!(
                status.success(),
                "{transport}: {}",
                host.wait_with_output_now()
            );
        }
        assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));
    }
}

/// A termination signal to one robot's sidecar stops the whole team, idle between episodes
/// as it is, each sidecar saying why on its output (a robot whose process dies is another
/// matter: the others go on without it, `elastic`). Nothing is left in shared memory.
#[test]
fn a_signal_stops_the_standing_team() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("privsig-{}", std::process::id());
    let n = 4;
    let team = team_file(dir.path(), &run, n, n, "topology = \"ring\"\n");
    let mut team_of = start_team(&team, n);
    let mut rng = SeededRng::new(8);
    let rows = uniform(&mut rng, n, n, 1.0, 0.0);
    assert_optimal(&episode(&mut team_of, &rows), &rows, false, "before");
    // SAFETY: signalling a child this test started.
    unsafe { libc::kill(team_of[2].child.id() as i32, libc::SIGTERM) };
    for s in team_of.iter_mut().filter(|s| s.id != 2) {
        let a = s.next();
        assert_eq!(a["failed"], true, "{a}");
        let error = a["error"].as_str().unwrap();
        assert!(error.contains("SIGTERM"), "{error}");
    }
    for s in team_of {
        let id = s.id;
        let (status, stderr) = s.finish();
        assert_eq!(
            status.code(),
            Some(128 + libc::SIGTERM),
            "robot {id}: {stderr}"
        );
    }
    assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));
}

/// The guide's Python robot example (standard library only) runs a standing team of its
/// robot programs to the end.
#[test]
fn the_python_robot_example_runs_a_standing_team() {
    if Command::new("python3").arg("--version").output().is_err() {
        eprintln!("skipped: python3 is not on PATH");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/robots/start_team.py");
    let out = Command::new("python3")
        .arg(script)
        .args(["--admm-ta", env!("CARGO_BIN_EXE_admm-ta")])
        .args(["--robots", "6", "--tasks", "4", "--episodes", "8"])
        .args(["--run", &format!("pyrobots-{}", std::process::id())])
        .arg("--dir")
        .arg(dir.path())
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("8 episodes") && stdout.ends_with("ok\n"),
        "{stdout}"
    );
}

/// `agent --row FILE`: robots started with only their own row, each from its own file (CSV
/// or JSON, inf or null for a forbidden task), solve one episode and leave together.
#[test]
fn robots_started_with_their_own_row_files() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("privrow-{}", std::process::id());
    let (n, m) = (5, 4);
    let team = team_file(dir.path(), &run, n, m, "topology = \"chain\"\n");
    let mut rng = SeededRng::new(12);
    let mut rows = forbidden(&mut rng, n, m, 0.3);
    rows[0][0] = Some(2.5);
    let children: Vec<Child> = (0..n)
        .map(|i| {
            let path = dir.path().join(format!("row-{i}"));
            let text = if i % 2 == 0 {
                let cells: Vec<String> = rows[i]
                    .iter()
                    .map(|v| v.map_or("inf".into(), |v| v.to_string()))
                    .collect();
                cells.join(",") + "\n"
            } else {
                serde_json::json!([rows[i]]).to_string()
            };
            std::fs::write(&path, text).unwrap();
            admm_ta()
                .args(["agent", "--team", team.to_str().unwrap(), "--id"])
                .arg(i.to_string())
                .arg("--row")
                .arg(&path)
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    let answers: Vec<Value> = children
        .into_iter()
        .map(|mut child| {
            let status = common::wait_with_deadline(&mut child, Duration::from_secs(60));
            let out = child.wait_with_output().unwrap();
            assert!(status.success(), "{}", String::from_utf8_lossy(&out.stderr));
            serde_json::from_slice(&out.stdout).unwrap()
        })
        .collect();
    assert_optimal(&answers, &rows, false, "row files");
    assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));
    // A team whose costs are not private takes no row.
    let plain = dir.path().join("plain.toml");
    std::fs::write(
        &plain,
        "run = \"privrowplain\"\nrobots = 2\ncosts = \"random\"\ntasks = 2\n",
    )
    .unwrap();
    let out = admm_ta()
        .args([
            "agent",
            "--team",
            plain.to_str().unwrap(),
            "--id",
            "0",
            "--row",
        ])
        .arg(dir.path().join("row-0"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("costs = \"private\""));
}
