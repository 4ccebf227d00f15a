//! One agent step of each ADMM method, and the centralized assignment oracle.
//!
//! `cargo bench -p admm-ta-bench --bench step`.
//!
//! * `step/METHOD/n`: robot 0's step on an `n × n` uniform problem over the complete graph
//!   (n − 1 neighbour payloads). The neighbours' payloads of rounds 30–59 of a lockstep run
//!   are recorded and fed to the agent in turn, so that it stays in flight (a step repeated
//!   on one fixed inbox would converge to a fixed point, where the projection is trivial).
//! * `oracle/n`: the centralized optimum (Jonker–Volgenant shortest augmenting paths) of an
//!   `n × n` uniform [0, 1) problem, for n = 50, 500, 2000 — the figures to compare with
//!   scipy's `linear_sum_assignment` (86 µs at 50, 9.8 ms at 500 on a CI runner).

use admm_ta_agents::agent::{ConsensusAgent, Inbox};
use admm_ta_agents::certify::oracle;
use admm_ta_agents::method::agent::MethodAgent;
use admm_ta_agents::method::team::TeamParams;
use admm_ta_agents::methods::{Contender, Method};
use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_runtime::workload::plan::AgentFactory;
use admm_ta_topologies::generate;
use admm_ta_transport::sim::process::LockstepSim;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::Duration;

/// Rounds of neighbour payloads fed to the timed agent in turn.
const RECORDED_ROUNDS: usize = 30;

/// Robot 0 after 60 rounds, and its neighbours' payloads of rounds 30–59.
fn agent_in_flight(method: Method, n: usize) -> (MethodAgent, Vec<Vec<Vec<f64>>>) {
    let problem =
        TaskAssignmentProblem::new(CostMatrix::uniform(n, n, 7).unwrap(), CaseChoice::Auto)
            .unwrap();
    let graph = generate::complete(n).unwrap();
    // Each method as the paper ran it (the primal method's paper variant).
    let contender = Contender::as_in_paper(method).unwrap_or(Contender::of(method));
    let setup = method.setup(&contender.settings()).unwrap().unwrap();
    let rho = setup
        .default_rho(problem.costs(), graph.mean_degree())
        .unwrap();
    let params = TeamParams {
        rho,
        diameter: 1,
        tolerance: f64::INFINITY,
    };
    let team = AgentFactory::new(&problem, &graph, setup, params, None, 0, None);
    let mut sim = LockstepSim::new(team.agents(), &graph);
    for _ in 0..30 {
        sim.step_round();
    }
    let mut rounds = Vec::with_capacity(RECORDED_ROUNDS);
    for _ in 0..RECORDED_ROUNDS {
        rounds.push(
            graph
                .neighbours(0)
                .iter()
                .map(|&j| sim.payload(j).to_vec())
                .collect(),
        );
        sim.step_round();
    }
    // Robot 0 as of round 60, fed the payloads of rounds 30–59: realistic inputs, a state
    // that is not at any fixed point of them.
    let agent = sim.into_agents().swap_remove(0);
    (agent, rounds)
}

fn step(c: &mut Criterion) {
    let mut group = c.benchmark_group("step");
    group
        .sample_size(30)
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(500));
    for method in Method::admm() {
        for n in [20usize, 50] {
            let (mut agent, rounds) = agent_in_flight(method, n);
            let inboxes: Vec<Vec<&[f64]>> = rounds
                .iter()
                .map(|r| r.iter().map(Vec::as_slice).collect())
                .collect();
            let mut out = vec![0.0; agent.payload_len()];
            let mut k = 0;
            group.bench_function(BenchmarkId::new(method.name(), n), |b| {
                b.iter(|| {
                    k = (k + 1) % inboxes.len();
                    black_box(agent.step(black_box(&inboxes[k] as &dyn Inbox), &mut out))
                })
            });
        }
    }
    group.finish();
}

fn assignment_oracle(c: &mut Criterion) {
    let mut group = c.benchmark_group("oracle");
    group.warm_up_time(Duration::from_millis(500));
    for n in [50usize, 500, 2000] {
        let problem =
            TaskAssignmentProblem::new(CostMatrix::uniform(n, n, 3).unwrap(), CaseChoice::Auto)
                .unwrap();
        if n >= 2000 {
            group
                .sample_size(10)
                .measurement_time(Duration::from_secs(20));
        } else {
            group
                .sample_size(20)
                .measurement_time(Duration::from_secs(3));
        }
        group.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| black_box(oracle::solve(black_box(&problem)).unwrap()))
        });
    }
    group.finish();
}

criterion_group!(benches, step, assignment_oracle);
criterion_main!(benches);
