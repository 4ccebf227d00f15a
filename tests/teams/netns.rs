//! Teams across hosts with real addresses: four network namespaces on a bridge (`ip netns`,
//! veth pairs; each host its own address, traffic only between them), each running
//! `admm-ta host` and its agents. Zenoh and mixed teams reach the optimum; a link cut mid-run
//! and a host killed mid-run end every host within the round deadline plus 10 s, naming the
//! lost host; nothing is left behind. Skipped, saying why, where the test is not root or
//! `ip` is missing or cannot make namespaces.

#![cfg(feature = "zenoh")]

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

const ADMM_TA: &str = env!("CARGO_BIN_EXE_admm-ta");

fn ip(args: &[&str]) -> Result<(), String> {
    let out = Command::new("ip")
        .args(args)
        .output()
        .map_err(|e| format!("ip {}: {e}", args.join(" ")))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(format!(
            "ip {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

/// Four (or `k`) namespaces on a bridge of the root namespace, removed on drop.
struct NetHosts {
    namespaces: Vec<String>,
    addresses: Vec<String>,
    /// The bridge-side end of each host's veth pair (down: the host's link is cut).
    ports: Vec<String>,
    bridge: String,
}

impl NetHosts {
    /// `None` (and a line saying why) where namespaces cannot be made here.
    fn create(k: usize) -> Option<Self> {
        // SAFETY: geteuid cannot fail.
        if unsafe { libc::geteuid() } != 0 {
            eprintln!("skipped: making network namespaces needs root");
            return None;
        }
        static NEXT: AtomicU32 = AtomicU32::new(0);
        let tag = format!(
            "{}{}",
            std::process::id() % 100_000,
            NEXT.fetch_add(1, Ordering::Relaxed)
        );
        let subnet = (std::process::id() + NEXT.load(Ordering::Relaxed) * 7) % 250 + 1;
        let mut hosts = Self {
            namespaces: Vec::new(),
            addresses: Vec::new(),
            ports: Vec::new(),
            bridge: format!("atb{tag}"),
        };
        match hosts.build(k, &tag, subnet) {
            Ok(()) => Some(hosts),
            Err(e) => {
                eprintln!("skipped: cannot make network namespaces here: {e}");
                None
            }
        }
    }

    fn build(&mut self, k: usize, tag: &str, subnet: u32) -> Result<(), String> {
        ip(&["link", "add", &self.bridge, "type", "bridge"])?;
        ip(&["link", "set", &self.bridge, "up"])?;
        for h in 0..k {
            let ns = format!("at{tag}h{h}");
            ip(&["netns", "add", &ns])?;
            self.namespaces.push(ns.clone());
            let (inner, outer) = (format!("at{tag}i{h}"), format!("at{tag}o{h}"));
            ip(&[
                "link", "add", &inner, "type", "veth", "peer", "name", &outer,
            ])?;
            self.ports.push(outer.clone());
            ip(&["link", "set", &outer, "master", &self.bridge])?;
            ip(&["link", "set", &outer, "up"])?;
            ip(&["link", "set", &inner, "netns", &ns])?;
            let address = format!("10.231.{subnet}.{}", h + 1);
            ip(&[
                "-n",
                &ns,
                "addr",
                "add",
                &format!("{address}/24"),
                "dev",
                &inner,
            ])?;
            ip(&["-n", &ns, "link", "set", &inner, "up"])?;
            ip(&["-n", &ns, "link", "set", "lo", "up"])?;
            self.addresses.push(address);
        }
        Ok(())
    }

    /// `admm-ta ARGS` in host `h`'s namespace.
    fn admm_ta(&self, h: usize, args: &[&str]) -> Command {
        let mut command = Command::new("ip");
        command
            .args(["netns", "exec", &self.namespaces[h], ADMM_TA])
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        command
    }

    /// Cuts host `h` off the bridge.
    fn cut(&self, h: usize) {
        ip(&["link", "set", &self.ports[h], "down"]).unwrap();
    }
}

impl Drop for NetHosts {
    fn drop(&mut self) {
        for ns in &self.namespaces {
            let _ = ip(&["netns", "del", ns]);
        }
        let _ = ip(&["link", "del", &self.bridge]);
    }
}

/// A team of `per_host` agents on each host, in `dir`.
fn team_file(
    dir: &Path,
    net: &NetHosts,
    run: &str,
    transport: &str,
    per_host: usize,
    round_timeout: f64,
) -> PathBuf {
    let n = per_host * net.namespaces.len();
    let path = dir.join("team.toml");
    let mut text = format!(
        "run = \"{run}\"\nrobots = {n}\ncosts = \"random\"\ntasks = {n}\nseed = 11\ntopology = \"random:0.3\"\nresults = \"results\"\nstartup_timeout = 30.0\nround_timeout = {round_timeout:.1}\ntransport = \"{transport}\"\n"
    );
    for (h, address) in net.addresses.iter().enumerate() {
        let agents: Vec<String> = (h * per_host..(h + 1) * per_host)
            .map(|a| a.to_string())
            .collect();
        text += &format!(
            "\n[[hosts]]\nname = \"h{h}\"\nagents = [{}]\nendpoint = \"tcp/{address}:7447\"\n",
            agents.join(", ")
        );
    }
    std::fs::write(&path, text).unwrap();
    path
}

struct Started {
    hosts: Vec<Child>,
    agents: Vec<(usize, Child)>,
}

/// Every host and its agents, in their namespaces (`fault`: ADMM_TA_FAULT for all).
fn start(net: &NetHosts, team: &Path, per_host: usize, fault: Option<&str>) -> Started {
    let team = team.to_str().unwrap();
    let mut started = Started {
        hosts: Vec::new(),
        agents: Vec::new(),
    };
    for h in 0..net.namespaces.len() {
        let name = format!("h{h}");
        let mut host = net.admm_ta(h, &["host", "--team", team, "--name", &name]);
        started.hosts.push(host.spawn().unwrap());
        for id in h * per_host..(h + 1) * per_host {
            let mut agent = net.admm_ta(h, &["agent", "--team", team, "--robot", &id.to_string()]);
            if let Some(fault) = fault {
                agent.env("ADMM_TA_FAULT", fault);
            }
            started.agents.push((id, agent.spawn().unwrap()));
        }
    }
    started
}

fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// The hosts' outputs with when each ended, and the agents' outputs.
type Ended = (Vec<(Output, Instant)>, Vec<(usize, Output)>);

/// Waits for every process but the agents `hanging` (killing all after `limit`, and the
/// hanging ones once the others ended); the hosts' outputs, when each host ended, and the
/// agents' outputs.
fn wait(started: Started, limit: Duration, hanging: &[usize]) -> Ended {
    let until = Instant::now() + limit;
    let mut children: Vec<(Option<usize>, Child)> = started
        .hosts
        .into_iter()
        .map(|c| (None, c))
        .chain(started.agents.into_iter().map(|(id, c)| (Some(id), c)))
        .collect();
    let mut ended: Vec<Option<Instant>> = vec![None; children.len()];
    let awaited = |k: usize, children: &[(Option<usize>, Child)]| {
        children[k].0.is_none_or(|a| !hanging.contains(&a))
    };
    while (0..children.len()).any(|k| ended[k].is_none() && awaited(k, &children))
        && Instant::now() < until
    {
        for (k, (_, child)) in children.iter_mut().enumerate() {
            if ended[k].is_none() && child.try_wait().unwrap().is_some() {
                ended[k] = Some(Instant::now());
            }
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let hung: Vec<String> = children
        .iter()
        .zip(&ended)
        .filter(|((id, _), e)| e.is_none() && id.is_none_or(|a| !hanging.contains(&a)))
        .map(|((id, _), _)| id.map_or("a host".into(), |a| format!("agent {a}")))
        .collect();
    for (_, child) in &mut children {
        let _ = child.kill();
    }
    let mut hosts = Vec::new();
    let mut agents = Vec::new();
    for ((id, child), end) in children.into_iter().zip(ended) {
        let out = child.wait_with_output().unwrap();
        match id {
            None => hosts.push((out, end.unwrap_or_else(Instant::now))),
            Some(a) => agents.push((a, out)),
        }
    }
    assert!(
        hung.is_empty(),
        "still running after {limit:?} (killed): {hung:?}; hosts:\n{}",
        hosts
            .iter()
            .map(|(o, _)| text(o))
            .collect::<Vec<_>>()
            .join("\n")
    );
    (hosts, agents)
}

fn shm_left(run: &str) -> Vec<String> {
    let prefix = format!("adtat{}-{run}", common::euid());
    std::fs::read_dir("/dev/shm")
        .map(|d| {
            d.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.starts_with(&prefix))
                .collect()
        })
        .unwrap_or_default()
}

fn collect(team: &Path) -> (Output, serde_json::Value) {
    let out = Command::new(ADMM_TA)
        .args([
            "collect",
            "--team",
            team.to_str().unwrap(),
            "--check",
            "--json",
        ])
        .output()
        .unwrap();
    let value = serde_json::from_slice(&out.stdout).unwrap_or(serde_json::Value::Null);
    (out, value)
}

#[test]
fn four_namespace_hosts_reach_the_optimum_over_zenoh_and_mixed() {
    let Some(net) = NetHosts::create(4) else {
        return;
    };
    for transport in ["zenoh", "mixed"] {
        let dir = tempfile::tempdir().unwrap();
        let run = format!("n{}{}", &transport[..1], std::process::id());
        let team = team_file(dir.path(), &net, &run, transport, 5, 5.0);
        let started = start(&net, &team, 5, None);
        let (hosts, agents) = wait(started, Duration::from_secs(90), &[]);
        for (out, _) in &hosts {
            assert!(out.status.success(), "{transport}: host: {}", text(out));
        }
        for (id, out) in &agents {
            assert!(
                out.status.success(),
                "{transport}: agent {id}: {}",
                text(out)
            );
        }
        let (out, result) = collect(&team);
        assert!(out.status.success(), "{transport}: {}", text(&out));
        assert_eq!(result["optimal"], true, "{transport}: {result}");
        assert_eq!(result["certified"], true, "{transport}: {result}");
        assert!(
            shm_left(&run).is_empty(),
            "{transport}: {:?}",
            shm_left(&run)
        );
    }
}

/// The round deadline of the teams that lose a host: longer than Zenoh's lease (10 s), so
/// that the loss, not the held agent's silence, is what the hosts find.
const ROUND_TIMEOUT: f64 = 30.0;

/// A team held mid-run (agent 14, of host h3, stops sending after round 2), then h3 is
/// cut off (`kill`: false) or its `admm-ta host` killed (`kill`: true): every host ends
/// within the round deadline plus 10 s, the others naming h3; every agent of the other
/// hosts with exit code 4.
fn lose_a_host_mid_run(transport: &str, kill: bool) {
    let Some(net) = NetHosts::create(4) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let run = format!(
        "c{}{}{}",
        &transport[..1],
        u8::from(kill),
        std::process::id()
    );
    let team = team_file(dir.path(), &net, &run, transport, 4, ROUND_TIMEOUT);
    // Agent 14 (host h3) hangs after round 2: the team waits for it (round deadline 5 s).
    let mut started = start(&net, &team, 4, Some("14:2:hang"));
    std::thread::sleep(Duration::from_secs(3));
    let lost_at = Instant::now();
    if kill {
        started.hosts[3].kill().unwrap();
    } else {
        net.cut(3);
    }
    let (hosts, agents) = wait(started, Duration::from_secs(90), &[14]);
    if std::env::var_os("NETNS_DEBUG").is_some() {
        for (id, out) in &agents {
            eprintln!("agent {id}: {}", text(out));
        }
    }
    for (h, (out, ended)) in hosts.iter().enumerate() {
        let message = text(out);
        let took = ended.duration_since(lost_at);
        if h == 3 {
            if !kill {
                // Cut off, h3's agents time out (the round deadline), and h3 then waits for
                // the held agent, which never leaves, no longer than the round deadline plus
                // 10 s.
                assert!(!out.status.success(), "{transport}: h3: {message}");
                assert!(
                    took <= Duration::from_secs_f64(2.0 * ROUND_TIMEOUT + 15.0),
                    "{transport}: h3 ended {took:?} after the cut: {message}"
                );
            }
            continue;
        }
        assert!(!out.status.success(), "{transport}: h{h}: {message}");
        assert!(
            message.contains("host h3 left the team during the run without a goodbye"),
            "{transport}: h{h}: {message}"
        );
        assert!(
            took <= Duration::from_secs_f64(ROUND_TIMEOUT + 10.0),
            "{transport}: h{h} ended {took:?} after the loss: {message}"
        );
        eprintln!("{transport}, kill {kill}: h{h} ended {took:?} after the loss");
    }
    for (id, out) in agents.iter().filter(|(id, _)| *id < 12) {
        if std::env::var_os("NETNS_DEBUG").is_some() {
            eprintln!("agent {id}: {}", text(out));
        }
        assert_eq!(
            out.status.code(),
            Some(4),
            "{transport}: agent {id}: {}",
            text(out)
        );
    }
    let shm: Vec<String> = shm_left(&run)
        .into_iter()
        .filter(|n| !n.contains("-h3_"))
        .collect();
    assert!(shm.is_empty(), "{transport}: {shm:?}");
    // Host h3's own files (a killed host cannot clean up; the next start of the team would).
    for name in shm_left(&run) {
        let path = Path::new("/dev/shm").join(name);
        let _ = std::fs::remove_dir_all(&path).or_else(|_| std::fs::remove_file(&path));
    }
}

#[test]
fn a_link_cut_mid_run_ends_every_host_naming_the_lost_one() {
    lose_a_host_mid_run("zenoh", false);
    lose_a_host_mid_run("mixed", false);
}

#[test]
fn a_host_killed_mid_run_ends_every_host_naming_it() {
    lose_a_host_mid_run("zenoh", true);
    lose_a_host_mid_run("mixed", true);
}

/// With a round deadline no longer than Zenoh's lease (10 s), an agent that times out
/// waiting for a neighbour does not name it before the network had a lease to say who is
/// gone: the hosts left name the host cut off, not a healthy agent that waited for it.
#[test]
fn a_short_round_deadline_still_names_the_host_cut_off() {
    let Some(net) = NetHosts::create(4) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let run = format!("cs{}", std::process::id());
    let team = team_file(dir.path(), &net, &run, "zenoh", 4, 10.0);
    // Agent 14 (host h3) stops sending after round 2; then h3 is cut off.
    let started = start(&net, &team, 4, Some("14:2:hang"));
    std::thread::sleep(Duration::from_secs(3));
    net.cut(3);
    let (hosts, _) = wait(started, Duration::from_secs(90), &[14]);
    for (h, (out, _)) in hosts.iter().enumerate().take(3) {
        let message = text(out);
        assert!(
            message.contains("host h3 left the team during the run without a goodbye"),
            "h{h}: {message}"
        );
    }
    for name in shm_left(&run) {
        let path = Path::new("/dev/shm").join(name);
        let _ = std::fs::remove_dir_all(&path).or_else(|_| std::fs::remove_file(&path));
    }
}

/// A standing team on four namespace hosts (two robots each, a ring) loses a host to a cut
/// link: the robots of the three others drop its robots (named in `crashed`) and go on,
/// every episode certified and optimal; the robots cut off say so and exit 4.
#[test]
fn a_standing_team_goes_on_without_a_host_cut_off() {
    use crate::private::{Row, Sidecar, optimum};
    use serde_json::Value;
    let Some(net) = NetHosts::create(4) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let run = format!("sc{}", std::process::id());
    let (per_host, m) = (2, 4);
    let n = per_host * 4;
    let path = dir.path().join("team.toml");
    let mut text_of_team = format!(
        "run = \"{run}\"\nrobots = {n}\ncosts = \"private\"\ntasks = {m}\ntopology = \"ring\"\nstartup_timeout = 30.0\nround_timeout = 30.0\nepisode_timeout = 60.0\ntransport = \"zenoh\"\n"
    );
    for (h, address) in net.addresses.iter().enumerate() {
        let agents: Vec<String> = (h * per_host..(h + 1) * per_host)
            .map(|a| a.to_string())
            .collect();
        text_of_team += &format!(
            "\n[[hosts]]\nname = \"h{h}\"\nagents = [{}]\nendpoint = \"tcp/{address}:7447\"\n",
            agents.join(", ")
        );
    }
    std::fs::write(&path, text_of_team).unwrap();
    let team = path.to_str().unwrap();
    let mut hosts: Vec<Child> = (0..4)
        .map(|h| {
            net.admm_ta(h, &["host", "--team", team, "--name", &format!("h{h}")])
                .spawn()
                .unwrap()
        })
        .collect();
    let mut robots: Vec<Sidecar> = (0..n)
        .map(|id| {
            let mut command = Command::new("ip");
            command.args(["netns", "exec", &net.namespaces[id / per_host], ADMM_TA]);
            command.args([
                "agent",
                "--team",
                team,
                "--robot",
                &id.to_string(),
                "--serve",
            ]);
            Sidecar::spawn(command, id)
        })
        .collect();
    let mut value = 0.0;
    let mut row = || -> Row {
        (0..m)
            .map(|_| {
                value = (value * 7.3 + 1.1) % 10.0;
                Some((value * 100.0f64).round() / 100.0)
            })
            .collect()
    };
    let mut check = |robots: &mut [Sidecar], count: usize, what: &str| {
        let rows: Vec<Row> = (0..robots.len()).map(|_| row()).collect();
        for (s, r) in robots.iter_mut().zip(&rows) {
            s.send_row(r);
        }
        let answers: Vec<Value> = robots.iter_mut().take(count).map(Sidecar::next).collect();
        let best = optimum(&rows[..count], false).unwrap();
        for a in &answers {
            assert_eq!(a["certified"], true, "{what}: {a}");
            let total = a["total_cost"].as_f64().unwrap();
            assert!(
                common::relative_gap(total, best) <= 1e-9,
                "{what}: {a}, optimum {best}"
            );
        }
        answers
    };
    for k in 0..2 {
        check(&mut robots, n, &format!("episode {k}"));
    }
    net.cut(3);
    let answers = check(&mut robots, n - per_host, "the episode of the cut");
    assert_eq!(
        answers[0]["crashed"],
        serde_json::json!([6, 7]),
        "{}",
        answers[0]
    );
    for s in &mut robots[n - per_host..] {
        let line = s.next();
        assert_eq!(line["failed"], true, "{line}");
        assert!(
            line["error"].as_str().unwrap().contains("cut off"),
            "{line}"
        );
    }
    let mut cut_off = robots.split_off(n - per_host);
    for k in 0..2 {
        check(&mut robots, n - per_host, &format!("after the cut, {k}"));
    }
    for s in &mut robots {
        s.close();
    }
    for s in robots {
        let (status, stderr) = s.finish();
        assert!(status.success(), "robot: {stderr}");
    }
    for s in cut_off.drain(..) {
        let (status, _) = s.finish();
        assert_eq!(status.code(), Some(4));
    }
    for (h, host) in hosts.iter_mut().enumerate().take(3) {
        let status = common::wait_with_deadline(host, Duration::from_secs(60));
        assert!(status.success(), "h{h}");
    }
    let _ = hosts[3].kill();
    let _ = hosts[3].wait();
}
