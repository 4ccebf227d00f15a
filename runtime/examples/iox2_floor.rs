//! What iceoryx2 0.10 publish/subscribe costs per delivered sample with nothing of admm-ta
//! around it: the floor under the `ipc` transport's rounds (issue 21).
//!
//! ```sh
//! cargo run --release -p admm-ta-runtime --example iox2_floor -- [--agents 10,50,100] \
//!     [--rounds 300] [--warmup 50] [--values 100]
//! ```
//!
//! For each team size `N` it starts `N` processes on a complete graph, each with one
//! publisher (its own service, created by this parent before the children start, with the
//! limits the `ipc` transport uses: one publisher, `N − 1` subscribers, buffer 2, no history)
//! and a subscriber to every other agent's service. A round: loan a sample of `--values` f64,
//! write it, send it; then receive round `r` from every neighbour once, polling the
//! subscribers still missing and yielding the core after a pass without progress (no
//! board, no futex: only iceoryx2). Each child times, with the monotonic clock:
//! * `recv ns/sample`: a `Subscriber::receive` that returned the sample, plus reading one
//!   value and dropping it (returning it to the publisher);
//! * `empty ns/poll`: a `receive` that found nothing;
//! * `send ns/round`: loan, write and send of its own sample (which reclaims returned ones);
//! * `CPU µs/agent-round` and `CPU µs/sample` (`CLOCK_THREAD_CPUTIME_ID` over the measured
//!   rounds, over agent-rounds × `N − 1`: what `bench rounds` prints as CPU per received
//!   sample, so the two are comparable);
//! * `start ms`: from the first spawn until every child has opened its ports (iceoryx2's
//!   port and connection set-up, with the runtime's configuration: services created up
//!   front, no dead-node scans).
//!
//! The parent prints the medians over the agents, and the floor they put under a round: the
//! part of iceoryx2's cost that no waiting strategy removes. Every delivered sample needs a
//! receive and every agent a send, so on `C` cores a round takes at least
//! `(N (N − 1) · recv + N · send) / C` (`recv+send floor`), whatever the wake-ups cost.

use admm_ta_transport::ipc::nodes::run_config;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::*;
use std::io::{BufRead, BufReader, Write};
use std::process::{Child, Command, Stdio};
use std::time::Instant;

type Svc = ipc::Service;

/// Options of one measurement.
#[derive(Debug, Clone)]
struct Options {
    agents: Vec<usize>,
    rounds: u64,
    warmup: u64,
    values: usize,
}

fn parse_options(args: &[String]) -> Result<Options, String> {
    let mut options = Options {
        agents: vec![10, 50, 100],
        rounds: 300,
        warmup: 50,
        values: 100,
    };
    let mut it = args.iter();
    while let Some(flag) = it.next() {
        let value = it.next().ok_or(format!("{flag} needs a value"))?;
        let bad = |e: std::num::ParseIntError| format!("{flag} {value}: {e}");
        match flag.as_str() {
            "--agents" => {
                options.agents = value
                    .split(',')
                    .map(|a| a.parse::<usize>().map_err(bad))
                    .collect::<Result<_, _>>()?;
                if options.agents.iter().any(|&a| !(2..=200).contains(&a)) {
                    return Err("--agents: team sizes from 2 to 200".into());
                }
            }
            "--rounds" => options.rounds = value.parse().map_err(bad)?,
            "--warmup" => options.warmup = value.parse().map_err(bad)?,
            "--values" => options.values = value.parse().map_err(bad)?,
            _ => return Err(format!("unknown option {flag}")),
        }
    }
    if options.rounds == 0 || options.values == 0 {
        return Err("--rounds and --values must be positive".into());
    }
    Ok(options)
}

/// The iceoryx2 configuration of one measurement: the runtime's own (`run_config`: no
/// dead-node scans, small expired-connection buffers), with its prefix and a root on the
/// tmpfs.
fn config(prefix: &str) -> Result<Config, String> {
    let root = std::path::PathBuf::from(format!("/dev/shm/{prefix}root"));
    std::fs::create_dir_all(&root).map_err(|e| format!("{}: {e}", root.display()))?;
    run_config(prefix, &root).map_err(|e| e.to_string())
}

fn service_name(i: usize) -> Result<ServiceName, String> {
    ServiceName::new(&format!("floor/{i}")).map_err(|e| format!("{e:?}"))
}

fn builder(
    node: &Node<Svc>,
    name: &ServiceName,
    agents: usize,
) -> iceoryx2::service::builder::publish_subscribe::Builder<[f64], u64, Svc> {
    node.service_builder(name)
        .publish_subscribe::<[f64]>()
        .user_header::<u64>()
        .max_publishers(1)
        .max_subscribers(agents - 1)
        .max_nodes(agents + 1)
        .subscriber_max_buffer_size(2)
        .subscriber_max_borrowed_samples(2)
        .history_size(0)
        .enable_safe_overflow(false)
}

/// Thread CPU time in nanoseconds.
fn thread_cpu_ns() -> u64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec for the call to fill.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64
}

/// One child's measurement.
#[derive(Debug, Clone, Copy, Default)]
struct ChildReport {
    recv_ns: f64,
    empty_ns: f64,
    send_ns: f64,
    cpu_us_per_round: f64,
    wall_us_per_round: f64,
}

fn child(index: usize, agents: usize, options: &Options, prefix: &str) -> Result<(), String> {
    let node = NodeBuilder::new()
        .config(&config(prefix)?)
        .create::<Svc>()
        .map_err(|e| format!("node: {e:?}"))?;
    let mut subscribers = Vec::with_capacity(agents - 1);
    for j in (0..agents).filter(|&j| j != index) {
        let service = builder(&node, &service_name(j)?, agents)
            .open()
            .map_err(|e| format!("open {j}: {e:?}"))?;
        subscribers.push(
            service
                .subscriber_builder()
                .create()
                .map_err(|e| format!("subscriber {j}: {e:?}"))?,
        );
    }
    let own = builder(&node, &service_name(index)?, agents)
        .open()
        .map_err(|e| format!("open own: {e:?}"))?;
    let publisher = own
        .publisher_builder()
        .initial_max_slice_len(options.values)
        .create()
        .map_err(|e| format!("publisher: {e:?}"))?;
    // Connections: every subscriber of the team exists once all children are ready, so the
    // publisher connects in the first round; the subscribers connect to the publishers that
    // exist now, the rest on their first receive (as in the `ipc` transport's start-up).
    for subscriber in &subscribers {
        let _ = subscriber.update_connections();
    }
    // Ready; wait for the parent's go (every subscriber of the team exists by then).
    println!("ready");
    std::io::stdout().flush().map_err(|e| e.to_string())?;
    let mut go = String::new();
    std::io::stdin()
        .read_line(&mut go)
        .map_err(|e| e.to_string())?;

    let mut pending = vec![true; subscribers.len()];
    let (mut recv_ns, mut recv_n, mut empty_ns, mut empty_n, mut send_ns) =
        (0u64, 0u64, 0u64, 0u64, 0u64);
    let mut checksum = 0.0;
    let (mut cpu0, mut wall0) = (0, Instant::now());
    for round in 0..options.warmup + options.rounds {
        if round == options.warmup {
            (recv_ns, recv_n, empty_ns, empty_n, send_ns) = (0, 0, 0, 0, 0);
            cpu0 = thread_cpu_ns();
            wall0 = Instant::now();
        }
        let t = Instant::now();
        let mut sample = publisher
            .loan_slice_uninit(options.values)
            .map_err(|e| format!("loan: {e:?}"))?;
        *sample.user_header_mut() = round;
        let sample = sample.write_from_fn(|k| (round as usize + k) as f64);
        sample.send().map_err(|e| format!("send: {e:?}"))?;
        send_ns += t.elapsed().as_nanos() as u64;

        pending.fill(true);
        let mut missing = subscribers.len();
        while missing > 0 {
            let mut progress = false;
            for (k, subscriber) in subscribers.iter().enumerate() {
                if !pending[k] {
                    continue;
                }
                let t = Instant::now();
                let got = subscriber
                    .receive()
                    .map_err(|e| format!("receive: {e:?}"))?;
                match got {
                    Some(sample) => {
                        if *sample.user_header() != round {
                            return Err(format!(
                                "neighbour sent round {} during round {round}",
                                sample.user_header()
                            ));
                        }
                        checksum += sample.payload()[0];
                        drop(sample);
                        recv_ns += t.elapsed().as_nanos() as u64;
                        recv_n += 1;
                        pending[k] = false;
                        missing -= 1;
                        progress = true;
                    }
                    None => {
                        empty_ns += t.elapsed().as_nanos() as u64;
                        empty_n += 1;
                    }
                }
            }
            if !progress {
                std::thread::yield_now();
            }
        }
    }
    let rounds = options.rounds as f64;
    let report = ChildReport {
        recv_ns: recv_ns as f64 / recv_n.max(1) as f64,
        empty_ns: empty_ns as f64 / empty_n.max(1) as f64,
        send_ns: send_ns as f64 / rounds,
        cpu_us_per_round: (thread_cpu_ns() - cpu0) as f64 / 1e3 / rounds,
        wall_us_per_round: wall0.elapsed().as_secs_f64() * 1e6 / rounds,
    };
    println!(
        "{} {} {} {} {} {checksum}",
        report.recv_ns,
        report.empty_ns,
        report.send_ns,
        report.cpu_us_per_round,
        report.wall_us_per_round
    );
    Ok(())
}

fn parse_report(line: &str) -> Result<ChildReport, String> {
    let v: Vec<f64> = line
        .split_whitespace()
        .map(|x| x.parse::<f64>().map_err(|e| format!("{line:?}: {e}")))
        .collect::<Result<_, _>>()?;
    if v.len() < 5 {
        return Err(format!("short report {line:?}"));
    }
    Ok(ChildReport {
        recv_ns: v[0],
        empty_ns: v[1],
        send_ns: v[2],
        cpu_us_per_round: v[3],
        wall_us_per_round: v[4],
    })
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Kills and reaps every child still running (on an error).
fn reap(children: &mut [Child]) {
    for c in children.iter_mut() {
        let _ = c.kill();
        let _ = c.wait();
    }
}

fn measure(agents: usize, options: &Options) -> Result<(), String> {
    let prefix = format!("iox2floor{}n{agents}_", std::process::id());
    let node = NodeBuilder::new()
        .config(&config(&prefix)?)
        .create::<Svc>()
        .map_err(|e| format!("node: {e:?}"))?;
    let services = (0..agents)
        .map(|i| {
            builder(&node, &service_name(i)?, agents)
                .create()
                .map_err(|e| format!("create {i}: {e:?}"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let started = Instant::now();
    let mut children = Vec::with_capacity(agents);
    for i in 0..agents {
        let spawned = Command::new(&exe)
            .args([
                "--child",
                &i.to_string(),
                &agents.to_string(),
                &prefix,
                "--rounds",
                &options.rounds.to_string(),
                "--warmup",
                &options.warmup.to_string(),
                "--values",
                &options.values.to_string(),
            ])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn();
        match spawned {
            Ok(c) => children.push(c),
            Err(e) => {
                reap(&mut children);
                return Err(format!("spawn: {e}"));
            }
        }
    }
    let mut outputs = Vec::with_capacity(agents);
    for c in children.iter_mut() {
        let mut out = BufReader::new(c.stdout.take().expect("piped stdout"));
        let mut line = String::new();
        if out.read_line(&mut line).map_err(|e| e.to_string())? == 0 || line.trim() != "ready" {
            reap(&mut children);
            return Err(format!("a child did not get ready: {line:?}"));
        }
        outputs.push(out);
    }
    let startup = started.elapsed();
    for c in children.iter_mut() {
        let stdin = c.stdin.as_mut().expect("piped stdin");
        if let Err(e) = stdin.write_all(b"go\n").and_then(|_| stdin.flush()) {
            reap(&mut children);
            return Err(e.to_string());
        }
    }
    let mut reports = Vec::with_capacity(agents);
    for out in outputs.iter_mut() {
        let mut line = String::new();
        out.read_line(&mut line).map_err(|e| e.to_string())?;
        match parse_report(&line) {
            Ok(r) => reports.push(r),
            Err(e) => {
                reap(&mut children);
                return Err(e);
            }
        }
    }
    for c in children.iter_mut() {
        let status = c.wait().map_err(|e| e.to_string())?;
        if !status.success() {
            return Err(format!("a child exited with {status}"));
        }
    }
    drop(services);
    drop(node);
    remove_leftovers(&prefix);
    let pick = |f: fn(&ChildReport) -> f64| median(reports.iter().map(f).collect());
    let cpu = pick(|r| r.cpu_us_per_round);
    let (recv, send) = (pick(|r| r.recv_ns), pick(|r| r.send_ns));
    let cores = available_cores() as f64;
    let floor = ((agents * (agents - 1)) as f64 * recv + agents as f64 * send) / 1e3 / cores;
    println!(
        "{agents:>6} {:>10.1} {:>10.1} {:>10.1} {:>13.1} {:>14.2} {:>10.0} {:>17.0} {:>9.0}",
        recv,
        pick(|r| r.empty_ns),
        send,
        cpu,
        cpu / (agents - 1) as f64,
        pick(|r| r.wall_us_per_round),
        floor,
        startup.as_secs_f64() * 1e3,
    );
    Ok(())
}

/// Removes what iceoryx2 leaves of the measurement in `/dev/shm` (its root directory and the
/// nodes' management objects).
fn remove_leftovers(prefix: &str) {
    let _ = std::fs::remove_dir_all(format!("/dev/shm/{prefix}root"));
    if let Ok(entries) = std::fs::read_dir("/dev/shm") {
        for entry in entries.flatten() {
            if entry.file_name().to_string_lossy().starts_with(prefix) {
                let _ = std::fs::remove_file(entry.path());
            }
        }
    }
}

fn available_cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

fn main() {
    // iceoryx2 warns once that no config file was loaded: this example configures it in code.
    set_log_level(LogLevel::Error);
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = if args.first().map(String::as_str) == Some("--child") {
        let index = args.get(1).and_then(|a| a.parse().ok());
        let agents = args.get(2).and_then(|a| a.parse().ok());
        match (
            index,
            agents,
            args.get(3),
            parse_options(args.get(4..).unwrap_or(&[])),
        ) {
            (Some(i), Some(n), Some(prefix), Ok(options)) => child(i, n, &options, prefix),
            _ => Err(format!("bad child arguments {args:?}")),
        }
    } else {
        parse_options(&args).and_then(|options| {
            println!(
                "iceoryx2 alone, complete graph, {} f64 per sample, {} rounds after {}, {} cores; medians over the agents",
                options.values, options.rounds, options.warmup, available_cores()
            );
            println!(
                "{:>6} {:>10} {:>10} {:>10} {:>13} {:>14} {:>10} {:>17} {:>9}",
                "agents", "recv ns", "empty ns", "send ns", "CPU µs/round", "CPU µs/sample",
                "wall µs", "recv+send floor µs", "start ms"
            );
            options.agents.iter().try_for_each(|&n| measure(n, &options))
        })
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
