//! Shared helpers of the end-to-end tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// The oracle instances with their known optima (`tests/fixtures/oracle`, see its README).
pub fn oracle_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/oracle")
}

/// One oracle instance with its expected optimum.
pub struct OracleInstance {
    pub name: String,
    pub csv: PathBuf,
    pub case: u8,
    pub optimal_cost: f64,
    pub lp_optimal_cost: f64,
    pub optimal_assignment: Vec<usize>,
    pub unique: Option<bool>,
}

pub fn oracle_instances() -> Vec<OracleInstance> {
    let dir = oracle_dir();
    let text = std::fs::read_to_string(dir.join("expected.json"))
        .expect("tests/fixtures/oracle/expected.json is part of the repository");
    let expected: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut instances: Vec<OracleInstance> = expected
        .as_object()
        .unwrap()
        .iter()
        .map(|(name, v)| OracleInstance {
            name: name.clone(),
            csv: dir.join(format!("{name}.csv")),
            case: v["case"].as_u64().unwrap() as u8,
            optimal_cost: v["optimal_cost"].as_f64().unwrap(),
            lp_optimal_cost: v["lp_optimal_cost"].as_f64().unwrap(),
            optimal_assignment: v["optimal_assignment"]
                .as_array()
                .unwrap()
                .iter()
                .map(|t| t.as_u64().unwrap() as usize)
                .collect(),
            unique: v.get("unique").and_then(|u| u.as_bool()),
        })
        .collect();
    instances.sort_by(|a, b| a.name.cmp(&b.name));
    assert!(
        instances.len() >= 5,
        "expected the oracle instances of tests/fixtures/oracle"
    );
    instances
}

pub fn relative_gap(cost: f64, optimum: f64) -> f64 {
    (cost - optimum).abs() / optimum.abs().max(1e-12)
}

/// Files a multi-process run of launcher `pid` may leave behind: shared memory with its
/// prefix (`adta<pid in hex>…`) and its run directory (`<runs>/<pid in hex>…` in the user's
/// private runs directory).
pub fn leftovers_of(pid: u32) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for (dir, start) in [
        (PathBuf::from("/dev/shm"), format!("adta{pid:x}")),
        (
            admm_ta::runtime::process::namespace::runs_dir(),
            format!("{pid:x}"),
        ),
    ] {
        if let Ok(entries) = std::fs::read_dir(dir) {
            found.extend(
                entries
                    .flatten()
                    .filter(|e| e.file_name().to_string_lossy().starts_with(&start))
                    .map(|e| e.path()),
            );
        }
    }
    found
}

/// Child processes of `parent` and their command lines.
pub fn children_of(parent: u32) -> Vec<(u32, String)> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir("/proc").unwrap().flatten() {
        let Ok(pid) = entry.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        let Ok(stat) = std::fs::read_to_string(format!("/proc/{pid}/stat")) else {
            continue;
        };
        // The parent pid is the second field after the parenthesised command name.
        let after = &stat[stat.rfind(')').unwrap_or(0) + 1..];
        let ppid: u32 = after
            .split_whitespace()
            .nth(1)
            .and_then(|p| p.parse().ok())
            .unwrap_or(0);
        if ppid == parent {
            let cmdline = std::fs::read(format!("/proc/{pid}/cmdline")).unwrap_or_default();
            found.push((pid, String::from_utf8_lossy(&cmdline).replace('\0', " ")));
        }
    }
    found
}

/// Waits for `child` with a deadline (a test must never hang); kills it and panics after.
pub fn wait_with_deadline(
    child: &mut std::process::Child,
    limit: std::time::Duration,
) -> std::process::ExitStatus {
    let started = std::time::Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status;
        }
        if started.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("the process did not exit within {limit:?}");
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
}

/// `admm_ta::solve` of `problem` by `method` on a complete graph, with the centralized check.
pub fn solve_checked(
    problem: &admm_ta::TaskAssignmentProblem,
    method: admm_ta::Method,
) -> Result<admm_ta::SolveReport, admm_ta::SolveError> {
    let graph = admm_ta::generate::complete(problem.robots()).unwrap();
    let options = admm_ta::SolveOptions::builder()
        .method(method)
        .check(true)
        .build()
        .unwrap();
    admm_ta::solve(problem, &graph, &options)
}

/// A loopback TCP port for a team file's host endpoint that nothing else will take before
/// the host binds it. Ports from `bind(":0")` come from the kernel's ephemeral range, which
/// the agents' own outgoing connections (and every other test's listeners) draw from too,
/// so such a port can be taken again between the test releasing it and the host binding it.
/// These ports lie below the ephemeral range, advance by a per-process counter (no two tests
/// of one binary share one) from a base that differs between processes, and are checked free.
pub fn loopback_port() -> u16 {
    use std::sync::atomic::{AtomicU32, Ordering};
    static NEXT: AtomicU32 = AtomicU32::new(0);
    let ephemeral_low = std::fs::read_to_string("/proc/sys/net/ipv4/ip_local_port_range")
        .ok()
        .and_then(|t| t.split_whitespace().next()?.parse::<u32>().ok())
        .unwrap_or(32768)
        .clamp(2048, 65535);
    let (low, span) = (1024u32, ephemeral_low - 1024);
    let base = std::process::id().wrapping_mul(7919);
    for _ in 0..span {
        let port = (low + (base.wrapping_add(NEXT.fetch_add(1, Ordering::Relaxed))) % span) as u16;
        if std::net::TcpListener::bind(("127.0.0.1", port)).is_ok() {
            return port;
        }
    }
    panic!("no free loopback port below the ephemeral range {ephemeral_low}");
}

/// The effective user id of the tests (team namespaces are per user).
pub fn euid() -> u32 {
    // SAFETY: geteuid cannot fail.
    unsafe { libc::geteuid() }
}
