//! The fast primal variant (the default) is sound: every certified assignment is optimal,
//! across cost models (uniform, tied integers, distances, scaled and shifted, duplicate
//! robots), graphs, Case 1 and Case 2; nothing certifies before the first step; and its
//! consensus multipliers sum to zero exactly, however many rounds run.

use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::certify::oracle;
use admm_ta_agents::certify::stopping::NeverStop;
use admm_ta_agents::methods::primal::settings::fast_rho;
use admm_ta_agents::methods::primal::{PrimalAgent, PrimalParams, PrimalVariant, team_agents};
use admm_ta_agents::problem::cost_model::geometric;
use admm_ta_agents::problem::{AssignmentCase, CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_runtime::options::SolveOptions;
use admm_ta_runtime::solve::solve;
use admm_ta_topologies::TopologySpec;
use admm_ta_topologies::rng::SeededRng;
use admm_ta_transport::sim::process::LockstepSim;

/// The cost models of the sweep, `robots × tasks` from `seed`.
fn costs(model: usize, robots: usize, tasks: usize, seed: u64) -> CostMatrix {
    let mut rng = SeededRng::for_stream(seed, model as u64);
    let values: Vec<f64> = match model {
        0 => CostMatrix::uniform(robots, tasks, seed)
            .unwrap()
            .values()
            .to_vec(),
        // Small integers: many exactly tied optima.
        1 => (0..robots * tasks)
            .map(|_| (rng.uniform() * 4.0).floor())
            .collect(),
        2 => geometric(robots, tasks, seed).unwrap().values().to_vec(),
        // Scaled and shifted.
        3 => (0..robots * tasks)
            .map(|_| 250.0 * rng.uniform() - 40.0)
            .collect(),
        // Duplicate robots: robot 2k + 1 has robot 2k's costs (exact ties).
        _ => {
            let base = CostMatrix::uniform(robots, tasks, seed).unwrap();
            (0..robots)
                .flat_map(|i| base.row(i - i % 2).to_vec())
                .collect()
        }
    };
    CostMatrix::new(robots, tasks, values).unwrap()
}

#[test]
fn every_certified_assignment_is_optimal() {
    let shapes = [
        (2, 1),
        (2, 2),
        (3, 2),
        (4, 4),
        (5, 3),
        (6, 6),
        (7, 4),
        (8, 8),
        (12, 12),
    ];
    let topologies = ["complete", "chain", "random:0.3", "star"];
    let (mut runs, mut wrong, mut uncertified) = (0, Vec::new(), Vec::new());
    for model in 0..5 {
        for &(n, m) in &shapes {
            for topology in topologies {
                for seed in 0..2 {
                    let problem =
                        TaskAssignmentProblem::new(costs(model, n, m, seed), CaseChoice::Auto)
                            .unwrap();
                    let spec: TopologySpec = topology.parse().unwrap();
                    let graph = spec.build(n, seed).unwrap();
                    let options = SolveOptions::builder().seed(seed).build().unwrap();
                    let report = solve(&problem, &graph, &options).unwrap();
                    runs += 1;
                    let label = format!("model {model}, {n}×{m}, {topology}, seed {seed}");
                    if !report.converged {
                        uncertified.push(label);
                        continue;
                    }
                    // Nothing is certified from the state before the first step (with one
                    // task, sending every robot to it is optimal and provably so at once).
                    assert!(
                        m == 1 || report.certified_round.is_some_and(|r| r >= 1),
                        "{label}"
                    );
                    let optimum = oracle::solve(&problem).unwrap().cost;
                    let scale = problem.costs().spread().max(optimum.abs()).max(1e-300);
                    if (report.cost - optimum) / scale > 1e-9 {
                        wrong.push(format!("{label}: {} vs {optimum}", report.cost));
                    }
                }
            }
        }
    }
    assert_eq!(runs, 360);
    assert!(wrong.is_empty(), "wrong certified stops: {wrong:#?}");
    assert!(uncertified.is_empty(), "not certified: {uncertified:#?}");
}

/// The fast variant's agents (without the extrapolated readout, whose filter a solve's team
/// designs), and the graph's diameter.
fn fast_agents(problem: &TaskAssignmentProblem, spec: TopologySpec) -> (Vec<PrimalAgent>, usize) {
    let n = problem.robots();
    let graph = spec.build(n, 0).unwrap();
    let diameter = graph.diameter().unwrap();
    let rho = fast_rho(problem.costs().spread(), graph.mean_degree());
    let params = PrimalParams::for_variant(PrimalVariant::Fast, rho, diameter, n, 1e-9 * n as f64);
    (team_agents(problem, &graph, params, None, 0), diameter)
}

#[test]
fn nothing_is_certified_before_the_first_step() {
    let problem =
        TaskAssignmentProblem::new(CostMatrix::uniform(4, 4, 3).unwrap(), CaseChoice::Auto)
            .unwrap();
    let (agents, _) = fast_agents(&problem, TopologySpec::Complete);
    for agent in &agents {
        // Before any step the robot has read nothing: no by-construction slack.
        assert_eq!(agent.certificate_slack(), f64::INFINITY);
    }
}

#[test]
fn the_multipliers_sum_to_zero_exactly_on_a_long_chain_run() {
    let (n, m) = (30, 30);
    let problem =
        TaskAssignmentProblem::new(geometric(n, m, 5).unwrap(), CaseChoice::Auto).unwrap();
    assert_eq!(problem.case(), AssignmentCase::One);
    let graph = TopologySpec::Chain.build(n, 0).unwrap();
    let (agents, _) = fast_agents(&problem, TopologySpec::Chain);
    let mut sim = LockstepSim::new(agents, &graph);
    sim.run(2000, &mut NeverStop, &mut |_| {});
    let mut sum = vec![0i128; n * m];
    let mut float_sum = vec![0.0f64; n * m];
    let mut magnitude = vec![0.0f64; n * m];
    for agent in sim.agents() {
        let primal = agent;
        for (k, &units) in primal.exact_multipliers().unwrap().iter().enumerate() {
            sum[k] += units;
        }
        for (k, &q) in primal.multipliers().iter().enumerate() {
            float_sum[k] += q;
            magnitude[k] += q.abs();
        }
    }
    assert!(sum.iter().all(|&s| s == 0), "Σ K_i = 0 exactly");
    // Σ Q_i: one rounding per robot and entry (plus the summation here), not per round.
    for (s, a) in float_sum.iter().zip(&magnitude) {
        assert!(s.abs() <= 4.0 * f64::EPSILON * a * n as f64, "{s} vs {a}");
    }
    // And the team agrees on the optimum.
    let optimum = oracle::solve(&problem).unwrap();
    let decided: Vec<usize> = sim.agents().iter().map(|a| a.decide()).collect();
    assert!((problem.cost_of(&decided).unwrap() - optimum.cost).abs() < 1e-9);
}

/// The long-graph regression guard of `admm-ta experiment size-sweep` (which runs chains up
/// to 120 robots): a 30-robot chain (diameter 29) certifies the optimum, uniform and
/// distance costs, within about ten diameters (measured: 2.5–4.5; the paper's variant
/// needs thousands of rounds on chains).
#[test]
fn a_thirty_robot_chain_certifies_the_optimum_within_ten_diameters() {
    for (model, name) in [(0, "uniform"), (2, "distance")] {
        for seed in 1..=2 {
            let problem =
                TaskAssignmentProblem::new(costs(model, 30, 30, seed), CaseChoice::Auto).unwrap();
            let graph = TopologySpec::Chain.build(30, seed).unwrap();
            let options = SolveOptions::builder().seed(seed).build().unwrap();
            let report = solve(&problem, &graph, &options).unwrap();
            let optimum = oracle::solve(&problem).unwrap().cost;
            let label = format!("{name}, seed {seed}: {} rounds", report.iterations);
            assert!(report.converged && report.iterations <= 290, "{label}");
            assert!(
                (report.cost - optimum).abs() <= 1e-9 * optimum.abs().max(1.0),
                "{label}"
            );
        }
    }
}
