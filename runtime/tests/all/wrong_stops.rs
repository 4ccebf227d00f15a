//! The decentralized stop never certifies a non-optimal assignment: every method, Case 1
//! and Case 2, complete and random graphs, many seeds. (The oracle instances are checked in
//! the workspace's `tests/answers/oracle_instances.rs`.)

use crate::common;

use admm_ta_agents::certify::oracle;
use admm_ta_agents::methods::Method;
use admm_ta_runtime::options::SolveOptions;
use admm_ta_runtime::solve::solve;

#[test]
fn the_local_stop_never_certifies_a_wrong_assignment() {
    let settings = [
        (10, 10, "complete"),
        (10, 10, "random:0.4"),
        (12, 7, "complete"),
        (12, 7, "random:0.4"),
    ];
    let (mut runs, mut certified) = (0, 0);
    for method in Method::admm() {
        for (robots, tasks, topology) in settings {
            for seed in 0..15 {
                let (problem, graph) =
                    common::uniform_instance(robots, tasks, 100 + seed, topology, seed);
                let config = SolveOptions::builder()
                    .method(method)
                    .seed(seed)
                    .max_iters(4000)
                    .build()
                    .unwrap();
                let report = solve(&problem, &graph, &config).unwrap();
                let optimum = oracle::solve(&problem).unwrap();
                runs += 1;
                if report.converged {
                    certified += 1;
                    assert!(
                        report.cost <= optimum.cost + 1e-9 * optimum.cost.abs().max(1.0),
                        "{} {robots}×{tasks} {topology} seed {seed}: certified cost {} > optimum {}",
                        method.name(),
                        report.cost,
                        optimum.cost
                    );
                    assert!(!report.repaired, "a certified assignment needs no repair");
                }
            }
        }
    }
    // The rule must also actually stop: nearly every run certifies within the limit.
    assert!(
        certified * 10 >= runs * 9,
        "{certified} of {runs} runs certified"
    );
    eprintln!("{certified} of {runs} runs certified, none wrong");
}
