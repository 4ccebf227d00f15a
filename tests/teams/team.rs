//! Agents started independently (`admm-ta agent --team FILE --robot I`), in a shuffled order with
//! delays, as separate commands: they find each other, solve, and `admm-ta collect` gets the
//! oracle's optimum. A missing agent fails the team with a line naming it, after the
//! start-up deadline, and nothing is left in shared memory.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::Duration;

fn admm_ta() -> Command {
    Command::new(env!("CARGO_BIN_EXE_admm-ta"))
}

/// Writes a team file; `run` must be unique among concurrently running tests.
fn team_file(
    dir: &Path,
    run: &str,
    robots: usize,
    costs: &Path,
    topology: &str,
    startup: f64,
) -> PathBuf {
    let path = dir.join("team.toml");
    std::fs::write(
        &path,
        format!(
            "run = \"{run}\"\nrobots = {robots}\ncosts = \"{}\"\ntopology = \"{topology}\"\nresults = \"results\"\nstartup_timeout = {startup}\nround_timeout = 20.0\n",
            costs.display()
        ),
    )
    .unwrap();
    path
}

/// A fixed shuffle of `0..n` (no RNG crate needed: a multiplicative permutation).
fn shuffled(n: usize, seed: usize) -> Vec<usize> {
    let step = (1..n)
        .rev()
        .find(|s| gcd(*s, n) == 1 && *s > n / 2)
        .unwrap_or(1);
    (0..n).map(|k| (seed + k * step) % n).collect()
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 { a } else { gcd(b, a % b) }
}

/// Starts agent `id` of `team` (a robot number, or a name when the costs name robots).
fn start(team: &Path, id: impl std::fmt::Display) -> Child {
    admm_ta()
        .args([
            "agent",
            "--team",
            team.to_str().unwrap(),
            "--robot",
            &id.to_string(),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Waits for every agent; each must succeed. Their outputs, by agent.
fn all_succeed(agents: impl IntoIterator<Item = (usize, Child)>) -> Vec<(usize, Output)> {
    agents
        .into_iter()
        .map(|(id, child)| {
            let out = child.wait_with_output().unwrap();
            assert!(
                out.status.success(),
                "agent {id}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            (id, out)
        })
        .collect()
}

/// Waits for every agent; each must succeed, report its own number and have converged.
fn all_converge(agents: impl IntoIterator<Item = (usize, Child)>) {
    for (id, out) in all_succeed(agents) {
        let line: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(line["id"], id);
        assert_eq!(line["converged"], true);
    }
}

/// `collect --json` of `team` (with `extra` arguments), which must succeed.
fn collect_json(team: &Path, extra: &[&str]) -> serde_json::Value {
    let out = admm_ta()
        .args(["collect", "--team", team.to_str().unwrap(), "--json"])
        .args(extra)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn team_shm_left(run: &str) -> Vec<String> {
    std::fs::read_dir("/dev/shm")
        .map(|d| {
            d.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.starts_with(&format!("adtat{}-{run}_", common::euid())))
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn independently_started_agents_reach_the_oracle_optimum() {
    for (k, (name, topology)) in [
        ("case2_uniform_10x2", "ring"),
        ("case1_uniform_20x20", "random:0.3"),
    ]
    .into_iter()
    .enumerate()
    {
        let instance = common::oracle_instances()
            .into_iter()
            .find(|i| i.name == name)
            .unwrap();
        let robots = instance.optimal_assignment.len();
        let dir = tempfile::tempdir().unwrap();
        let run = format!("t{}-{k}", std::process::id());
        let team = team_file(dir.path(), &run, robots, &instance.csv, topology, 60.0);
        let order = shuffled(robots, 3 + k);
        let mut children = Vec::new();
        for (n, &id) in order.iter().enumerate() {
            children.push((id, start(&team, id)));
            // Staggered starts: the early ones wait for the late ones.
            std::thread::sleep(Duration::from_millis(if n % 3 == 0 { 40 } else { 2 }));
        }
        all_converge(children);
        let result = collect_json(&team, &["--check"]);
        assert_eq!(result["optimal"], true, "{name}: {result}");
        let cost = result["cost"].as_f64().unwrap();
        assert!(
            common::relative_gap(cost, instance.optimal_cost) < 1e-9,
            "{name}: {cost}"
        );
        if instance.unique == Some(true) {
            let assignment: Vec<usize> =
                serde_json::from_value(result["assignment"].clone()).unwrap();
            assert_eq!(assignment, instance.optimal_assignment, "{name}");
        }
        assert!(team_shm_left(&run).is_empty(), "{:?}", team_shm_left(&run));
    }
}

/// A team whose cost file names its robots: the topology file and the agents' `--robot` use the
/// names, and a zenoh team's hosts list them by name.
#[test]
fn robots_go_by_the_cost_files_names_in_team_and_topology_files() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("n{}", std::process::id());
    let names = ["uav1", "uav2", "uav3", "uav4"];
    std::fs::write(
        dir.path().join("costs.csv"),
        ",dock_A,dock_B,dock_C\nuav1,4,1,3\nuav2,2,0,5\nuav3,3,2,2\nuav4,1,1,1\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("net.toml"),
        "robots = 4\nedges = [[\"uav1\", \"uav2\"], [\"uav2\", \"uav3\"], [\"uav3\", \"uav4\"]]\n",
    )
    .unwrap();
    let team = team_file(
        dir.path(),
        &run,
        4,
        &dir.path().join("costs.csv"),
        "net.toml",
        60.0,
    );
    let children: Vec<(usize, Child)> = names
        .iter()
        .enumerate()
        .map(|(id, name)| (id, start(&team, name)))
        .collect();
    all_converge(children);
    let out = collect(&team, &["--check", "--json"]);
    let result: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(result["optimal"], true, "{result}");
    // Case 2 (every robot works, every task is covered), by hand: uav1→B (1), uav2→B (0),
    // uav3→C (2), uav4→A (1).
    assert_eq!(result["cost"].as_f64().unwrap(), 4.0, "{result}");
    assert_eq!(result["assignment"], serde_json::json!([1, 1, 2, 0]));
    assert!(team_shm_left(&run).is_empty());
    // A name the costs do not have: exit 2, one line, nothing started.
    let out = admm_ta()
        .args(["agent", "--team", team.to_str().unwrap(), "--robot", "uav9"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("no robot is named 'uav9'"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");

    // Hosts by name, names and numbers mixed (a zenoh team: only a build with the feature
    // reads its file).
    if !cfg!(feature = "zenoh") {
        return;
    }
    let hosts = |second: &str| {
        format!(
            "run = \"h{run}\"\nrobots = 4\ncosts = \"costs.csv\"\ntransport = \"zenoh\"\n\
             [[hosts]]\nname = \"alpha\"\nagents = [\"uav1\", 1]\nendpoint = \"tcp/127.0.0.1:7447\"\n\
             [[hosts]]\nname = \"beta\"\nagents = {second}\nendpoint = \"tcp/127.0.0.1:7448\"\n"
        )
    };
    let path = dir.path().join("hosts.toml");
    std::fs::write(&path, hosts("[\"uav4\", \"uav3\"]")).unwrap();
    let read = admm_ta_runtime::team::team_file::Team::read(&path).unwrap();
    assert_eq!(read.file.hosts[0].agents, [0, 1]);
    assert_eq!(read.file.hosts[1].agents, [3, 2]);
    for (second, needle) in [
        (
            "[\"uav4\", \"uav5\"]",
            "host 'beta': no robot is named 'uav5'",
        ),
        ("[\"uav4\", \"uav1\"]", "robot 0 is on two hosts"),
    ] {
        std::fs::write(&path, hosts(second)).unwrap();
        let out = admm_ta()
            .args(["agent", "--team", path.to_str().unwrap(), "--id", "uav1"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains(needle), "{second}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
}

#[test]
fn a_missing_agent_fails_the_team_after_the_deadline_naming_it() {
    let instance = common::oracle_instances()
        .into_iter()
        .find(|i| i.name == "case1_uniform_5x5")
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let run = format!("m{}", std::process::id());
    let team = team_file(dir.path(), &run, 5, &instance.csv, "ring", 1.5);
    let started = std::time::Instant::now();
    let children: Vec<(usize, Child)> = [4, 0, 3, 1]
        .into_iter()
        .map(|id| (id, start(&team, id)))
        .collect();
    let mut messages = String::new();
    for (id, child) in children {
        let out = child.wait_with_output().unwrap();
        assert!(
            !out.status.success(),
            "agent {id} succeeded without agent 2"
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.trim().lines().count(), 1, "agent {id}: {err}");
        messages += &err;
    }
    assert!(started.elapsed() < Duration::from_secs(20), "the team hung");
    assert!(messages.contains("missing: agent(s) [2]"), "{messages}");
    // collect names the robots without results.
    let out = admm_ta()
        .args(["collect", "--team", team.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("left no result"));
    assert!(team_shm_left(&run).is_empty(), "{:?}", team_shm_left(&run));
}

#[test]
fn bad_team_files_are_refused_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    for (text, needle) in [
        (
            "run = \"a_b\"\nrobots = 2\ncosts = \"random\"\ntasks = 2\n",
            "letters, digits and dashes",
        ),
        (
            "run = \"x\"\nrobots = 2\ncosts = \"random\"\n",
            "needs tasks",
        ),
        (
            "run = \"x\"\nrobots = 3\ncosts = \"nope.csv\"\n",
            "nope.csv",
        ),
        (
            "run = \"x\"\nrobots = 2\ncosts = \"random\"\ntasks = 2\ncolour = 1\n",
            "unknown field",
        ),
        (
            "run = \"x\"\nrobots = 2\ncosts = \"random\"\ntasks = 3\n",
            "cannot cover",
        ),
    ]
    .into_iter()
    .map(|(t, n)| (t.to_string(), n))
    .chain(bad_host_tables())
    {
        let text = text.as_str();
        let path = dir.path().join("bad.toml");
        std::fs::write(&path, text).unwrap();
        let out = admm_ta()
            .args(["agent", "--team", path.to_str().unwrap(), "--robot", "0"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(needle),
            "{text}: {err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
    let out = admm_ta()
        .args(["agent", "--team", "/nonexistent/team.toml", "--robot", "0"])
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read team file"));
}

/// Team files whose [[hosts]] cannot describe a team across machines.
fn bad_host_tables() -> Vec<(String, &'static str)> {
    let base = "run = \"x\"\nrobots = 3\ncosts = \"random\"\ntasks = 3\n";
    let host = |name: &str, agents: &str, endpoint: &str| {
        format!("[[hosts]]\nname = \"{name}\"\nagents = {agents}\nendpoint = \"{endpoint}\"\n")
    };
    let a = host("a", "[0, 1]", "tcp/127.0.0.1:7447");
    let b = host("b", "[2]", "tcp/127.0.0.1:7448");
    vec![
        (format!("{base}{a}{b}"), "add transport = \"zenoh\""),
        (format!("{base}transport = \"zenoh\"\n"), "needs [[hosts]]"),
        (
            format!("{base}transport = \"zenoh\"\n{a}"),
            "robot(s) [2] are on no host",
        ),
        (
            format!(
                "{base}transport = \"zenoh\"\n{a}{}",
                host("b", "[2, 1]", "tcp/127.0.0.1:7448")
            ),
            "robot 1 is on two hosts",
        ),
        (
            format!(
                "{base}transport = \"mixed\"\n{a}{}",
                host("b", "[2, 3]", "tcp/127.0.0.1:7448")
            ),
            "lists robot 3",
        ),
        (
            format!(
                "{base}transport = \"zenoh\"\n{a}{}",
                host("b", "[2]", "udp/127.0.0.1:7448")
            ),
            "not a Zenoh TCP endpoint",
        ),
        (
            format!(
                "{base}transport = \"zenoh\"\n{a}{}",
                host("b", "[2]", "tcp/127.0.0.1:7447")
            ),
            "the same endpoint",
        ),
        (
            format!(
                "{base}transport = \"zenoh\"\n{a}{}",
                host("a", "[2]", "tcp/127.0.0.1:7448")
            ),
            "two hosts are called 'a'",
        ),
        (
            format!("{base}transport = \"carrier-pigeon\"\n"),
            "unknown variant",
        ),
        (
            format!("{base}transport = \"threads\"\n"),
            "unknown variant `threads`, expected one of `iceoryx2`, `ipc`, `shm`, `uds`, `zenoh`, `mixed`",
        ),
    ]
}

#[test]
fn host_refuses_what_it_cannot_run() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("team.toml");
    std::fs::write(
        &path,
        "run = \"h\"\nrobots = 2\ncosts = \"random\"\ntasks = 2\ntransport = \"zenoh\"\n[[hosts]]\nname = \"a\"\nagents = [0, 1]\nendpoint = \"tcp/127.0.0.1:7447\"\n",
    )
    .unwrap();
    let out = admm_ta()
        .args(["host", "--team", path.to_str().unwrap(), "--name", "gamma"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    let needle = if cfg!(feature = "zenoh") {
        "no host 'gamma'"
    } else {
        "built without Zenoh support"
    };
    assert!(err.contains(needle), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    if cfg!(feature = "zenoh") {
        assert_eq!(
            out.status.code(),
            Some(2),
            "a host not in the team file: {err}"
        );
    }
}

#[test]
fn an_agent_of_another_team_is_refused_by_name_before_round_0_and_the_team_runs_on() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("d{}", std::process::id());
    let write = |name: &str, extra: &str| {
        let path = dir.path().join(name);
        std::fs::write(
            &path,
            format!("run = \"{run}\"\nrobots = 4\ncosts = \"random\"\ntasks = 4\ntopology = \"ring\"\nresults = \"results\"\nstartup_timeout = 60.0\nround_timeout = 20.0\n{extra}"),
        )
        .unwrap();
        path
    };
    let team = write("team.toml", "seed = 1\n");
    let other_seed = write("seed.toml", "seed = 2\n");
    let other_graph = write("graph.toml", "seed = 1\n");
    let text = std::fs::read_to_string(&other_graph).unwrap();
    std::fs::write(&other_graph, text.replace("\"ring\"", "\"complete\"")).unwrap();
    let members: Vec<(usize, Child)> = [0, 1, 2]
        .into_iter()
        .map(|id| (id, start(&team, id)))
        .collect();
    std::thread::sleep(Duration::from_millis(500));
    for (file, needle) in [
        (&other_seed, "costs and parameters differ"),
        (&other_graph, "): topology"),
    ] {
        let out = start(file, 3).wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{needle}: a wrong agent joined");
        // Refused, not failed: bad input (exit 2), told apart from a fault (exit 4).
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(
            err.contains("agent 3's team file differs from the running team's (digest"),
            "{err}"
        );
        assert!(err.contains(needle), "{needle}: {err}");
    }
    // The right agent 3 completes the team.
    let last = start(&team, 3);
    all_succeed(members.into_iter().chain([(3, last)]));
    assert!(team_shm_left(&run).is_empty(), "{:?}", team_shm_left(&run));
}

/// Runs every agent of `team` (robots `0..n`) to the end; their exit codes.
fn run_team(team: &Path, n: usize) -> Vec<Option<i32>> {
    let children: Vec<Child> = (0..n).map(|id| start(team, id)).collect();
    children
        .into_iter()
        .map(|c| c.wait_with_output().unwrap().status.code())
        .collect()
}

fn collect(team: &Path, extra: &[&str]) -> std::process::Output {
    admm_ta()
        .args(["collect", "--team", team.to_str().unwrap()])
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn a_team_takes_forbidden_pairs_and_profits_and_collect_ends_as_solve_does() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("p{}", std::process::id());
    // Profits; (0, 0), (1, 1) and (3, 3) may not be taken, and robot 2's best is forbidden
    // in the CSV itself (-inf).
    let csv = dir.path().join("profits.csv");
    std::fs::write(&csv, "9,1,2,3\n4,8,1,2\n-inf,3,2,7\n1,2,6,9\n").unwrap();
    let pairs = dir.path().join("pairs.txt");
    std::fs::write(&pairs, "# robot,task\n0,0\n1,1\n3,3\n").unwrap();
    let team = team_file(dir.path(), &run, 4, &csv, "chain", 60.0);
    let text = std::fs::read_to_string(&team).unwrap();
    std::fs::write(
        &team,
        format!("{text}maximize = true\nforbidden = \"pairs.txt\"\n"),
    )
    .unwrap();
    assert_eq!(run_team(&team, 4), vec![Some(0); 4]);
    let out = collect(&team, &["--check", "--json"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let result: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    // The centralized solver on the same input, for reference.
    let reference = admm_ta()
        .args([
            "solve",
            "--method",
            "hungarian",
            "--maximize",
            "--json",
            "--costs",
        ])
        .arg(&csv)
        .arg("--forbidden")
        .arg(&pairs)
        .output()
        .unwrap();
    assert!(reference.status.success());
    let reference: serde_json::Value = serde_json::from_slice(&reference.stdout).unwrap();
    assert_eq!(result["maximize"], true, "{result}");
    assert_eq!(result["certified"], true, "{result}");
    assert_eq!(result["optimal"], true, "{result}");
    assert_eq!(result["cost"], reference["cost"], "{result} vs {reference}");
    let assignment: Vec<usize> = serde_json::from_value(result["assignment"].clone()).unwrap();
    for (robot, task) in [(0, 0), (1, 1), (3, 3), (2, 0)] {
        assert_ne!(
            assignment[robot], task,
            "forbidden pair used: {assignment:?}"
        );
    }
    let text = String::from_utf8_lossy(&collect(&team, &[]).stdout).into_owned();
    assert!(
        text.contains("profit") && text.contains("certified optimal"),
        "{text}"
    );

    // A result copied over another agent's is named as such.
    let results = dir.path().join("results");
    let saved = std::fs::read(results.join("result-0.json")).unwrap();
    std::fs::copy(results.join("result-1.json"), results.join("result-0.json")).unwrap();
    let out = collect(&team, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("is agent 1's result, not agent 0's"), "{err}");
    std::fs::write(results.join("result-0.json"), saved).unwrap();

    // Results of another team in the same directory are refused (bad input, 2).
    let changed = std::fs::read_to_string(&team)
        .unwrap()
        .replace("chain", "ring");
    std::fs::write(&team, changed).unwrap();
    let out = collect(&team, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("is not a result of this team"), "{err}");

    // One round of Algorithm 1 certifies nothing: the agents and collect exit 5 and say so.
    let text = std::fs::read_to_string(&team).unwrap();
    std::fs::write(
        &team,
        format!("{text}max_iters = 1\nprimal_variant = \"paper\"\n"),
    )
    .unwrap();
    assert_eq!(run_team(&team, 4), vec![Some(5); 4]);
    let out = collect(&team, &[]);
    assert_eq!(
        out.status.code(),
        Some(5),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("NOT certified optimal"), "{text}");
    // Whatever one round left (conflicting choices are repaired), no forbidden pair is used.
    let out = collect(&team, &["--json"]);
    let result: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(result["certified"], false, "{result}");
    let assignment: Vec<usize> = serde_json::from_value(result["assignment"].clone()).unwrap();
    for (robot, task) in [(0, 0), (1, 1), (3, 3), (2, 0)] {
        assert_ne!(
            assignment[robot], task,
            "forbidden pair used: {assignment:?}"
        );
    }
    assert!(team_shm_left(&run).is_empty(), "{:?}", team_shm_left(&run));
}

#[test]
fn a_second_copy_of_a_running_agent_is_refused_and_the_team_runs_on() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("dup{}", std::process::id());
    let team = dir.path().join("team.toml");
    std::fs::write(
        &team,
        format!("run = \"{run}\"\nrobots = 4\ncosts = \"random\"\ntasks = 4\ntopology = \"ring\"\nresults = \"results\"\nstartup_timeout = 60.0\nround_timeout = 20.0\n"),
    )
    .unwrap();
    // Agents 0..3 start; 3 is late, so the team waits at start-up.
    let members: Vec<(usize, Child)> = [0, 1, 2]
        .into_iter()
        .map(|id| (id, start(&team, id)))
        .collect();
    std::thread::sleep(Duration::from_millis(500));
    let copy = start(&team, 1).wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&copy.stderr);
    assert_eq!(copy.status.code(), Some(2), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("agent 1 of this team is already running (pid"),
        "{err}"
    );
    let last = start(&team, 3);
    all_succeed(members.into_iter().chain([(3, last)]));
    assert!(team_shm_left(&run).is_empty(), "{:?}", team_shm_left(&run));
}

/// A team file's settings go through the command line's rule: a key the team never reads,
/// or a value no run can take, is refused by `agent`, `collect` and `host` alike, with exit
/// 2 and one line naming the file and the key (not a command-line flag).
#[test]
fn team_file_settings_are_refused_by_the_command_lines_rule_naming_file_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let base = "robots = 3\ncosts = \"random\"\ntasks = 3\n";
    // With Zenoh built, a team across hosts, so that `host` reads the file too.
    let zenoh_hosts = if cfg!(feature = "zenoh") {
        "transport = \"zenoh\"\n[[hosts]]\nname = \"a\"\nagents = [0, 1, 2]\nendpoint = \"tcp/127.0.0.1:7447\"\n"
    } else {
        ""
    };
    for (run, keys, needle) in [
        (
            "k1",
            "method = \"market\"\nadaptive_rho = true\n",
            "adaptive_rho = true does not apply to method = \"market\"",
        ),
        (
            "k2",
            "method = \"cbaa\"\nprimal_variant = \"fast\"\n",
            "primal_variant = \"fast\" does not apply to method = \"cbaa\"",
        ),
        ("k3", "max_iters = 0\n", "max_iters must be at least 1"),
        (
            "k4",
            "adaptive_rho = true\n",
            "adaptive_rho = true applies to the paper's primal variant, not the fast one: add primal_variant = \"paper\"",
        ),
        (
            "k5",
            "round_timeout = -1\n",
            "round_timeout must be a positive",
        ),
        (
            "k6",
            "method = \"hungarian\"\n",
            "method = \"hungarian\" is the centralized solver",
        ),
        // A method's own settings are the file's keys too, checked by the method.
        (
            "k7",
            "method = \"dual\"\ngamma_factor = 0.3\n",
            "gamma_factor = 0.3 does not apply to method = \"dual\": it works with method = \"inexact-dual\"",
        ),
        (
            "k8",
            "primal_variant = \"fancy\"\n",
            "primal_variant must be \"paper\" or \"fast\", got 'fancy'",
        ),
        (
            "k9",
            "method = \"inexact-dual\"\ngamma_factor = -1\n",
            "gamma_factor (the γ factor) must be a positive finite number, got -1",
        ),
        (
            "k10",
            "gamma_factor = [1]\n",
            "gamma_factor must be a number or a name",
        ),
    ] {
        let path = dir.path().join(format!("{run}.toml"));
        std::fs::write(&path, format!("run = \"{run}\"\n{base}{keys}{zenoh_hosts}")).unwrap();
        let team = path.to_str().unwrap();
        let mut commands = vec![
            vec!["agent", "--team", team, "--robot", "0"],
            vec!["collect", "--team", team],
        ];
        if cfg!(feature = "zenoh") {
            commands.push(vec!["host", "--team", team, "--name", "a"]);
        }
        for args in commands {
            let out = admm_ta().args(&args).output().unwrap();
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{args:?} {keys}: {err}");
            assert_eq!(err.trim().lines().count(), 1, "{err}");
            assert!(err.contains(needle), "{args:?} {keys}: {err}");
            assert!(err.contains(&format!("{run}.toml")), "the file: {err}");
            assert!(!err.contains("--"), "a command-line flag: {err}");
        }
    }
}

/// A team file's `timeline`: every agent stamps its rounds and `collect` writes the trace
/// and names the critical path.
#[test]
fn a_team_file_timeline_is_written_by_collect() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("tl{}", std::process::id());
    let instance = common::oracle_instances()
        .into_iter()
        .find(|i| i.name == "case1_uniform_5x5")
        .unwrap();
    let team = team_file(dir.path(), &run, 5, &instance.csv, "ring", 30.0);
    let mut text = std::fs::read_to_string(&team).unwrap();
    text.push_str("timeline = \"trace.json\"\n");
    std::fs::write(&team, text).unwrap();
    let agents: Vec<(usize, Child)> = (0..5).map(|id| (id, start(&team, id))).collect();
    all_converge(agents);
    let result = collect_json(&team, &[]);
    let rounds = result["iterations"].as_u64().unwrap();
    assert_eq!(
        result["critical_path"]["rounds"].as_array().unwrap().len() as u64,
        rounds - 1
    );
    let trace: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("trace.json")).unwrap()).unwrap();
    for agent in 0..5u64 {
        let waits = trace["traceEvents"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|e| e["name"] == "wait" && e["pid"] == agent)
            .count() as u64;
        assert_eq!(waits, rounds, "agent {agent}");
    }
    assert!(team_shm_left(&run).is_empty());
}

/// The shared-slot reference transport and the copying socket baseline run a team file too
/// (the first member creates what the transport needs, the last removes it).
#[test]
fn independently_started_agents_over_shm_and_uds() {
    let instance = common::oracle_instances()
        .into_iter()
        .find(|i| i.name == "case2_uniform_10x2")
        .unwrap();
    let robots = instance.optimal_assignment.len();
    for transport in ["shm", "uds"] {
        let dir = tempfile::tempdir().unwrap();
        let run = format!("t{transport}{}", std::process::id());
        let team = team_file(dir.path(), &run, robots, &instance.csv, "ring", 60.0);
        let text = std::fs::read_to_string(&team).unwrap();
        std::fs::write(&team, format!("{text}transport = \"{transport}\"\n")).unwrap();
        let children = shuffled(robots, 5)
            .into_iter()
            .map(|id| (id, start(&team, id)))
            .collect::<Vec<_>>();
        all_converge(children);
        let result = collect_json(&team, &["--check"]);
        assert_eq!(result["optimal"], true, "{transport}: {result}");
        assert!(team_shm_left(&run).is_empty(), "{:?}", team_shm_left(&run));
    }
}
