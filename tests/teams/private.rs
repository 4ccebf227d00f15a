//! Standing teams whose robots keep their own costs (`costs = "private"`), each robot an
//! `admm-ta agent --serve` sidecar driven through its standard input and output, as a robot
//! program would: every episode's assignment is the centralized optimum of the stacked rows
//! (which no process of the team ever holds) on uniform, distance, forbidden-pair,
//! tie-heavy, constant and shifted costs, maximizing too; an infeasible episode says so and
//! the next one is optimal again; bad rows get an error line and the team waits; a robot
//! without a row is named by every robot; a robot whose program closes its input ends the
//! team cleanly, with nothing left in shared memory.

use crate::common;

use admm_ta_agents::certify::oracle;
use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_topologies::rng::SeededRng;
use serde_json::Value;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::Duration;

type Row = Vec<Option<f64>>;

fn admm_ta() -> Command {
    Command::new(env!("CARGO_BIN_EXE_admm-ta"))
}

/// A private team's file; `extra` adds keys.
fn team_file(dir: &Path, run: &str, robots: usize, tasks: usize, extra: &str) -> PathBuf {
    let path = dir.join("team.toml");
    std::fs::write(
        &path,
        format!(
            "run = \"{run}\"\nrobots = {robots}\ntasks = {tasks}\ncosts = \"private\"\nstartup_timeout = 30.0\nround_timeout = 20.0\n{extra}"
        ),
    )
    .unwrap();
    path
}

/// One robot's sidecar, as its program sees it.
struct Sidecar {
    id: usize,
    child: Child,
    stdin: Option<ChildStdin>,
    lines: Receiver<String>,
}

impl Sidecar {
    fn start(team: &Path, id: usize) -> Self {
        let mut child = admm_ta()
            .args(["agent", "--team", team.to_str().unwrap(), "--id"])
            .arg(id.to_string())
            .arg("--serve")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let stdout = child.stdout.take().unwrap();
        let (sender, lines) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { return };
                if sender.send(line).is_err() {
                    return;
                }
            }
        });
        let stdin = child.stdin.take();
        Self {
            id,
            child,
            stdin,
            lines,
        }
    }

    fn send(&mut self, line: &str) {
        let stdin = self.stdin.as_mut().unwrap();
        writeln!(stdin, "{line}").unwrap();
        stdin.flush().unwrap();
    }

    fn send_row(&mut self, row: &Row) {
        self.send(&serde_json::json!({ "costs": row }).to_string());
    }

    /// The next line, within a minute (a test never hangs).
    fn next(&mut self) -> Value {
        match self.lines.recv_timeout(Duration::from_secs(60)) {
            Ok(line) => serde_json::from_str(&line).unwrap_or_else(|e| panic!("{line}: {e}")),
            Err(_) => {
                let _ = self.child.kill();
                let out = self.child.wait_with_output_now();
                panic!("robot {}: no line within 60 s; stderr: {out}", self.id)
            }
        }
    }

    fn close(&mut self) {
        self.stdin = None;
    }

    /// Its exit status, within a minute, and its standard error.
    fn finish(mut self) -> (std::process::ExitStatus, String) {
        self.stdin = None;
        let status = common::wait_with_deadline(&mut self.child, Duration::from_secs(60));
        (status, self.child.wait_with_output_now())
    }
}

trait StderrNow {
    fn wait_with_output_now(&mut self) -> String;
}

impl StderrNow for Child {
    fn wait_with_output_now(&mut self) -> String {
        let mut text = String::new();
        if let Some(mut err) = self.stderr.take() {
            let _ = std::io::Read::read_to_string(&mut err, &mut text);
        }
        text
    }
}

/// Every program closes its input (all leave at once, in one agreement); every sidecar
/// must exit 0.
fn finish_all(mut sidecars: Vec<Sidecar>) {
    for s in &mut sidecars {
        s.close();
    }
    for s in sidecars {
        let id = s.id;
        let (status, stderr) = s.finish();
        assert!(status.success(), "robot {id}: {status}: {stderr}");
    }
}

/// Starts every robot's sidecar; each says it is ready.
fn start_team(team: &Path, robots: usize) -> Vec<Sidecar> {
    let mut sidecars: Vec<Sidecar> = (0..robots).map(|i| Sidecar::start(team, i)).collect();
    for s in &mut sidecars {
        let ready = s.next();
        assert_eq!(ready["ready"], true, "{ready}");
        assert_eq!(ready["robot"], s.id);
    }
    sidecars
}

/// One episode: every robot gives its row, then reads its answer.
fn episode(sidecars: &mut [Sidecar], rows: &[Row]) -> Vec<Value> {
    for (s, row) in sidecars.iter_mut().zip(rows) {
        s.send_row(row);
    }
    sidecars.iter_mut().map(Sidecar::next).collect()
}

/// The centralized optimum of the stacked rows (`None`: no feasible assignment).
fn optimum(rows: &[Row], maximize: bool) -> Option<f64> {
    let (n, m) = (rows.len(), rows[0].len());
    let forbidden = if maximize {
        f64::NEG_INFINITY
    } else {
        f64::INFINITY
    };
    let values = rows
        .iter()
        .flat_map(|r| r.iter().map(|v| v.unwrap_or(forbidden)))
        .collect();
    let costs = CostMatrix::new(n, m, values).unwrap();
    let problem = if maximize {
        TaskAssignmentProblem::maximizing(costs, CaseChoice::Auto)
    } else {
        TaskAssignmentProblem::new(costs, CaseChoice::Auto)
    }
    .ok()?;
    Some(oracle::solve(&problem).unwrap().cost)
}

/// Every robot certified the same assignment, its own task in it, at the optimum.
fn assert_optimal(answers: &[Value], rows: &[Row], maximize: bool, what: &str) {
    let best = optimum(rows, maximize).expect("a feasible episode");
    let assignment = &answers[0]["assignment"];
    for (i, a) in answers.iter().enumerate() {
        assert_eq!(a["certified"], true, "{what}: robot {i}: {a}");
        assert_eq!(a["feasible"], true, "{what}: robot {i}: {a}");
        assert_eq!(&a["assignment"], assignment, "{what}: robot {i}: {a}");
        assert_eq!(a["task"], assignment[i], "{what}: robot {i}: {a}");
        let total = a["total_cost"].as_f64().unwrap();
        assert!(
            common::relative_gap(total, best) <= 1e-9,
            "{what}: robot {i} reports {total}, the optimum is {best}"
        );
        let task = a["task"].as_u64().unwrap() as usize;
        assert_eq!(a["cost"].as_f64(), rows[i][task], "{what}: robot {i}");
    }
}

/// Shared-memory files of the team `run`.
fn shm_of(run: &str) -> Vec<String> {
    std::fs::read_dir("/dev/shm")
        .map(|entries| {
            entries
                .flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|name| name.contains(run))
                .collect()
        })
        .unwrap_or_default()
}

fn uniform(rng: &mut SeededRng, n: usize, m: usize, scale: f64, shift: f64) -> Vec<Row> {
    (0..n)
        .map(|_| {
            (0..m)
                .map(|_| Some(shift + scale * rng.uniform()))
                .collect()
        })
        .collect()
}

fn distances(rng: &mut SeededRng, n: usize, m: usize) -> Vec<Row> {
    let robots: Vec<(f64, f64)> = (0..n).map(|_| (rng.uniform(), rng.uniform())).collect();
    let tasks: Vec<(f64, f64)> = (0..m).map(|_| (rng.uniform(), rng.uniform())).collect();
    robots
        .iter()
        .map(|r| {
            tasks
                .iter()
                .map(|t| Some(((r.0 - t.0).powi(2) + (r.1 - t.1).powi(2)).sqrt() * 100.0))
                .collect()
        })
        .collect()
}

/// Integer costs in 1..=levels: many ties.
fn ties(rng: &mut SeededRng, n: usize, m: usize, levels: usize) -> Vec<Row> {
    (0..n)
        .map(|_| {
            (0..m)
                .map(|_| Some(1.0 + rng.below(levels) as f64))
                .collect()
        })
        .collect()
}

/// Integer costs with about `share` of the pairs forbidden, feasible.
fn forbidden(rng: &mut SeededRng, n: usize, m: usize, share: f64) -> Vec<Row> {
    loop {
        let rows: Vec<Row> = (0..n)
            .map(|_| {
                (0..m)
                    .map(|_| (rng.uniform() >= share).then(|| rng.below(20) as f64))
                    .collect()
            })
            .collect();
        if optimum(&rows, false).is_some() {
            return rows;
        }
    }
}

#[test]
fn private_rows_reach_the_optimum_of_the_stacked_rows() {
    for transport in ["ipc", "shm", "uds"] {
        stacked_rows_optimal_over(transport);
    }
}

fn stacked_rows_optimal_over(transport: &str) {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("priv{transport}-{}", std::process::id());
    let (n, m) = (7, 5);
    let team = team_file(
        dir.path(),
        &run,
        n,
        m,
        &format!("topology = \"ring\"\nseed = 3\ntransport = \"{transport}\"\n"),
    );
    let mut team_of = start_team(&team, n);
    let mut rng = SeededRng::new(11);
    let mut cases: Vec<(&str, Vec<Row>)> = vec![
        ("uniform", uniform(&mut rng, n, m, 1.0, 0.0)),
        ("uniform again", uniform(&mut rng, n, m, 1.0, 0.0)),
        ("distance", distances(&mut rng, n, m)),
        ("ties", ties(&mut rng, n, m, 3)),
        ("forbidden", forbidden(&mut rng, n, m, 0.5)),
        ("shifted", uniform(&mut rng, n, m, 1e-3, 1e9)),
        ("negative", uniform(&mut rng, n, m, 50.0, -80.0)),
        ("constant", vec![vec![Some(4.0); m]; n]),
    ];
    // A small change of the last costs (a warm episode).
    let mut drift = cases[2].1.clone();
    for row in &mut drift {
        for v in row.iter_mut().flatten() {
            *v += rng.uniform();
        }
    }
    cases.insert(3, ("distance, moved", drift));
    for (what, rows) in &cases {
        let answers = episode(&mut team_of, rows);
        assert_optimal(&answers, rows, false, &format!("{transport}: {what}"));
    }
    // No robot may do task 0: no feasible assignment, said by every robot.
    let mut infeasible = uniform(&mut rng, n, m, 1.0, 0.0);
    for row in &mut infeasible {
        row[0] = None;
    }
    for a in episode(&mut team_of, &infeasible) {
        assert_eq!(a["feasible"], false, "{a}");
        assert_eq!(a["certified"], false, "{a}");
        assert!(a["task"].is_null(), "{a}");
    }
    // And the next episode is optimal again.
    let rows = distances(&mut rng, n, m);
    assert_optimal(
        &episode(&mut team_of, &rows),
        &rows,
        false,
        "after infeasible",
    );
    finish_all(team_of);
    assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));
}

#[test]
fn private_profits_are_maximised_on_a_complete_graph() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("privmax-{}", std::process::id());
    let n = 5;
    let team = team_file(
        dir.path(),
        &run,
        n,
        n,
        "maximize = true\nwarm_start = false\n",
    );
    let mut team_of = start_team(&team, n);
    let mut rng = SeededRng::new(4);
    for k in 0..4 {
        let rows = if k % 2 == 0 {
            uniform(&mut rng, n, n, 10.0, 0.0)
        } else {
            forbidden(&mut rng, n, n, 0.3)
        };
        assert_optimal(&episode(&mut team_of, &rows), &rows, true, "maximize");
    }
    finish_all(team_of);
}

/// 100 consecutive episodes of a 10-robot standing team with costs changing every episode:
/// every one optimal, nothing left in shared memory afterwards.
#[test]
fn a_hundred_episodes_of_ten_robots() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("priv100-{}", std::process::id());
    let (n, m) = (10, 8);
    let team = team_file(
        dir.path(),
        &run,
        n,
        m,
        "topology = \"random:0.4\"\nseed = 9\n",
    );
    let mut team_of = start_team(&team, n);
    let mut rng = SeededRng::new(100);
    let mut rows = distances(&mut rng, n, m);
    for k in 0..100 {
        for row in &mut rows {
            for v in row.iter_mut().flatten() {
                *v = (*v + 4.0 * (rng.uniform() - 0.5)).max(0.0);
            }
        }
        let answers = episode(&mut team_of, &rows);
        assert_optimal(&answers, &rows, false, &format!("episode {k}"));
        assert_eq!(answers[0]["episode"], k);
    }
    finish_all(team_of);
    assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));
}

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
            "method = \"dual\"\n",
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
    // Too small a message for the agreement.
    let team = dir.path().join("small.toml");
    std::fs::write(
        &team,
        "run = \"privsmall\"\nrobots = 3\ntasks = 1\ncosts = \"private\"\n",
    )
    .unwrap();
    let out = admm_ta()
        .args([
            "agent",
            "--team",
            team.to_str().unwrap(),
            "--id",
            "0",
            "--serve",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("its agreement needs 4"));
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
/// as it is, each sidecar saying why on its output; a robot whose process dies is named by
/// the others at the next episode. Nothing is left in shared memory either way.
#[test]
fn a_signal_or_a_dead_robot_stops_the_standing_team() {
    let dir = tempfile::tempdir().unwrap();
    for kill in [libc::SIGTERM, libc::SIGKILL] {
        let run = format!("privsig{kill}-{}", std::process::id());
        let n = 4;
        let team = team_file(dir.path(), &run, n, n, "topology = \"ring\"\n");
        let mut team_of = start_team(&team, n);
        let mut rng = SeededRng::new(8);
        let rows = uniform(&mut rng, n, n, 1.0, 0.0);
        assert_optimal(&episode(&mut team_of, &rows), &rows, false, "before");
        // SAFETY: signalling a child this test started.
        unsafe { libc::kill(team_of[2].child.id() as i32, kill) };
        if kill == libc::SIGKILL {
            std::thread::sleep(Duration::from_millis(200));
            for s in team_of.iter_mut().filter(|s| s.id != 2) {
                s.send_row(&rows[s.id]);
            }
        }
        for s in team_of.iter_mut().filter(|s| s.id != 2) {
            let a = s.next();
            assert_eq!(a["failed"], true, "{a}");
            let error = a["error"].as_str().unwrap();
            if kill == libc::SIGTERM {
                assert!(error.contains("SIGTERM"), "{error}");
            } else {
                assert!(error.contains('2'), "robot 2 is named: {error}");
            }
        }
        for s in team_of {
            let id = s.id;
            let (status, stderr) = s.finish();
            if kill == libc::SIGTERM {
                assert_eq!(
                    status.code(),
                    Some(128 + libc::SIGTERM),
                    "robot {id}: {stderr}"
                );
            } else if id != 2 {
                assert_eq!(status.code(), Some(4), "robot {id}: {stderr}");
            }
        }
        assert!(shm_of(&run).is_empty(), "{kill}: {:?}", shm_of(&run));
    }
}

/// Every robot that took part certified the optimum of the rows of those that took part;
/// the others relayed (no task).
fn assert_optimal_part(answers: &[Value], rows: &[Option<Row>], what: &str) {
    let taking: Vec<Row> = rows.iter().flatten().cloned().collect();
    let best = optimum(&taking, false).expect("a feasible episode");
    let assignment = &answers[0]["assignment"];
    for (i, a) in answers.iter().enumerate() {
        assert_eq!(&a["assignment"], assignment, "{what}: robot {i}: {a}");
        assert_eq!(a["certified"], true, "{what}: robot {i}: {a}");
        let total = a["total_cost"].as_f64().unwrap();
        assert!(
            common::relative_gap(total, best) <= 1e-9,
            "{what}: robot {i} reports {total}, the optimum is {best}"
        );
        match &rows[i] {
            Some(row) => {
                let task = a["task"].as_u64().unwrap() as usize;
                assert_eq!(a["task"], assignment[i], "{what}: robot {i}");
                assert_eq!(a["cost"].as_f64(), row[task], "{what}: robot {i}");
            }
            None => assert!(
                a["task"].is_null() && assignment[i].is_null(),
                "{what}: {a}"
            ),
        }
    }
}

/// Episodes with robots that take no part (unavailable, or without a row and
/// `on_failure = "continue"`) and with fewer tasks than declared: the optimum of what takes
/// part; too few robots, or rows of different lengths, solve nothing and say why.
#[test]
fn unavailable_robots_missing_rows_and_fewer_tasks() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("privpart-{}", std::process::id());
    let (n, m) = (6, 5);
    let team = team_file(
        dir.path(),
        &run,
        n,
        m,
        "topology = \"ring\"\non_failure = \"continue\"\nepisode_timeout = 2.0\n",
    );
    let mut team_of = start_team(&team, n);
    let mut rng = SeededRng::new(31);
    // (robots without a part: unavailable, missing), tasks
    let plans: [(&[usize], &[usize], usize); 6] = [
        (&[], &[], 5),
        (&[2], &[], 5),
        (&[], &[], 3),
        (&[1, 4], &[], 4),
        (&[], &[3], 5),
        (&[], &[], 5),
    ];
    for (k, (unavailable, missing, tasks)) in plans.iter().enumerate() {
        let full = distances(&mut rng, n, *tasks);
        let rows: Vec<Option<Row>> = (0..n)
            .map(|i| (!unavailable.contains(&i) && !missing.contains(&i)).then(|| full[i].clone()))
            .collect();
        for s in &mut team_of {
            match &rows[s.id] {
                Some(row) => s.send_row(row),
                None if unavailable.contains(&s.id) => s.send("{\"available\": false}"),
                None => {}
            }
        }
        let answers: Vec<Value> = team_of.iter_mut().map(Sidecar::next).collect();
        let what = format!("episode {k}");
        assert_optimal_part(&answers, &rows, &what);
        for a in &answers {
            assert_eq!(
                a["unavailable"].as_array().map_or(0, Vec::len),
                unavailable.len()
            );
            assert_eq!(a["missing"].as_array().map_or(0, Vec::len), missing.len());
        }
    }
    // Four robots for five tasks: infeasible, said by every robot.
    let full = uniform(&mut rng, n, m, 1.0, 0.0);
    for s in &mut team_of {
        if s.id < 2 {
            s.send("{\"available\": false}");
        } else {
            s.send_row(&full[s.id]);
        }
    }
    for s in &mut team_of {
        let a = s.next();
        assert!(a["task"].is_null() && a["feasible"] == false, "{a}");
        assert!(
            a["unsolved"].as_str().unwrap().contains("infeasible"),
            "{a}"
        );
    }
    // Rows of different lengths: nothing solved, and why.
    for s in &mut team_of {
        let len = if s.id == 0 { 4 } else { 5 };
        s.send_row(&full[s.id][..len].to_vec());
    }
    for s in &mut team_of {
        let a = s.next();
        assert!(a["task"].is_null(), "{a}");
        assert!(
            a["unsolved"].as_str().unwrap().contains("4 to 5 costs"),
            "{a}"
        );
    }
    // And everybody again.
    let rows = uniform(&mut rng, n, m, 1.0, 0.0);
    assert_optimal(&episode(&mut team_of, &rows), &rows, false, "all again");
    finish_all(team_of);
    assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));
}

/// The README's Python robot example (standard library only) runs a standing team of its
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

/// Robots that take no part on graphs whose robots have different numbers of neighbours (a
/// star's hub and leaves, a chain's ends): each runs its place in the part with its own
/// neighbours.
#[test]
fn parts_on_irregular_graphs() {
    for topology in ["star", "chain"] {
        let dir = tempfile::tempdir().unwrap();
        let run = format!("privirr{topology}-{}", std::process::id());
        let (n, m) = (6, 4);
        let team = team_file(
            dir.path(),
            &run,
            n,
            m,
            &format!("topology = \"{topology}\"\n"),
        );
        let mut team_of = start_team(&team, n);
        let mut rng = SeededRng::new(17);
        for away in [vec![3], vec![0], vec![0, 5]] {
            let full = distances(&mut rng, n, m);
            let rows: Vec<Option<Row>> = (0..n)
                .map(|i| (!away.contains(&i)).then(|| full[i].clone()))
                .collect();
            for s in &mut team_of {
                match &rows[s.id] {
                    Some(row) => s.send_row(row),
                    None => s.send("{\"available\": false, \"episode\": null}"),
                }
            }
            let answers: Vec<Value> = team_of.iter_mut().map(Sidecar::next).collect();
            assert_optimal_part(&answers, &rows, &format!("{topology}, away {away:?}"));
        }
        finish_all(team_of);
        assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));
    }
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
