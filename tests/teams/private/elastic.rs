//! Standing teams whose robots come and go while the team goes on, as robot programs drive
//! their sidecars: a robot leaves (its program closes its input) and the others solve
//! without it on the graph that is left (a ring becomes a chain: its diameter grows); a new
//! robot takes the free slot and is admitted; a hub's leave is refused (or forced, and the
//! robots cut off say so); a robot killed mid-episode costs at most that episode and a
//! restarted one joins again. Every episode is certified and the centralized optimum of
//! the stacked rows of the robots that took part; the other robots' processes stay the
//! same throughout; nothing is left in shared memory.

use super::*;
use crate::common;
use admm_ta_topologies::rng::SeededRng;
use serde_json::Value;
use std::collections::BTreeMap;
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

/// A standing team's robots as their programs see them.
struct Fleet {
    team: PathBuf,
    run: String,
    tasks: usize,
    /// The robots that take part, by number.
    members: BTreeMap<usize, Sidecar>,
    /// A robot started for a free slot, with the row it gave at once.
    joining: Option<(Sidecar, Row)>,
    /// The members' process ids when they started.
    pids: BTreeMap<usize, u32>,
    rng: SeededRng,
    /// Hosts of a team across hosts.
    hosts: Vec<Child>,
}

/// One episode's answers and rows, by robot.
struct Episode {
    answers: BTreeMap<usize, Value>,
    rows: BTreeMap<usize, Row>,
}

impl Fleet {
    fn start(team: PathBuf, run: &str, robots: usize, tasks: usize, hosts: Vec<Child>) -> Self {
        Self::start_with(team, run, (robots, tasks), hosts, &[])
    }

    /// [`Fleet::start`] with `env` added to every sidecar's environment.
    fn start_with(
        team: PathBuf,
        run: &str,
        (robots, tasks): (usize, usize),
        hosts: Vec<Child>,
        env: &[(&str, &str)],
    ) -> Self {
        let members: BTreeMap<usize, Sidecar> = (0..robots)
            .map(|i| (i, Sidecar::start_with(&team, i, env)))
            .collect();
        let pids = members.iter().map(|(&i, s)| (i, s.child.id())).collect();
        Self {
            team,
            run: run.to_string(),
            tasks,
            members,
            joining: None,
            pids,
            rng: SeededRng::new(robots as u64 * 7 + tasks as u64),
            hosts,
        }
    }

    fn row(&mut self) -> Row {
        (0..self.tasks)
            .map(|_| Some((self.rng.uniform() * 100.0).round() / 10.0))
            .collect()
    }

    /// One episode: every member gives a row; a joiner named in `joined` answers too.
    fn episode(&mut self) -> Episode {
        let rows: BTreeMap<usize, Row> = self
            .members
            .keys()
            .copied()
            .collect::<Vec<_>>()
            .into_iter()
            .map(|i| (i, self.row()))
            .collect();
        for (i, s) in &mut self.members {
            s.send_row(&rows[i]);
        }
        let mut answers: BTreeMap<usize, Value> = self
            .members
            .iter_mut()
            .map(|(&i, s)| (i, s.next()))
            .collect();
        let mut rows = rows;
        let first = answers.values().next().cloned().unwrap();
        if let Some((joiner, _)) = &self.joining
            && first["joined"]
                .as_array()
                .is_some_and(|j| j.contains(&Value::from(joiner.id)))
        {
            let (mut joiner, row) = self.joining.take().unwrap();
            let id = joiner.id;
            answers.insert(id, joiner.next());
            rows.insert(id, row);
            self.pids.insert(id, joiner.child.id());
            self.members.insert(id, joiner);
        }
        Episode { answers, rows }
    }

    /// Robot `id`'s program ends: it leaves at the next episode. Odd robots say so,
    /// `{"leave": true}` with their input still open; even ones close their input.
    fn close(&mut self, id: usize) -> Sidecar {
        let mut s = self.members.remove(&id).unwrap();
        if id % 2 == 1 {
            s.send(r#"{"leave": true}"#);
        } else {
            s.close();
        }
        s
    }

    /// A robot started for slot `id`, once it asks to join, with its first row waiting.
    fn join(&mut self, id: usize) {
        let s = Sidecar::start_with(&self.team, id, &[("RUST_LOG", "admm_ta_runtime=info")]);
        s.await_stderr("asking to join the running team");
        let row = self.row();
        let mut s = s;
        s.send_row(&row);
        self.joining = Some((s, row));
    }

    /// Robot `id`'s process killed.
    fn kill(&mut self, id: usize) {
        let mut s = self.members.remove(&id).unwrap();
        let _ = s.child.kill();
        let _ = s.child.wait();
    }

    /// Every program closes its input; every sidecar and host exits 0, the members'
    /// processes are those that started, nothing is left in shared memory.
    fn finish(mut self) {
        for (&i, s) in &self.members {
            assert_eq!(s.child.id(), self.pids[&i], "robot {i} was replaced");
        }
        let members = std::mem::take(&mut self.members);
        finish_all(members.into_values().collect());
        for host in &mut self.hosts {
            let status = common::wait_with_deadline(host, Duration::from_secs(60));
            assert!(status.success(), "host: {}", host.wait_with_output_now());
        }
        assert!(shm_of(&self.run).is_empty(), "{:?}", shm_of(&self.run));
    }
}

/// Every answer of `e` certified, the same assignment, each robot's own task in it, the
/// total the optimum of the stacked rows of those that took part.
fn assert_optimal_among(e: &Episode, what: &str) -> Value {
    let stacked: Vec<Row> = e.rows.values().cloned().collect();
    let best = optimum(&stacked, false).expect("a feasible episode");
    let first = e.answers.values().next().unwrap().clone();
    for (i, a) in &e.answers {
        assert_eq!(a["certified"], true, "{what}: robot {i}: {a}");
        assert_eq!(a["episode"], first["episode"], "{what}: robot {i}: {a}");
        assert_eq!(
            a["assignment"], first["assignment"],
            "{what}: robot {i}: {a}"
        );
        assert_eq!(a["task"], first["assignment"][*i], "{what}: robot {i}: {a}");
        let total = a["total_cost"].as_f64().unwrap();
        assert!(
            common::relative_gap(total, best) <= 1e-9,
            "{what}: robot {i} reports {total}, the optimum of {} rows is {best}",
            stacked.len()
        );
        let task = a["task"].as_u64().unwrap() as usize;
        assert_eq!(a["cost"].as_f64(), e.rows[i][task], "{what}: robot {i}");
    }
    let assignment = first["assignment"].as_array().unwrap();
    for (slot, task) in assignment.iter().enumerate() {
        assert_eq!(
            task.is_null(),
            !e.rows.contains_key(&slot),
            "{what}: slot {slot} in {first}"
        );
    }
    first
}

/// The hosts of a team across two hosts on loopback, and the team file's text for them.
pub(super) fn two_hosts(transport: &str, n: usize) -> String {
    let mut text = format!("transport = \"{transport}\"\n");
    let half = n / 2;
    for (name, agents) in [
        ("alpha", (0..half).collect::<Vec<_>>()),
        ("beta", (half..n).collect()),
    ] {
        text += &format!(
            "\n[[hosts]]\nname = \"{name}\"\nagents = {agents:?}\nendpoint = \"tcp/127.0.0.1:{}\"\n",
            common::loopback_port()
        );
    }
    text
}

pub(super) fn start_hosts(team: &Path) -> Vec<Child> {
    ["alpha", "beta"]
        .iter()
        .map(|name| {
            admm_ta()
                .args(["host", "--team", team.to_str().unwrap(), "--name", name])
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect()
}

/// The issue's fleet: an 8-robot ring, 30 episodes; robot 5 leaves after episode 9 (the 7
/// others solve on a chain: diameter 4 → 6), a new robot 5 joins at episode 20 and is named
/// within 2 episodes; every episode certified and optimal.
fn a_ring_loses_a_robot_and_takes_a_new_one(transport: &str) {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("elastic{}-{}", &transport[..2], std::process::id());
    let (n, m) = (8, 6);
    let across = matches!(transport, "zenoh" | "mixed");
    let extra = if across {
        two_hosts(transport, n)
    } else {
        format!("transport = \"{transport}\"\n")
    };
    let team = team_file(
        dir.path(),
        &run,
        n,
        m,
        &format!("topology = \"ring\"\nepisode_timeout = 30.0\n{extra}"),
    );
    let hosts = if across {
        start_hosts(&team)
    } else {
        Vec::new()
    };
    let mut fleet = Fleet::start(team, &run, n, m, hosts);
    let mut leaver = None;
    let mut joined_at = None;
    for k in 0..30u64 {
        let what = format!("{transport} episode {k}");
        if k == 10 {
            leaver = Some(fleet.close(5));
        }
        if k == 20 {
            fleet.join(5);
        }
        let e = fleet.episode();
        let first = assert_optimal_among(&e, &what);
        assert_eq!(first["episode"], k, "{what}: {first}");
        if k == 10 {
            assert_eq!(first["left"], serde_json::json!([5]), "{what}: {first}");
            let (status, stderr) = leaver.take().unwrap().finish();
            assert!(status.success(), "robot 5 leaving: {stderr}");
        }
        if (11..20).contains(&k) {
            // The ring without robot 5 is a chain of diameter 6: floods of 6 rounds.
            assert_eq!(first["agreement_rounds"], 13, "{what}: {first}");
            assert_eq!(e.answers.len(), 7, "{what}");
        }
        if k >= 20 && joined_at.is_none() && e.answers.contains_key(&5) {
            assert_eq!(first["joined"], serde_json::json!([5]), "{what}: {first}");
            joined_at = Some(k);
        }
        if k < 10 || joined_at.is_some() {
            assert_eq!(e.answers.len(), 8, "{what}");
        }
    }
    let joined_at = joined_at.expect("robot 5 joined");
    assert!(
        joined_at <= 22,
        "{transport}: robot 5 joined at episode {joined_at}"
    );
    fleet.finish();
}

#[test]
fn a_ring_loses_a_robot_and_takes_a_new_one_on_one_machine() {
    for transport in ["ipc", "shm", "uds"] {
        a_ring_loses_a_robot_and_takes_a_new_one(transport);
    }
}

#[cfg(feature = "zenoh")]
#[test]
fn a_ring_loses_a_robot_and_takes_a_new_one_across_two_hosts() {
    for transport in ["zenoh", "mixed"] {
        a_ring_loses_a_robot_and_takes_a_new_one(transport);
    }
}

/// A star's hub cannot leave while the others need it: its leave is refused with one line,
/// it relays, and the team goes on; once every other robot left, it leaves too. With
/// `leave = "force"`, it goes and the robots cut off say so.
#[test]
fn a_star_keeps_its_hub_unless_its_leave_is_forced() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("elasticstar-{}", std::process::id());
    let (n, m) = (5, 3);
    let team = team_file(dir.path(), &run, n, m, "topology = \"star\"\n");
    let mut fleet = Fleet::start(team, &run, n, m, Vec::new());
    fleet.episode();
    let mut hub = fleet.close(0);
    let e = fleet.episode();
    let first = assert_optimal_among(&e, "the hub asked to leave");
    assert_eq!(first["leave_refused"], serde_json::json!([0]), "{first}");
    let refused = hub.next();
    assert_eq!(refused["leave_refused"], true, "{refused}");
    assert!(
        refused["error"].as_str().unwrap().contains("cannot leave"),
        "{refused}"
    );
    for k in 0..3 {
        let e = fleet.episode();
        let first = assert_optimal_among(&e, &format!("the hub relays, {k}"));
        assert!(first["assignment"][0].is_null(), "{first}");
    }
    // The others leave; the hub goes with them.
    let members = std::mem::take(&mut fleet.members);
    finish_all(members.into_values().collect());
    let (status, stderr) = hub.finish();
    assert!(status.success(), "the hub: {stderr}");
    assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));

    let run = format!("elasticforce-{}", std::process::id());
    let team = team_file(
        dir.path(),
        &run,
        n,
        m,
        "topology = \"star\"\nleave = \"force\"\n",
    );
    let mut team_of = start_team(&team, n);
    let mut rng = SeededRng::new(3);
    let rows = uniform(&mut rng, n, m, 1.0, 0.0);
    assert_optimal(&episode(&mut team_of, &rows), &rows, false, "before");
    team_of[0].close();
    for s in &mut team_of[1..] {
        s.send_row(&rows[s.id]);
    }
    for s in &mut team_of[1..] {
        let a = s.next();
        assert_eq!(a["left"], serde_json::json!([0]), "{a}");
        assert_eq!(a["lost"], serde_json::json!([2, 3, 4]), "{a}");
    }
    // Robot 1 goes on alone; the others say they were cut off.
    for s in &mut team_of[2..] {
        let line = s.next();
        assert_eq!(line["failed"], true, "{line}");
        assert!(
            line["error"].as_str().unwrap().contains("cut off"),
            "{line}"
        );
    }
    let mut team_of = team_of.into_iter();
    let (status, stderr) = team_of.next().unwrap().finish();
    assert!(status.success(), "the hub: {stderr}");
    let mut one = team_of.next().unwrap();
    let alone = vec![Some(1.0); m];
    one.send_row(&alone);
    let a = one.next();
    assert_eq!(a["certified"], false, "one robot for {m} tasks: {a}");
    let (status, stderr) = one.finish();
    assert!(status.success(), "robot 1: {stderr}");
    for s in team_of {
        let (status, _) = s.finish();
        assert_eq!(status.code(), Some(4));
    }
    assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));
}

/// A robot killed mid-episode (SIGKILL: no cleanup) costs at most that episode: the others
/// solve it again without it, name it in `crashed` and go on; a restarted process for its
/// slot joins again; nothing is left in shared memory.
fn a_killed_robot_costs_at_most_one_episode(transport: &str) {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("elastickill{}-{}", &transport[..2], std::process::id());
    let (n, m) = (6, 4);
    let across = matches!(transport, "zenoh" | "mixed");
    let extra = if across {
        two_hosts(transport, n)
    } else {
        format!("transport = \"{transport}\"\n")
    };
    let team = team_file(
        dir.path(),
        &run,
        n,
        m,
        &format!("topology = \"ring\"\n{extra}"),
    );
    let hosts = if across {
        start_hosts(&team)
    } else {
        Vec::new()
    };
    let mut fleet = Fleet::start(team.clone(), &run, n, m, hosts);
    for _ in 0..2 {
        let e = fleet.episode();
        assert_optimal_among(&e, "before");
    }
    // Robot 2 dies in the middle of episode 2: the others wait for its row.
    let rows: BTreeMap<usize, Row> = fleet
        .members
        .keys()
        .copied()
        .collect::<Vec<_>>()
        .into_iter()
        .map(|i| (i, fleet.row()))
        .collect();
    for (i, s) in fleet.members.iter_mut().filter(|(i, _)| **i != 2) {
        s.send_row(&rows[i]);
    }
    std::thread::sleep(Duration::from_millis(100));
    let started = Instant::now();
    fleet.kill(2);
    let mut answers = BTreeMap::new();
    for (&i, s) in &mut fleet.members {
        answers.insert(i, s.next());
    }
    let took = started.elapsed();
    let mut rows = rows;
    rows.remove(&2);
    let e = Episode { answers, rows };
    let first = assert_optimal_among(&e, &format!("{transport}: the episode of the crash"));
    assert_eq!(first["crashed"], serde_json::json!([2]), "{first}");
    assert_eq!(first["episode"], 2, "{first}");
    assert!(took < Duration::from_secs(15), "{transport}: {took:?}");
    for k in 3..5 {
        let e = fleet.episode();
        assert_optimal_among(&e, &format!("{transport}: after the crash, {k}"));
    }
    // A robot for the free slot with another team file is refused by name.
    let rogue = team.with_file_name("rogue.toml");
    let text = std::fs::read_to_string(&team).unwrap();
    std::fs::write(&rogue, format!("seed = 99\n{text}")).unwrap();
    let out = admm_ta()
        .args([
            "agent",
            "--team",
            rogue.to_str().unwrap(),
            "--robot",
            "2",
            "--serve",
        ])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{transport}: {stderr}");
    assert!(stderr.contains("differs"), "{transport}: {stderr}");
    fleet.join(2);
    let mut joined = false;
    for k in 5..8 {
        let e = fleet.episode();
        assert_optimal_among(&e, &format!("{transport}: {k}"));
        joined |= e.answers.contains_key(&2);
    }
    assert!(joined, "{transport}: the restarted robot 2 joined");
    fleet.finish();
}

#[test]
fn a_killed_robot_costs_at_most_one_episode_on_one_machine() {
    for transport in ["ipc", "shm", "uds"] {
        a_killed_robot_costs_at_most_one_episode(transport);
    }
}

#[cfg(feature = "zenoh")]
#[test]
fn a_killed_robot_costs_at_most_one_episode_across_two_hosts() {
    for transport in ["zenoh", "mixed"] {
        a_killed_robot_costs_at_most_one_episode(transport);
    }
}

/// A robot leaving while two crashes split its ring is out, as it asked: the part that goes
/// on is the larger one, without it; its sidecar exits 0 (it said "cut off" and exited 4
/// before), while the robot beside it that did not ask to leave says it was cut off (4).
#[test]
fn a_leaver_cut_off_by_crashes_in_its_leave_is_out_as_it_asked() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("elasticsplit-{}", std::process::id());
    let (n, m) = (7, 3);
    let team = team_file(dir.path(), &run, n, m, "topology = \"ring\"\n");
    let log = [("RUST_LOG", "admm_ta_runtime=info")];
    let mut fleet = Fleet::start_with(team, &run, (n, m), Vec::new(), &log);
    assert_optimal_among(&fleet.episode(), "before");
    // Robot 2 asks to leave and waits in its leave episode for its neighbours' rows; robot
    // 3 beside it gives its row.
    let mut leaver = fleet.members.remove(&2).unwrap();
    leaver.send(r#"{"leave": true}"#);
    leaver.await_stderr("leaving the team");
    let mut beside = fleet.members.remove(&3).unwrap();
    let row = fleet.row();
    beside.send_row(&row);
    std::thread::sleep(Duration::from_millis(100));
    // Robots 1 and 4 die together: {2, 3} and {5, 6, 0} are apart; the larger part goes on.
    let mut dead: Vec<Sidecar> = [1, 4].map(|i| fleet.members.remove(&i).unwrap()).into();
    for s in &mut dead {
        let _ = s.child.kill();
    }
    for s in &mut dead {
        let _ = s.child.wait();
    }
    let e = fleet.episode();
    let first = assert_optimal_among(&e, "the part that goes on");
    let crashed = first["crashed"].as_array().unwrap();
    assert!(
        crashed.contains(&1.into()) && crashed.contains(&4.into()),
        "{first}"
    );
    let (status, stderr) = leaver.finish();
    assert!(status.success(), "the leaver: {status:?}: {stderr}");
    let line = beside.next();
    assert_eq!(line["failed"], true, "{line}");
    assert!(
        line["error"].as_str().unwrap().contains("cut off"),
        "{line}"
    );
    let (status, _) = beside.finish();
    assert_eq!(status.code(), Some(4));
    fleet.finish();
}
