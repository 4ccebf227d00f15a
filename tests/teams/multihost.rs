//! Teams across machines, on one machine: every "host" is its own process group (its
//! `admm-ta host` and its agents, started as independent commands) and the hosts talk Zenoh
//! over 127.0.0.1 only. Two hosts × five agents reach the oracle's optimum with exactly the
//! iterates of the lockstep simulation, in both multi-host modes (every agent on Zenoh, and
//! iceoryx2 on each host with a bridge between hosts); an agent that crashes on one host
//! stops the whole team, on both hosts, with errors naming it; a host killed without a
//! goodbye is named by the others, which stop their agents at once; a host or agent whose
//! team file differs from the running team's is refused by name before round 0.

#![cfg(feature = "zenoh")]

use crate::common;

use admm_ta_runtime::solve::report::SolveReport;
use admm_ta_runtime::solve::solve;
use admm_ta_runtime::team::team_file::Team;
use admm_ta_transport::Transport;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn admm_ta() -> Command {
    Command::new(env!("CARGO_BIN_EXE_admm-ta"))
}

/// Writes a team of the 10×10 oracle-style instance over two hosts of five robots.
fn team_file(dir: &Path, run: &str, transport: &str, costs: &Path, topology: &str) -> PathBuf {
    let path = dir.join("team.toml");
    let mut text = format!(
        "run = \"{run}\"\nrobots = 10\ncosts = \"{}\"\ntopology = \"{topology}\"\nseed = 4\nresults = \"results\"\nstartup_timeout = 30.0\nround_timeout = 5.0\ntransport = \"{transport}\"\ntimeline = \"trace.json\"\n",
        costs.display()
    );
    for (name, agents) in [("alpha", "[0, 1, 2, 3, 4]"), ("beta", "[5, 6, 7, 8, 9]")] {
        text += &format!(
            "\n[[hosts]]\nname = \"{name}\"\nagents = {agents}\nendpoint = \"tcp/127.0.0.1:{}\"\n",
            common::loopback_port()
        );
    }
    std::fs::write(&path, text).unwrap();
    path
}

/// Ten rows of the 20×20 oracle instance's first ten columns: a fixed 10×10 problem.
fn costs_10x10(dir: &Path) -> PathBuf {
    let instance = common::oracle_instances()
        .into_iter()
        .find(|i| i.name == "case1_uniform_20x20")
        .unwrap();
    let text = std::fs::read_to_string(&instance.csv).unwrap();
    let rows: Vec<String> = text
        .lines()
        .take(10)
        .map(|l| l.split(',').take(10).collect::<Vec<_>>().join(","))
        .collect();
    let path = dir.join("costs.csv");
    std::fs::write(&path, rows.join("\n") + "\n").unwrap();
    path
}

/// One host: its `admm-ta host` leads a new process group, and its agents join it.
struct HostGroup {
    host: Child,
    agents: Vec<(usize, Child)>,
}

fn start_host(team: &Path, name: &str, agents: &[usize], env: &[(&str, &str)]) -> HostGroup {
    let host = admm_ta()
        .args(["host", "--team", team.to_str().unwrap(), "--name", name])
        .envs(env.iter().copied())
        .process_group(0)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let group = host.id() as i32;
    let agents = agents
        .iter()
        .map(|&id| {
            let child = admm_ta()
                .args([
                    "agent",
                    "--team",
                    team.to_str().unwrap(),
                    "--robot",
                    &id.to_string(),
                ])
                .envs(env.iter().copied())
                .process_group(group)
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap();
            (id, child)
        })
        .collect();
    HostGroup { host, agents }
}

/// Waits for every process of the groups, killing them all (and failing) after `limit`.
fn wait_all(groups: Vec<HostGroup>, limit: Duration) -> (Vec<Output>, Vec<(usize, Output)>) {
    let started = Instant::now();
    let pgids: Vec<i32> = groups.iter().map(|g| g.host.id() as i32).collect();
    let watchdog = std::thread::spawn(move || {
        while started.elapsed() < limit {
            std::thread::sleep(Duration::from_millis(50));
            if pgids
                .iter()
                // SAFETY: signal 0 only asks whether the group still has a process.
                .all(|&g| unsafe { libc::kill(-g, 0) } != 0)
            {
                return false;
            }
        }
        for g in pgids {
            // SAFETY: killing the process groups this test made.
            unsafe { libc::kill(-g, libc::SIGKILL) };
        }
        true
    });
    let mut hosts = Vec::new();
    let mut agents = Vec::new();
    for g in groups {
        for (id, child) in g.agents {
            agents.push((id, child.wait_with_output().unwrap()));
        }
        hosts.push(g.host.wait_with_output().unwrap());
    }
    if watchdog.join().unwrap() {
        let outputs: Vec<String> = hosts
            .iter()
            .map(text)
            .chain(
                agents
                    .iter()
                    .map(|(id, o)| format!("agent {id}: {}", text(o))),
            )
            .collect();
        panic!(
            "the team hung: killed after {limit:?}; output:\n{}",
            outputs.join("\n")
        );
    }
    (hosts, agents)
}

fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// The lockstep simulation of the team's problem with the team's settings.
fn sim_report(team: &Path) -> SolveReport {
    let team = Team::read(team).unwrap();
    let (problem, graph) = team.problem_and_graph().unwrap();
    let config = team
        .solve_options()
        .unwrap()
        .to_builder()
        // The same settings on the simulation, which reads no timeouts: not refused.
        .refuse_unread(false)
        .transport(Transport::Sim)
        .build()
        .unwrap();
    solve(&problem, &graph, &config).unwrap()
}

fn shm_left(prefix: &str) -> Vec<String> {
    std::fs::read_dir("/dev/shm")
        .map(|d| {
            d.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.starts_with(prefix))
                .collect()
        })
        .unwrap_or_default()
}

fn two_hosts_reach_the_optimum_with_the_iterates_of_sim(transport: &str, run: &str) {
    let dir = tempfile::tempdir().unwrap();
    let costs = costs_10x10(dir.path());
    let topology = "random:0.4";
    let team = team_file(dir.path(), run, transport, &costs, topology);
    let groups = vec![
        start_host(&team, "alpha", &[0, 1, 2, 3, 4], &[]),
        start_host(&team, "beta", &[5, 6, 7, 8, 9], &[]),
    ];
    let (hosts, agents) = wait_all(groups, Duration::from_secs(90));
    let all = || {
        hosts
            .iter()
            .map(text)
            .chain(
                agents
                    .iter()
                    .map(|(id, o)| format!("agent {id}: {}", text(o))),
            )
            .collect::<Vec<_>>()
            .join("\n")
    };
    for out in &hosts {
        assert!(out.status.success(), "host: {}\nall:\n{}", text(out), all());
    }
    for (id, out) in &agents {
        assert!(
            out.status.success(),
            "agent {id}: {}\nall:\n{}",
            text(out),
            all()
        );
    }
    let reports: Vec<serde_json::Value> = hosts
        .iter()
        .map(|o| serde_json::from_slice(&o.stdout).unwrap())
        .collect();
    for r in &reports {
        assert_eq!(r["agents_seen"], 10, "{r}");
        let forwarded = r["forwarded_out"].as_u64().unwrap();
        // Only the mixed mode's bridge forwards; it carries the cross-host messages.
        assert_eq!(forwarded > 0, transport == "mixed", "{r}");
    }
    let out = admm_ta()
        .args([
            "collect",
            "--team",
            team.to_str().unwrap(),
            "--check",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out));
    let result: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(result["optimal"], true, "{result}");
    // One machine, one clock: the offset estimated from the round messages must bracket 0.
    let clocks = result["host_clocks"].as_array().expect("host clocks");
    assert_eq!(clocks.len(), 2, "{result}");
    assert_eq!(clocks[0]["host"], "alpha");
    assert_eq!(clocks[0]["offset_ns"], 0);
    let beta = &clocks[1];
    assert_eq!(beta["estimated"], true, "{beta}");
    assert_eq!(beta["consistent"], true, "{beta}");
    let (offset, uncertainty) = (
        beta["offset_ns"].as_i64().unwrap(),
        beta["uncertainty_ns"].as_u64().unwrap(),
    );
    assert!(offset.unsigned_abs() <= uncertainty, "{beta}");
    assert!(uncertainty < 50_000_000, "{beta}");
    let trace: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("trace.json")).unwrap()).unwrap();
    assert!(
        trace["otherData"]["clock"]
            .as_str()
            .unwrap()
            .contains("beta"),
        "{}",
        trace["otherData"]
    );
    assert!(
        result["critical_path"]["by_agent"]
            .as_array()
            .unwrap()
            .len()
            == 10
    );
    let sim = sim_report(&team);
    assert_eq!(result["assignment"], serde_json::json!(sim.assignment));
    assert_eq!(result["iterations"], sim.iterations as u64);
    assert_eq!(
        result["certified_round"],
        serde_json::json!(sim.certified_round)
    );
    // Bit for bit: every agent's last payload hashes as in the simulation.
    for id in 0..10 {
        let path = dir.path().join(format!("results/result-{id}.json"));
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        assert_eq!(
            report["outcome"]["iterate_digest"], sim.iterate_digests[id],
            "agent {id}"
        );
    }
    for host in ["alpha", "beta"] {
        let left = shm_left(&format!("adtat{}-{run}-{host}_", common::euid()));
        assert!(left.is_empty(), "{left:?}");
    }
}

#[test]
fn a_two_host_zenoh_team_reaches_the_optimum_with_the_iterates_of_sim() {
    two_hosts_reach_the_optimum_with_the_iterates_of_sim(
        "zenoh",
        &format!("z{}", std::process::id()),
    );
}

#[test]
fn a_two_host_mixed_team_reaches_the_optimum_with_the_iterates_of_sim() {
    two_hosts_reach_the_optimum_with_the_iterates_of_sim(
        "mixed",
        &format!("x{}", std::process::id()),
    );
}

#[test]
fn an_agent_crashing_on_one_host_stops_both_hosts_naming_it() {
    for transport in ["zenoh", "mixed"] {
        let dir = tempfile::tempdir().unwrap();
        let costs = costs_10x10(dir.path());
        let run = format!("c{}{}", &transport[..1], std::process::id());
        let team = team_file(dir.path(), &run, transport, &costs, "ring");
        // Agent 7 (on beta) exits without any cleanup before publishing round 4.
        let fault = [("ADMM_TA_FAULT", "7:3:exit")];
        let started = Instant::now();
        let groups = vec![
            start_host(&team, "alpha", &[0, 1, 2, 3, 4], &fault),
            start_host(&team, "beta", &[5, 6, 7, 8, 9], &fault),
        ];
        let (hosts, agents) = wait_all(groups, Duration::from_secs(60));
        for (id, out) in &agents {
            assert!(!out.status.success(), "{transport}: agent {id} succeeded");
            if *id != 7 {
                let message = text(out);
                assert!(
                    message.contains("agent 7"),
                    "{transport}: agent {id}: {message}"
                );
                // A failure of the team, not bad input: exit 4.
                assert_eq!(
                    out.status.code(),
                    Some(4),
                    "{transport}: agent {id}: {message}"
                );
            }
        }
        for out in &hosts {
            assert!(!out.status.success(), "{transport}: a host succeeded");
            assert!(text(out).contains("agent 7 failed"), "{}", text(out));
        }
        // Far below the 5 s round deadline times the ring's rounds: detected, not timed out.
        assert!(
            started.elapsed() < Duration::from_secs(20),
            "{transport}: {:?}",
            started.elapsed()
        );
        for host in ["alpha", "beta"] {
            let left = shm_left(&format!("adtat{}-{run}-{host}_", common::euid()));
            assert!(left.is_empty(), "{transport}: {left:?}");
        }
    }
}

#[test]
fn a_host_killed_without_a_goodbye_is_named_and_the_team_stops() {
    for transport in ["zenoh", "mixed"] {
        let dir = tempfile::tempdir().unwrap();
        let costs = costs_10x10(dir.path());
        let run = format!("l{}{}", &transport[..1], std::process::id());
        let team = team_file(dir.path(), &run, transport, &costs, "ring");
        let beta_port: u16 = Team::read(&team).unwrap().file.hosts[1]
            .endpoint
            .rsplit(':')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let alpha = start_host(&team, "alpha", &[0, 1, 2, 3, 4], &[]);
        let mut beta = start_host(&team, "beta", &[], &[]);
        // Beta's router is up (its token follows within a moment); then beta dies, its agents
        // never started: alpha's agents wait for them, and must not wait out the start-up
        // deadline (30 s) or blame one of their own.
        let up = Instant::now();
        while std::net::TcpStream::connect(("127.0.0.1", beta_port)).is_err() {
            assert!(
                up.elapsed() < Duration::from_secs(30),
                "beta never listened"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        std::thread::sleep(Duration::from_secs(1));
        beta.host.kill().unwrap();
        let killed = Instant::now();
        let _ = beta.host.wait();
        let (hosts, agents) = wait_all(vec![alpha], Duration::from_secs(60));
        let took = killed.elapsed();
        let host = text(&hosts[0]);
        assert!(!hosts[0].status.success(), "{transport}: {host}");
        assert!(
            host.contains("host beta left the team during the run without a goodbye"),
            "{transport}: {host}"
        );
        for (id, out) in &agents {
            let message = text(out);
            assert_eq!(
                out.status.code(),
                Some(4),
                "{transport}: agent {id}: {message}"
            );
            assert!(
                (5..10).any(|b| message.contains(&format!("agent {b} failed"))),
                "{transport}: agent {id} blamed an agent of its own host: {message}"
            );
        }
        assert!(took < Duration::from_secs(20), "{transport}: {took:?}");
        let left = shm_left(&format!("adtat{}-{run}-alpha_", common::euid()));
        assert!(left.is_empty(), "{transport}: {left:?}");
        // A killed host cannot clean up: the next start of its team on that machine does
        // (the first member sweeps a team's stale files); this test removes them itself.
        for name in shm_left(&format!("adtat{}-{run}-beta_", common::euid())) {
            let path = Path::new("/dev/shm").join(name);
            let _ = std::fs::remove_dir_all(&path).or_else(|_| std::fs::remove_file(&path));
        }
    }
}

#[test]
fn bench_rounds_measures_zenoh_next_to_iceoryx2_and_threads() {
    let dir = tempfile::tempdir().unwrap();
    let out = admm_ta()
        .args([
            "bench",
            "rounds",
            "--agents",
            "4",
            "--transports",
            "threads,ipc,zenoh",
            "--rounds",
            "40",
            "--warmup",
            "10",
            "--out",
            dir.path().to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out));
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(table.contains("| zenoh |"), "{table}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("rounds.json")).unwrap())
            .unwrap();
    assert!(v["failures"].as_array().unwrap().is_empty(), "{v}");
    let zenoh = v["results"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["transport"] == "zenoh")
        .expect("a zenoh case");
    assert_eq!(zenoh["recorded"], 4 * 40);
    assert!(zenoh["round_us"]["p50"].as_f64().unwrap() > 0.0);
    // The ratio column is filled for the zenoh case's ipc twin.
    let ratios = table
        .lines()
        .find(|l| l.starts_with("| 4 | complete |") && l.matches('×').count() >= 3)
        .unwrap_or_else(|| panic!("no ratio row with zenoh / ipc:\n{table}"));
    assert!(!ratios.ends_with("| - | - |"), "{ratios}");
}

/// The team file at `team` with another seed (same run, hosts and endpoints).
fn rogue_of(team: &Path) -> PathBuf {
    let text = std::fs::read_to_string(team).unwrap();
    let rogue = team.with_file_name("rogue.toml");
    std::fs::write(&rogue, text.replace("seed = 4", "seed = 5")).unwrap();
    rogue
}

/// Waits for `child` (a process that should be refused quickly), killing it after `limit`.
fn refused(mut child: Child, limit: Duration) -> (Output, Duration) {
    let started = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if started.elapsed() > limit {
            let _ = child.kill();
            let out = child.wait_with_output().unwrap();
            panic!("not refused within {limit:?}: {}", text(&out));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    (child.wait_with_output().unwrap(), started.elapsed())
}

/// The only line of a refused process's error output.
fn refusal(out: &Output) -> String {
    assert!(!out.status.success(), "it ran: {}", text(out));
    let err = String::from_utf8_lossy(&out.stderr).trim().to_string();
    assert_eq!(err.lines().count(), 1, "{}", text(out));
    err
}

fn agent_of(team: &Path, id: usize, group: i32) -> Child {
    admm_ta()
        .args([
            "agent",
            "--team",
            team.to_str().unwrap(),
            "--robot",
            &id.to_string(),
        ])
        .process_group(group)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Every host and agent of the team succeeded.
fn all_succeeded(what: &str, hosts: &[Output], agents: &[(usize, Output)]) {
    for out in hosts {
        assert!(out.status.success(), "{what}: host: {}", text(out));
    }
    for (id, out) in agents {
        assert!(out.status.success(), "{what}: agent {id}: {}", text(out));
    }
}

#[test]
fn a_host_or_agent_whose_team_file_differs_is_refused_by_name_and_the_team_runs_on() {
    for transport in ["zenoh", "mixed"] {
        let dir = tempfile::tempdir().unwrap();
        let costs = costs_10x10(dir.path());
        let run = format!("d{}{}", &transport[..1], std::process::id());
        let team = team_file(dir.path(), &run, transport, &costs, "ring");
        let rogue = rogue_of(&team);
        let alpha = start_host(&team, "alpha", &[0, 1, 2, 3, 4], &[]);
        // The running team is the host that started first.
        std::thread::sleep(Duration::from_millis(1500));
        let HostGroup { host: beta, .. } = start_host(&rogue, "beta", &[], &[]);
        let (out, took) = refused(beta, Duration::from_secs(25));
        let err = refusal(&out);
        assert!(
            err.contains("host beta's team file differs from the running team's (digest"),
            "{transport}: {err}"
        );
        assert!(err.contains("parameters differ"), "{transport}: {err}");
        assert_eq!(
            out.status.code(),
            Some(2),
            "{transport}: refused, not failed: {err}"
        );
        eprintln!("{transport}: host beta refused in {took:?}");
        // The right beta completes the team, as on an ipc board.
        let beta = start_host(&team, "beta", &[5, 6, 7, 8, 9], &[]);
        let (hosts, agents) = wait_all(vec![alpha, beta], Duration::from_secs(90));
        all_succeeded(transport, &hosts, &agents);
        for host in ["alpha", "beta"] {
            let left = shm_left(&format!("adtat{}-{run}-{host}_", common::euid()));
            assert!(left.is_empty(), "{transport}: {left:?}");
        }
    }
    // A Zenoh agent of another team: refused once every host is up, before its token.
    let dir = tempfile::tempdir().unwrap();
    let costs = costs_10x10(dir.path());
    let run = format!("da{}", std::process::id());
    let team = team_file(dir.path(), &run, "zenoh", &costs, "ring");
    let rogue = rogue_of(&team);
    let alpha = start_host(&team, "alpha", &[0, 1, 2, 3, 4], &[]);
    let mut beta = start_host(&team, "beta", &[5, 6, 7, 8], &[]);
    let group = beta.host.id() as i32;
    let (out, took) = refused(agent_of(&rogue, 9, group), Duration::from_secs(25));
    let err = refusal(&out);
    assert!(
        err.contains("agent 9's team file differs from the running team's (digest"),
        "{err}"
    );
    assert_eq!(out.status.code(), Some(2), "refused, not failed: {err}");
    assert!(err.contains("parameters differ"), "{err}");
    eprintln!(
        "zenoh: agent 9 refused in {took:?} (exit {:?})",
        out.status.code()
    );
    beta.agents.push((9, agent_of(&team, 9, group)));
    let (hosts, agents) = wait_all(vec![alpha, beta], Duration::from_secs(90));
    all_succeeded("zenoh agent", &hosts, &agents);
}
