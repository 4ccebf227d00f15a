//! Every transport drives the same agent step: for the same seed they must produce the same
//! iterates (bit for bit), stop at the same round and assign the same tasks. The shm, ipc
//! and uds runs use real agent processes (and real shared memory, or real sockets), each in
//! its own namespace, and must leave nothing behind.

use admm_ta_agents::method::settings::{GivenSettings, SettingValue};
use admm_ta_agents::methods::Method;
use admm_ta_agents::methods::dual::VARIANT;
use admm_ta_agents::problem::{AssignmentCase, CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_runtime::options::error::ConfigError;
use admm_ta_runtime::options::run::RunOptions;
use admm_ta_runtime::options::{SolveOptions, SolveOptionsBuilder, StopRule};
use admm_ta_runtime::runner::RunError;
use admm_ta_runtime::solve::error::SolveError;
use admm_ta_runtime::solve::report::SolveReport;
use admm_ta_runtime::solve::solve;
use admm_ta_topologies::{Graph, TopologySpec};
use admm_ta_transport::Transport;
use std::path::PathBuf;
use std::time::Duration;

fn problem(robots: usize, tasks: usize, seed: u64) -> TaskAssignmentProblem {
    TaskAssignmentProblem::new(
        CostMatrix::uniform(robots, tasks, seed).unwrap(),
        CaseChoice::Auto,
    )
    .unwrap()
}

fn graph(spec: &str, robots: usize, seed: u64) -> Graph {
    spec.parse::<TopologySpec>()
        .unwrap()
        .build(robots, seed)
        .unwrap()
}

fn config(transport: Transport, stop: StopRule, max_iters: usize) -> SolveOptionsBuilder {
    SolveOptions::builder()
        .transport(transport)
        .stop(stop)
        .max_iters(max_iters)
        .check(true)
        .agent_program(PathBuf::from(env!("CARGO_BIN_EXE_admm-ta")))
}

/// Nothing of an ipc run may remain in /dev/shm or the run directory.
fn assert_clean(report: &SolveReport) {
    let id = report.run_id.as_ref().expect("ipc reports its run id");
    let prefix = format!("adta{id}_");
    let left: Vec<_> = std::fs::read_dir("/dev/shm")
        .map(|d| {
            d.filter_map(Result::ok)
                .filter(|e| e.file_name().to_string_lossy().starts_with(&prefix))
                .map(|e| e.path())
                .collect()
        })
        .unwrap_or_default();
    assert!(left.is_empty(), "left in /dev/shm: {left:?}");
    let dir = admm_ta::runtime::process::namespace::runs_dir().join(id);
    assert!(!dir.exists(), "run directory {} remains", dir.display());
}

fn assert_same(a: &SolveReport, b: &SolveReport) {
    let what = format!("{} vs {}", a.transport.name(), b.transport.name());
    assert_eq!(a.iterations, b.iterations, "{what}: rounds");
    assert_eq!(a.converged, b.converged, "{what}: converged");
    assert_eq!(
        a.certified_round, b.certified_round,
        "{what}: certified round"
    );
    assert_eq!(a.assignment, b.assignment, "{what}: assignment");
    assert_eq!(a.iterate_digests, b.iterate_digests, "{what}: iterates");
}

fn all_transports(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    stop: StopRule,
    max_iters: usize,
) {
    all_transports_with(Method::Primal, problem, graph, stop, max_iters)
}

fn all_transports_with(
    method: Method,
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    stop: StopRule,
    max_iters: usize,
) {
    all_transports_with_settings(
        method,
        GivenSettings::default(),
        problem,
        graph,
        stop,
        max_iters,
    );
}

/// As [`all_transports_with`], the method with these settings (a variant).
fn all_transports_with_settings(
    method: Method,
    settings: GivenSettings,
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    stop: StopRule,
    max_iters: usize,
) {
    let run = |transport| {
        let config = config(transport, stop, max_iters)
            .method(method)
            .settings(settings.clone())
            .build()
            .unwrap();
        solve(problem, graph, &config).unwrap()
    };
    let (sim, threads, shm, ipc, uds) = (
        run(Transport::Sim),
        run(Transport::Threads),
        run(Transport::Shm),
        run(Transport::Ipc),
        run(Transport::Uds),
    );
    assert_same(&sim, &threads);
    assert_same(&sim, &shm);
    assert_same(&sim, &ipc);
    assert_same(&sim, &uds);
    assert_clean(&shm);
    assert_clean(&ipc);
    assert_clean(&uds);
    #[allow(unused_mut)]
    let mut distributed = vec![&threads, &shm, &ipc, &uds];
    // The multi-host transport, through a router on loopback.
    #[cfg(feature = "zenoh")]
    let zenoh = run(Transport::Zenoh);
    #[cfg(feature = "zenoh")]
    {
        assert_same(&sim, &zenoh);
        assert_clean(&zenoh);
        assert!(zenoh.startup_ms.unwrap() > 0.0);
        distributed.push(&zenoh);
    }
    if stop == StopRule::Local {
        assert!(sim.converged, "{}: no certified stop", graph.name());
        // CBAA is greedy: conflict-free, not necessarily optimal.
        assert!(
            sim.check.as_ref().unwrap().optimal || method == Method::Cbaa,
            "{}: not optimal",
            graph.name()
        );
        assert!(!sim.repaired, "{}: conflicting choices", graph.name());
        // The decentralized stop costs exactly the diameter over the certified round.
        assert_eq!(
            sim.iterations - sim.certified_round.unwrap(),
            graph.diameter().unwrap()
        );
    }
    for r in distributed {
        let latency = r.round_latency_us.expect("distributed runs record latency");
        let usage = r.agent_usage.expect("distributed runs record CPU usage");
        assert!(usage.voluntary_switches + usage.involuntary_switches > 0);
        assert_eq!(
            latency.round.count,
            // One per agent and round (the tasks are the agents of n < m idle problems).
            (problem.internal().robots() * r.iterations) as u64
        );
        assert!(latency.round.p50 > 0.0 && latency.round.p99 >= latency.round.p50);
    }
    assert!(shm.startup_ms.unwrap() > 0.0);
    assert!(ipc.startup_ms.unwrap() > 0.0);
    assert!(uds.startup_ms.unwrap() > 0.0);
}

#[test]
fn transports_agree_on_a_complete_graph() {
    all_transports(
        &problem(8, 8, 3),
        &graph("complete", 8, 0),
        StopRule::Local,
        2000,
    );
}

#[test]
fn transports_agree_on_a_chain_in_case_2() {
    all_transports(
        &problem(10, 6, 4),
        &graph("chain", 10, 0),
        StopRule::Local,
        4000,
    );
}

#[test]
fn dual_methods_agree_across_transports() {
    // The dual payload: 2m values and the packed claims (fast variant) or the n + m
    // multipliers (paper), not the m × n matrix; the fast variant's certificate floods
    // claims (integers packed into values, which every transport must carry exactly) and
    // potentials.
    for variant in ["fast", "paper"] {
        let settings = GivenSettings::default().set(&VARIANT, SettingValue::Name(variant.into()));
        all_transports_with_settings(
            Method::Dual,
            settings.clone(),
            &problem(8, 8, 3),
            &graph("complete", 8, 0),
            StopRule::Local,
            3000,
        );
        all_transports_with_settings(
            Method::InexactDual,
            settings,
            &problem(9, 5, 6),
            &graph("random:0.5", 9, 6),
            StopRule::Local,
            5000,
        );
    }
}

#[test]
fn baselines_agree_across_transports() {
    for (method, (robots, tasks, seed), topology) in [
        (Method::Cbaa, (9, 9, 2), "ring"),
        (Method::DistHungarian, (10, 6, 7), "chain"),
        (Method::Market, (9, 6, 4), "random:0.3"),
    ] {
        all_transports_with(
            method,
            &problem(robots, tasks, seed),
            &graph(topology, robots, seed),
            StopRule::Local,
            5000,
        );
    }
}

#[test]
fn transports_agree_on_more_tasks_than_robots() {
    // `--case idle` with n < m: the transposed problem, the tasks as agents on the lifted
    // graph.
    let wide = TaskAssignmentProblem::new(
        CostMatrix::uniform(4, 7, 5).unwrap(),
        CaseChoice::Forced(AssignmentCase::Idle),
    )
    .unwrap();
    for method in [Method::Primal, Method::Market] {
        all_transports_with(method, &wide, &graph("ring", 4, 0), StopRule::Local, 3000);
    }
}

#[test]
fn transports_agree_on_a_random_graph_to_the_round_limit() {
    all_transports(
        &problem(12, 12, 5),
        &graph("random:0.3", 12, 5),
        StopRule::MaxIters,
        60,
    );
}

#[test]
fn a_global_barrier_changes_timing_not_iterates() {
    let (p, g) = (problem(6, 6, 8), graph("ring", 6, 0));
    let plain = solve(
        &p,
        &g,
        &config(Transport::Sim, StopRule::Local, 2000)
            .build()
            .unwrap(),
    )
    .unwrap();
    for transport in [Transport::Threads, Transport::Shm, Transport::Ipc] {
        let barrier = solve(
            &p,
            &g,
            &config(transport, StopRule::Local, 2000)
                .global_barrier(true)
                .build()
                .unwrap(),
        )
        .unwrap();
        assert_same(&plain, &barrier);
        let latency = barrier.round_latency_us.unwrap();
        assert_eq!(latency.barrier.count, latency.round.count);
        if transport != Transport::Threads {
            assert_clean(&barrier);
        }
    }
}

#[test]
fn concurrent_ipc_runs_do_not_collide() {
    let runs: Vec<SolveReport> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..3)
            .map(|seed| {
                s.spawn(move || {
                    let (p, g) = (problem(6, 6, seed), graph("complete", 6, 0));
                    solve(
                        &p,
                        &g,
                        &config(Transport::Ipc, StopRule::Local, 2000)
                            .build()
                            .unwrap(),
                    )
                    .unwrap()
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for r in &runs {
        assert!(r.check.as_ref().unwrap().optimal);
        assert_clean(r);
    }
}

#[test]
fn a_failing_agent_is_reported_and_cleaned_up() {
    let (p, g) = (problem(4, 4, 1), graph("complete", 4, 0));
    let broken = config(Transport::Ipc, StopRule::Local, 100)
        .agent_program(Some(PathBuf::from("/bin/false")))
        .build()
        .unwrap();
    let err = solve(&p, &g, &broken).unwrap_err();
    assert!(
        matches!(err, SolveError::Run(RunError::Launch(_)))
            && err.to_string().contains("failed (exit code 1)"),
        "{err}"
    );
    let missing = config(Transport::Ipc, StopRule::Local, 100)
        .agent_program(Some(PathBuf::from("/nonexistent/admm-ta")))
        .build()
        .unwrap();
    let err = solve(&p, &g, &missing).unwrap_err().to_string();
    assert!(err.contains("cannot start agent process 0"), "{err}");
}

#[test]
fn an_agent_that_never_connects_fails_the_run_within_the_deadline() {
    // Agent 0 sleeps instead of running; its neighbours must give up after the start-up
    // deadline with a message saying so, and the launcher must kill and reap agent 0.
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("agent.sh");
    std::fs::write(
        &script,
        format!(
            "#!/bin/sh\nif [ \"$5\" = 0 ]; then sleep 30; fi\nexec {} \"$@\"\n",
            env!("CARGO_BIN_EXE_admm-ta")
        ),
    )
    .unwrap();
    std::fs::set_permissions(&script, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    let (p, g) = (problem(4, 4, 1), graph("complete", 4, 0));
    let started = std::time::Instant::now();
    let err = solve(
        &p,
        &g,
        &config(Transport::Ipc, StopRule::Local, 100)
            .agent_program(Some(script))
            .startup_timeout(Duration::from_secs(1))
            .build()
            .unwrap(),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("of 3 neighbours connected"), "{err}");
    assert!(
        started.elapsed() < Duration::from_secs(25),
        "the sleeping agent was not killed"
    );
}

#[test]
fn central_stop_rules_are_refused_on_distributed_transports() {
    let (p, g) = (problem(4, 4, 1), graph("complete", 4, 0));
    // The options refuse them before any solve can start.
    for transport in [Transport::Threads, Transport::Ipc] {
        let err = config(transport, StopRule::Certified, 100)
            .build()
            .unwrap_err();
        assert!(err.to_string().contains("sim transport only"), "{err}");
    }
    let err = config(Transport::Sim, StopRule::Local, 100)
        .global_barrier(true)
        .build()
        .unwrap_err();
    assert!(err.to_string().contains("threads, shm or ipc"), "{err}");
    // A solve with options built on the way reports the same.
    let solved = config(Transport::Threads, StopRule::Certified, 100)
        .build()
        .map_err(SolveError::from)
        .and_then(|options| solve(&p, &g, &options));
    assert!(matches!(solved, Err(SolveError::Config(_))));
}

#[test]
fn every_wait_strategy_gives_the_same_iterates_on_every_distributed_transport() {
    use admm_ta_transport::wait::WaitStrategy;
    let (p, g) = (problem(6, 6, 9), graph("ring", 6, 0));
    let reference = solve(
        &p,
        &g,
        &config(Transport::Sim, StopRule::MaxIters, 40)
            .build()
            .unwrap(),
    )
    .unwrap();
    for wait in [
        WaitStrategy::Block,
        WaitStrategy::SpinThenBlock,
        WaitStrategy::Spin,
    ] {
        for transport in [
            Transport::Threads,
            Transport::Shm,
            Transport::Ipc,
            Transport::Uds,
        ] {
            let report = solve(
                &p,
                &g,
                &config(transport, StopRule::MaxIters, 40)
                    .wait(wait)
                    .warmup_rounds(10)
                    .build()
                    .unwrap(),
            )
            .unwrap();
            assert_same(&reference, &report);
            // Warm-up rounds are not recorded.
            let latency = report.round_latency_us.unwrap();
            assert_eq!(latency.round.count, 6 * 30, "{wait:?} {transport:?}");
            assert_eq!(latency.overhead.count, latency.round.count);
            assert!(latency.overhead.p50 <= latency.round.p50);
            if transport != Transport::Threads {
                assert_clean(&report);
            }
        }
    }
}

#[test]
fn the_socket_baseline_moves_payloads_larger_than_the_socket_buffers() {
    // 200×200 payload: 320 KB per message, more than a socket buffer holds: sends that the
    // kernel cannot take at once must not deadlock two agents sending to each other.
    use admm_ta_agents::methods::probe::ProbeStep;
    use admm_ta_runtime::probe_run::{ProbeRun, run_probe};
    let g = graph("complete", 6, 0);
    for transport in [
        Transport::Threads,
        Transport::Shm,
        Transport::Ipc,
        Transport::Uds,
    ] {
        let options = RunOptions::builder()
            .transport(transport)
            .warmup_rounds(5)
            .round_timeout(Duration::from_secs(20))
            .agent_program(PathBuf::from(env!("CARGO_BIN_EXE_admm-ta")))
            .build()
            .unwrap();
        let run = ProbeRun {
            rounds: 30,
            ..ProbeRun::new(200 * 200, ProbeStep::Average, options)
        };
        let report = run_probe(&g, &run).unwrap();
        assert_eq!(report.latency.round.count, 6 * 25, "{transport:?}");
        assert!(report.usage.cpu_ns > 0);
    }
    // No global barrier over sockets: refused before any run.
    let refused = RunOptions::builder()
        .transport(Transport::Uds)
        .global_barrier(true)
        .build();
    assert_eq!(refused, Err(ConfigError::BarrierNeedsAgents));
    // A lockstep team measures no latency.
    let lockstep = ProbeRun::new(4, ProbeStep::Touch, RunOptions::default());
    assert!(matches!(
        run_probe(&g, &lockstep),
        Err(RunError::NotDistributed)
    ));
}
