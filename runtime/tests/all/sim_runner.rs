//! The lockstep simulation: deterministic, worker-count independent, and its stop rule
//! does not stop at wrong assignments.

use admm_ta_agents::certify::oracle;
use admm_ta_agents::certify::stopping::NeverStop;
use admm_ta_agents::methods::primal::{
    PrimalAgent, PrimalParams, PrimalVariant, ProjectionPath, team_agents,
};
use admm_ta_agents::methods::rho::default_rho;
use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_runtime::options::{SolveOptions, StopRule};
use admm_ta_runtime::solve::solve;
use admm_ta_topologies::{Graph, TopologySpec, generate};
use admm_ta_transport::sim::process::LockstepSim;

/// One agent of the paper's primal variant per robot, with its own costs.
fn agents(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    path: ProjectionPath,
) -> Vec<PrimalAgent> {
    let rho = default_rho(problem.costs(), graph.mean_degree());
    let params = PrimalParams {
        projection: path,
        ..PrimalParams::new(rho)
    };
    team_agents(problem, graph, params, None, 0)
}

fn payloads<A: admm_ta_agents::agent::ConsensusAgent + Send>(
    sim: &LockstepSim<A>,
    n: usize,
) -> Vec<f64> {
    (0..n).flat_map(|i| sim.payload(i).to_vec()).collect()
}

#[test]
fn worker_threads_do_not_change_a_single_bit() {
    let problem =
        TaskAssignmentProblem::new(CostMatrix::uniform(12, 7, 4).unwrap(), CaseChoice::Auto)
            .unwrap();
    let graph = generate::random_connected(12, 0.3, 4).unwrap();
    let mut one =
        LockstepSim::new(agents(&problem, &graph, ProjectionPath::Fast), &graph).with_workers(1);
    let mut three =
        LockstepSim::new(agents(&problem, &graph, ProjectionPath::Fast), &graph).with_workers(3);
    for _ in 0..60 {
        let a = one.step_round().to_vec();
        let b = three.step_round().to_vec();
        assert_eq!(a, b);
        assert_eq!(payloads(&one, 12), payloads(&three, 12));
    }
}

#[test]
fn qp_path_gives_the_same_iterates_as_the_fast_path() {
    let problem =
        TaskAssignmentProblem::new(CostMatrix::uniform(5, 4, 8).unwrap(), CaseChoice::Auto)
            .unwrap();
    let graph = generate::ring(5).unwrap();
    let mut fast = LockstepSim::new(agents(&problem, &graph, ProjectionPath::Fast), &graph);
    let mut qp = LockstepSim::new(agents(&problem, &graph, ProjectionPath::Qp), &graph);
    let mut never = NeverStop;
    fast.run(40, &mut never, &mut |_| {});
    qp.run(40, &mut never, &mut |_| {});
    let diff = payloads(&fast, 5)
        .iter()
        .zip(payloads(&qp, 5))
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    // Interior-point accuracy (~1e-8 per round) accumulates over the rounds.
    assert!(diff < 1e-5, "fast and QP iterates differ by {diff:e}");
}

#[test]
fn agreement_and_certified_stops_never_stop_at_a_wrong_assignment() {
    for stop in [StopRule::Agreement, StopRule::Certified] {
        stop_rule_is_safe(stop);
    }
}

fn stop_rule_is_safe(stop: StopRule) {
    let mut rounds = Vec::new();
    for (robots, tasks, topology) in [
        (8, 8, "complete"),
        (10, 5, "ring"),
        (9, 9, "random:0.4"),
        (7, 3, "chain"),
    ] {
        let spec: TopologySpec = topology.parse().unwrap();
        for seed in 0..25 {
            let costs = CostMatrix::uniform(robots, tasks, 1000 + seed).unwrap();
            let problem = TaskAssignmentProblem::new(costs, CaseChoice::Auto).unwrap();
            let graph = spec.build(robots, seed).unwrap();
            // The agreement stop waits for near-integral iterates: the paper's variant.
            let config = SolveOptions::builder()
                .stop(stop)
                .setting(match stop {
                    StopRule::Agreement => PrimalVariant::Paper,
                    _ => PrimalVariant::Fast,
                })
                .build()
                .unwrap();
            let report = solve(&problem, &graph, &config).unwrap();
            let optimum = oracle::solve(&problem).unwrap();
            assert!(problem.is_feasible(&report.assignment));
            if report.converged {
                assert!(
                    !report.repaired,
                    "{robots}x{tasks} {topology} seed {seed}: stopped in disagreement"
                );
                assert!(
                    (report.cost - optimum.cost).abs() <= 1e-9 * optimum.cost.abs().max(1.0),
                    "{stop:?} {robots}x{tasks} {topology} seed {seed}: stopped at cost {} > {}",
                    report.cost,
                    optimum.cost
                );
                rounds.push(report.iterations);
            }
        }
    }
    // Almost every run must stop by itself well before the 5000-round limit.
    assert!(
        rounds.len() >= 95,
        "only {} of 100 runs stopped",
        rounds.len()
    );
}

#[test]
fn early_stops_still_return_feasible_assignments() {
    let mut repaired = 0;
    for (robots, tasks) in [(9, 9), (11, 4)] {
        for seed in 0..10 {
            let problem = TaskAssignmentProblem::new(
                CostMatrix::uniform(robots, tasks, seed).unwrap(),
                CaseChoice::Auto,
            )
            .unwrap();
            let graph = generate::chain(robots).unwrap();
            for max_iters in [1, 2, 5, 20] {
                let config = SolveOptions::builder()
                    .max_iters(max_iters)
                    .build()
                    .unwrap();
                let report = solve(&problem, &graph, &config).unwrap();
                assert!(
                    problem.is_feasible(&report.assignment),
                    "{robots}x{tasks} seed {seed} after {max_iters}"
                );
                repaired += usize::from(report.repaired);
            }
        }
    }
    // Unconverged chains disagree: the repair path is exercised, not just the happy path.
    assert!(repaired > 0);
}

#[test]
fn certified_stop_fires_soon_after_the_assignment_is_optimal() {
    // The certificate needs the robots' duals to settle, not their iterates to become
    // integral, so it stops far sooner than the agreement rule.
    let (mut certified, mut agreement) = (0, 0);
    for seed in 0..10 {
        let problem = TaskAssignmentProblem::new(
            CostMatrix::uniform(12, 12, 77 + seed).unwrap(),
            CaseChoice::Auto,
        )
        .unwrap();
        let graph = generate::complete(12).unwrap();
        let run = |stop| {
            solve(
                &problem,
                &graph,
                &SolveOptions::builder()
                    .stop(stop)
                    .check(true)
                    // The agreement rule is the paper variant's.
                    .setting(PrimalVariant::Paper)
                    .build()
                    .unwrap(),
            )
            .unwrap()
        };
        let (c, a) = (run(StopRule::Certified), run(StopRule::Agreement));
        assert!(c.converged && c.check.as_ref().unwrap().optimal);
        certified += c.iterations;
        agreement += a.iterations;
    }
    assert!(
        certified < agreement,
        "certified {certified} vs agreement {agreement} rounds"
    );
}

#[test]
fn certificate_slack_bounds_the_optimality_gap_in_every_round() {
    // The theorem behind the certified stop: for any feasible assignment π, its cost exceeds
    // the optimum by at most Σ_i s_i(π) — in every round, for optimal and suboptimal π.
    let mut suboptimal_checks = 0;
    for (robots, tasks, seed) in [(8, 8, 1), (10, 4, 2), (9, 9, 3)] {
        let problem = TaskAssignmentProblem::new(
            CostMatrix::uniform(robots, tasks, seed).unwrap(),
            CaseChoice::Auto,
        )
        .unwrap();
        let graph = generate::ring(robots).unwrap();
        let optimum = oracle::solve(&problem).unwrap();
        // Feasible candidates: the optimum and cyclic shifts of it (suboptimal).
        let candidates: Vec<Vec<usize>> = (0..4)
            .map(|shift| {
                let mut a = optimum.assignment.clone();
                a.rotate_left(shift);
                a
            })
            .collect();
        let mut sim = LockstepSim::new(agents(&problem, &graph, ProjectionPath::Fast), &graph);
        for round in 0..200 {
            sim.step_round();
            if round % 7 != 0 {
                continue;
            }
            for pi in &candidates {
                let gap = problem.cost_of(pi).unwrap() - optimum.cost;
                let slack: f64 = sim
                    .agents()
                    .iter()
                    .map(|a| a.certificate_slack_for(pi))
                    .sum();
                assert!(
                    gap <= slack + 1e-9,
                    "round {round}: gap {gap} exceeds the certified bound {slack}"
                );
                suboptimal_checks += usize::from(gap > 1e-9);
            }
        }
    }
    assert!(suboptimal_checks > 100);
}
