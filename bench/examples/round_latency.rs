//! Round latency of the distributed transports, measured in one run so that the ratios are
//! comparable on a shared, noisy machine: `threads` (one thread per agent, in-process slots)
//! against `ipc` (one process per agent, iceoryx2), on complete graphs and chains of 10 and 50
//! agents, for a fixed number of rounds (`--stop max-iters`, so both do the same work).
//!
//! ```text
//! cargo build --release && cargo run --release -p admm-ta-bench --example round_latency -- [ROUNDS] [AGENT_BINARY]
//! ```

use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_runtime::latency::Percentiles;
use admm_ta_runtime::solve::{SolveConfig, StopRule, Transport, solve};
use admm_ta_topologies::TopologySpec;
use std::path::PathBuf;

fn main() {
    let mut args = std::env::args().skip(1);
    let rounds: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(300);
    let agent = PathBuf::from(
        args.next()
            .unwrap_or_else(|| "target/release/admm-ta".to_string()),
    );
    assert!(
        agent.exists(),
        "{} not found: build it first (cargo build --release) or pass its path",
        agent.display()
    );
    println!(
        "{rounds} rounds per run, m = n tasks, uniform costs seed 1; latencies in µs (p50 / p99)\n"
    );
    println!(
        "| n | graph | barrier | transport | round p50 | round p99 | wait p50 | compute p50 | publish p50 | barrier p50 | start-up ms |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for n in [10usize, 50] {
        for topology in ["complete", "chain"] {
            for global_barrier in [false, true] {
                let problem = TaskAssignmentProblem::new(
                    CostMatrix::uniform(n, n, 1).expect("valid size"),
                    CaseChoice::Auto,
                )
                .expect("square problem");
                let graph = topology
                    .parse::<TopologySpec>()
                    .expect("known topology")
                    .build(n, 0)
                    .expect("connected");
                let mut p50 = Vec::new();
                for transport in [Transport::Threads, Transport::Ipc] {
                    let config = SolveConfig {
                        transport,
                        stop: StopRule::MaxIters,
                        max_iters: rounds,
                        global_barrier,
                        agent_program: Some(agent.clone()),
                        ..SolveConfig::default()
                    };
                    let report = solve(&problem, &graph, &config).expect("run succeeds");
                    let l = report.round_latency_us.expect("latency recorded");
                    let show = |p: Percentiles| format!("{:.0}", p.p50);
                    println!(
                        "| {n} | {topology} | {} | {} | {:.0} | {:.0} | {} | {} | {} | {} | {} |",
                        if global_barrier {
                            "global"
                        } else {
                            "neighbour"
                        },
                        transport.name(),
                        l.round.p50,
                        l.round.p99,
                        show(l.wait),
                        show(l.compute),
                        show(l.publish),
                        if global_barrier {
                            show(l.barrier)
                        } else {
                            "-".into()
                        },
                        report
                            .startup_ms
                            .map_or("-".to_string(), |s| format!("{s:.0}"))
                    );
                    p50.push(l.round.p50);
                }
                println!(
                    "|   |   |   | ipc / threads | {:.2}× | | | | | | |",
                    p50[1] / p50[0]
                );
            }
        }
    }
}
