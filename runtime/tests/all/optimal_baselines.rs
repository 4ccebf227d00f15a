//! The optimal baselines (market with strategic pricing, distributed Hungarian) on many seeds
//! and graphs: they always stop by themselves, every robot at the same round, with the
//! optimal conflict-free assignment, whatever the connected graph (including ties and
//! Case 2).

use crate::common;

use admm_ta_agents::certify::oracle;
use admm_ta_agents::methods::Method;
use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_runtime::options::SolveOptions;
use admm_ta_runtime::solve::solve;

fn always_optimal(method: Method) {
    let mut runs = 0;
    for (robots, tasks) in [(8, 8), (15, 15), (12, 5), (20, 20)] {
        for topology in [
            "complete",
            "chain",
            "ring",
            "star",
            "random:0.2",
            "geometric:0.4",
        ] {
            for seed in 0..6 {
                let (mut problem, graph) =
                    common::uniform_instance(robots, tasks, 900 + seed, topology, seed);
                if seed == 5 {
                    // Integer costs with many ties.
                    let ties: Vec<f64> = (0..robots * tasks)
                        .map(|k| ((k * 7 + seed as usize) % 4) as f64)
                        .collect();
                    problem = TaskAssignmentProblem::new(
                        CostMatrix::new(robots, tasks, ties).unwrap(),
                        CaseChoice::Auto,
                    )
                    .unwrap();
                }
                let config = SolveOptions::builder()
                    .method(method)
                    .seed(seed)
                    .max_iters(50_000)
                    .build()
                    .unwrap();
                let report = solve(&problem, &graph, &config).unwrap();
                let what = format!("{} {robots}×{tasks} {topology} seed {seed}", method.name());
                assert!(report.converged, "{what}: did not stop");
                assert!(!report.repaired, "{what}: robots' tasks conflicted");
                assert!(problem.is_feasible(&report.assignment), "{what}");
                assert_eq!(
                    report.iterations - report.certified_round.unwrap(),
                    graph.diameter().unwrap(),
                    "{what}: robots stopped at different rounds"
                );
                let best = oracle::solve(&problem).unwrap().cost;
                assert!(
                    (report.cost - best).abs() <= 1e-9 * best.abs().max(1.0),
                    "{what}: cost {} vs optimum {best}",
                    report.cost
                );
                runs += 1;
            }
        }
    }
    assert_eq!(runs, 4 * 6 * 6);
}

#[test]
fn market_is_always_optimal_on_any_connected_graph() {
    always_optimal(Method::Market);
}

#[test]
fn distributed_hungarian_is_always_optimal_on_any_connected_graph() {
    always_optimal(Method::DistHungarian);
}
