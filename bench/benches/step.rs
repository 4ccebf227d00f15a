//! One agent step of each ADMM method, and the centralized assignment oracle.
//!
//! `cargo bench -p admm-ta-bench --bench step`.
//!
//! * `step/METHOD/n`: robot 0's step on an `n × n` uniform problem over the complete graph
//!   (n − 1 neighbour payloads), in the state reached after 30 lockstep rounds, the
//!   neighbours' payloads held fixed (the step's cost does not depend on the round).
//! * `oracle/n`: the centralized optimum (Jonker–Volgenant shortest augmenting paths) of an
//!   `n × n` uniform [0, 1) problem, for n = 50, 500, 2000 — the figures to compare with
//!   scipy's `linear_sum_assignment` (86 µs at 50, 9.8 ms at 500 on a CI runner).

use admm_ta_agents::agent::{ConsensusAgent, Inbox};
use admm_ta_agents::method::{AgentSettings, Method, MethodAgent};
use admm_ta_agents::oracle;
use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_agents::rho;
use admm_ta_runtime::sim::LockstepSim;
use admm_ta_runtime::team::Team;
use admm_ta_topologies::generate;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::Duration;

/// Robot 0 after 30 rounds, and its neighbours' payloads of that round.
fn agent_in_flight(method: Method, n: usize) -> (MethodAgent, Vec<Vec<f64>>) {
    let problem =
        TaskAssignmentProblem::new(CostMatrix::uniform(n, n, 7).unwrap(), CaseChoice::Auto)
            .unwrap();
    let graph = generate::complete(n).unwrap();
    let rho = rho::default_rho_for(method, problem.costs(), graph.mean_degree());
    let team = Team {
        problem: &problem,
        graph: &graph,
        settings: AgentSettings::new(method, rho, 1, f64::INFINITY),
        epsilon: None,
        seed: 0,
        schedule: None,
    };
    let mut sim = LockstepSim::new(team.agents(), &graph);
    for _ in 0..30 {
        sim.step_round();
    }
    let payloads = graph
        .neighbours(0)
        .iter()
        .map(|&j| sim.payload(j).to_vec())
        .collect();
    let agent = sim.into_agents().swap_remove(0);
    (agent, payloads)
}

fn step(c: &mut Criterion) {
    let mut group = c.benchmark_group("step");
    group
        .sample_size(30)
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(500));
    for method in [Method::Primal, Method::Dual, Method::InexactDual] {
        for n in [20usize, 50] {
            let (mut agent, payloads) = agent_in_flight(method, n);
            let inbox: Vec<&[f64]> = payloads.iter().map(Vec::as_slice).collect();
            let mut out = vec![0.0; agent.payload_len()];
            group.bench_function(BenchmarkId::new(method.name(), n), |b| {
                b.iter(|| black_box(agent.step(black_box(&inbox as &dyn Inbox), &mut out)))
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
