//! Standing teams whose robots keep their own costs (`costs = "private"`), each robot an
//! `admm-ta agent --serve` sidecar driven through its standard input and output, as a robot
//! program would: every episode's assignment is the centralized optimum of the stacked rows
//! (which no process of the team ever holds) on uniform, distance, forbidden-pair,
//! tie-heavy, constant and shifted costs, maximizing too; an infeasible episode says so and
//! the next one is optimal again; bad rows get an error line and the team waits; a robot
//! without a row is named by every robot; a robot whose program closes its input ends the
//! team cleanly, with nothing left in shared memory.
//!
//! * `episodes`: every episode optimal (transports, costs, maximizing, 100 episodes,
//!   parts of the team);
//! * `faults`: bad rows, missing rows, leaving, signals, refusals, row files, hosts, the
//!   Python example;
//! * `elastic`: robots that leave, join and crash while the team goes on, on every
//!   transport a standing team runs on.

mod dual;
mod elastic;
mod episodes;
mod faults;

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

pub(crate) type Row = Vec<Option<f64>>;

pub(super) fn admm_ta() -> Command {
    Command::new(env!("CARGO_BIN_EXE_admm-ta"))
}

/// A private team's file; `extra` adds keys.
pub(super) fn team_file(
    dir: &Path,
    run: &str,
    robots: usize,
    tasks: usize,
    extra: &str,
) -> PathBuf {
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
pub(crate) struct Sidecar {
    pub(crate) id: usize,
    pub(crate) child: Child,
    stdin: Option<ChildStdin>,
    lines: Receiver<String>,
    /// Its standard error so far (read as it comes).
    stderr: std::sync::Arc<std::sync::Mutex<String>>,
}

impl Sidecar {
    pub(super) fn start(team: &Path, id: usize) -> Self {
        Self::start_with(team, id, &[])
    }

    /// A sidecar with more environment variables (`RUST_LOG`, `ADMM_TA_FAULT`).
    pub(super) fn start_with(team: &Path, id: usize, env: &[(&str, &str)]) -> Self {
        let mut command = admm_ta();
        command
            .args(["agent", "--team", team.to_str().unwrap(), "--robot"])
            .arg(id.to_string())
            .arg("--serve")
            .envs(env.iter().copied());
        Self::spawn(command, id)
    }

    /// Robot `id`'s sidecar started by `command` (an `admm-ta agent --serve`, maybe in a
    /// network namespace).
    pub(crate) fn spawn(mut command: Command, id: usize) -> Self {
        let mut child = command
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
        let stderr = std::sync::Arc::new(std::sync::Mutex::new(String::new()));
        let mut err = child.stderr.take().unwrap();
        let text = std::sync::Arc::clone(&stderr);
        std::thread::spawn(move || {
            let mut buffer = [0u8; 4096];
            while let Ok(read) = std::io::Read::read(&mut err, &mut buffer) {
                if read == 0 {
                    return;
                }
                text.lock()
                    .unwrap()
                    .push_str(&String::from_utf8_lossy(&buffer[..read]));
            }
        });
        let stdin = child.stdin.take();
        Self {
            id,
            child,
            stdin,
            lines,
            stderr,
        }
    }

    /// Its standard error so far.
    pub(crate) fn stderr_text(&self) -> String {
        self.stderr.lock().unwrap().clone()
    }

    /// Waits (up to a minute) until its standard error says `text`.
    pub(super) fn await_stderr(&self, text: &str) {
        let until = std::time::Instant::now() + Duration::from_secs(60);
        while !self.stderr_text().contains(text) {
            assert!(
                std::time::Instant::now() < until,
                "robot {}: no {text:?} on stderr within 60 s: {}",
                self.id,
                self.stderr_text()
            );
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    pub(super) fn send(&mut self, line: &str) {
        let stdin = self.stdin.as_mut().unwrap();
        writeln!(stdin, "{line}").unwrap();
        stdin.flush().unwrap();
    }

    /// Raw bytes (a line that is no text).
    pub(super) fn send_bytes(&mut self, bytes: &[u8]) {
        let stdin = self.stdin.as_mut().unwrap();
        stdin.write_all(bytes).unwrap();
        stdin.flush().unwrap();
    }

    /// Its row (an episode with fewer tasks than the team's says how many).
    pub(crate) fn send_row(&mut self, row: &Row) {
        self.send(&serde_json::json!({ "costs": row, "tasks": row.len() }).to_string());
    }

    /// The next line, within a minute (a test never hangs).
    pub(crate) fn next(&mut self) -> Value {
        match self.lines.recv_timeout(Duration::from_secs(60)) {
            Ok(line) => serde_json::from_str(&line).unwrap_or_else(|e| panic!("{line}: {e}")),
            Err(_) => {
                let _ = self.child.kill();
                let _ = self.child.wait();
                std::thread::sleep(Duration::from_millis(50));
                panic!(
                    "robot {}: no line within 60 s; stderr: {}",
                    self.id,
                    self.stderr_text()
                )
            }
        }
    }

    pub(crate) fn close(&mut self) {
        self.stdin = None;
    }

    /// Its exit status, within a minute, and its standard error.
    pub(crate) fn finish(mut self) -> (std::process::ExitStatus, String) {
        self.stdin = None;
        let status = common::wait_with_deadline(&mut self.child, Duration::from_secs(60));
        // The reader has the rest once the pipe closes.
        std::thread::sleep(Duration::from_millis(20));
        (status, self.stderr_text())
    }
}

pub(super) trait StderrNow {
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
pub(super) fn finish_all(mut sidecars: Vec<Sidecar>) {
    for s in &mut sidecars {
        s.close();
    }
    for s in sidecars {
        let id = s.id;
        let (status, stderr) = s.finish();
        assert!(status.success(), "robot {id}: {status}: {stderr}");
    }
}

/// Starts every robot's sidecar (its first row may come at once: it waits in the pipe).
pub(super) fn start_team(team: &Path, robots: usize) -> Vec<Sidecar> {
    (0..robots).map(|i| Sidecar::start(team, i)).collect()
}

/// One episode: every robot gives its row, then reads its answer.
pub(super) fn episode(sidecars: &mut [Sidecar], rows: &[Row]) -> Vec<Value> {
    for (s, row) in sidecars.iter_mut().zip(rows) {
        s.send_row(row);
    }
    sidecars.iter_mut().map(Sidecar::next).collect()
}

/// The centralized optimum of the stacked rows (`None`: no feasible assignment).
pub(crate) fn optimum(rows: &[Row], maximize: bool) -> Option<f64> {
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
pub(super) fn assert_optimal(answers: &[Value], rows: &[Row], maximize: bool, what: &str) {
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

/// Shared-memory files of the team `run` (on one machine, or on hosts `alpha` and `beta`):
/// its own and its rosters'.
pub(super) fn shm_of(run: &str) -> Vec<String> {
    use admm_ta_runtime::process::namespace::team_parts_prefix;
    let parts: Vec<String> = ["".to_string(), "-alpha".into(), "-beta".into()]
        .iter()
        .map(|host| team_parts_prefix(&format!("{run}{host}")))
        .collect();
    std::fs::read_dir("/dev/shm")
        .map(|entries| {
            entries
                .flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|name| name.contains(run) || parts.iter().any(|p| name.starts_with(p)))
                .collect()
        })
        .unwrap_or_default()
}

pub(crate) fn uniform(rng: &mut SeededRng, n: usize, m: usize, scale: f64, shift: f64) -> Vec<Row> {
    (0..n)
        .map(|_| {
            (0..m)
                .map(|_| Some(shift + scale * rng.uniform()))
                .collect()
        })
        .collect()
}

pub(super) fn distances(rng: &mut SeededRng, n: usize, m: usize) -> Vec<Row> {
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
pub(super) fn ties(rng: &mut SeededRng, n: usize, m: usize, levels: usize) -> Vec<Row> {
    (0..n)
        .map(|_| {
            (0..m)
                .map(|_| Some(1.0 + rng.below(levels) as f64))
                .collect()
        })
        .collect()
}

/// Integer costs with about `share` of the pairs forbidden, feasible.
pub(super) fn forbidden(rng: &mut SeededRng, n: usize, m: usize, share: f64) -> Vec<Row> {
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

/// Every robot that took part certified the optimum of the rows of those that took part;
/// the others relayed (no task).
pub(super) fn assert_optimal_part(answers: &[Value], rows: &[Option<Row>], what: &str) {
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
