//! The dual methods in both variants certify the centralized optimum (issue 30): uniform,
//! distance, tie-heavy, forbidden-pair, Case 2, idle (both shapes), maximize and shifted
//! costs, on complete, chain and sparse random graphs; every certified stop optimal.

use admm_ta::agents::certify::oracle;
use admm_ta::agents::method::settings::{GivenSettings, SettingValue};
use admm_ta::agents::methods::dual::VARIANT;
use admm_ta::agents::problem::cost_model::CostModel;
use admm_ta::{CaseChoice, CostMatrix, Method, SolveOptions, TaskAssignmentProblem};
use admm_ta_runtime::solve::solve;
use admm_ta_topologies::TopologySpec;

/// A deterministic stream of uniforms in [0, 1).
fn uniforms(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn matrix(robots: usize, tasks: usize, mut cell: impl FnMut() -> f64) -> CostMatrix {
    CostMatrix::new(robots, tasks, (0..robots * tasks).map(|_| cell()).collect()).unwrap()
}

/// The problems every variant must certify.
fn problems() -> Vec<(&'static str, TaskAssignmentProblem)> {
    let mut next = uniforms(30);
    let mut out = Vec::new();
    let mut add = |name, costs: CostMatrix, case| {
        out.push((name, TaskAssignmentProblem::new(costs, case).unwrap()));
    };
    add("uniform 12x12", matrix(12, 12, &mut next), CaseChoice::Auto);
    add(
        "distance 12x12",
        CostModel::Geometric.costs(12, 12, 4).unwrap(),
        CaseChoice::Auto,
    );
    add(
        "integer ties 12x12",
        matrix(12, 12, || (next() * 4.0).floor()),
        CaseChoice::Auto,
    );
    add("case 2 14x8", matrix(14, 8, &mut next), CaseChoice::Auto);
    add(
        "idle 7x11",
        matrix(7, 11, &mut next),
        CaseChoice::Forced(admm_ta::agents::problem::AssignmentCase::Idle),
    );
    add(
        "idle 11x7",
        matrix(11, 7, &mut next),
        CaseChoice::Forced(admm_ta::agents::problem::AssignmentCase::Idle),
    );
    add(
        "shifted 1e9 10x10",
        matrix(10, 10, || 1e9 + next()),
        CaseChoice::Auto,
    );
    // Most pairs forbidden, a hidden permutation keeps it feasible.
    let n = 12;
    let values: Vec<f64> = (0..n * n)
        .map(|k| {
            if (k / n + 5) % n == k % n || next() < 0.3 {
                (next() * 20.0).floor()
            } else {
                f64::INFINITY
            }
        })
        .collect();
    add(
        "forbidden 12x12",
        CostMatrix::new(n, n, values).unwrap(),
        CaseChoice::Auto,
    );
    out
}

fn run(
    problem: &TaskAssignmentProblem,
    method: Method,
    variant: &str,
    topology: &str,
) -> admm_ta_runtime::solve::report::SolveReport {
    let graph = topology
        .parse::<TopologySpec>()
        .unwrap()
        .build(problem.robots(), 3)
        .unwrap();
    let options = SolveOptions::builder()
        .method(method)
        .settings(GivenSettings::default().set(&VARIANT, SettingValue::Name(variant.into())))
        .check(true)
        .max_iters(8000)
        .build()
        .unwrap();
    solve(problem, &graph, &options).unwrap()
}

/// The fast variant (the default) certifies every problem on every graph.
#[test]
fn the_fast_variant_certifies_every_kind_of_problem() {
    for (name, problem) in problems() {
        let optimum = oracle::solve(&problem).unwrap().cost;
        for method in [Method::Dual, Method::InexactDual] {
            for topology in ["complete", "chain", "random:0.3"] {
                let report = run(&problem, method, "fast", topology);
                let label = format!("{} on {name}, {topology}", method.name());
                assert!(report.certified, "{label}: not certified: {report:?}");
                assert!(!report.repaired, "{label}: repaired");
                assert!(
                    (report.cost - optimum).abs() <= 1e-9 * optimum.abs().max(1.0),
                    "{label}: {} vs {optimum}",
                    report.cost
                );
            }
        }
    }
}

/// Case 2 on long graphs: the potentials restart whenever the settling claims change, and
/// otherwise only after `(m + 2) D` rounds, long enough for the relaxations to travel (a
/// restart every `4D` rounds cut them off for good here: optimal from round 277, never
/// certified).
#[test]
fn case_two_certifies_on_long_graphs() {
    let problem = TaskAssignmentProblem::new(
        CostModel::Uniform.costs(14, 18, 197_915).unwrap(),
        CaseChoice::Forced(admm_ta::agents::problem::AssignmentCase::Idle),
    )
    .unwrap();
    let optimum = oracle::solve(&problem).unwrap().cost;
    for method in [Method::Dual, Method::InexactDual] {
        for topology in ["chain", "ring"] {
            let report = run(&problem, method, "fast", topology);
            let label = format!("{} on {topology}", method.name());
            assert!(report.certified, "{label}: {} rounds", report.iterations);
            assert!((report.cost - optimum).abs() <= 1e-9, "{label}");
        }
    }
}

/// Maximize: profits, the best total.
#[test]
fn the_fast_variant_certifies_the_largest_profit() {
    let mut next = uniforms(31);
    let profits = matrix(10, 10, || (next() * 100.0).floor());
    let problem = TaskAssignmentProblem::maximizing(profits, CaseChoice::Auto).unwrap();
    let optimum = oracle::solve(&problem).unwrap().cost;
    for method in [Method::Dual, Method::InexactDual] {
        let report = run(&problem, method, "fast", "random:0.3");
        assert!(report.certified, "{}", method.name());
        assert_eq!(report.cost, optimum, "{}", method.name());
    }
}

/// The paper's Algorithm 2 stays reachable and certifies too (more slowly).
#[test]
fn the_paper_variant_still_certifies() {
    let (_, problem) = problems().remove(0);
    let optimum = oracle::solve(&problem).unwrap().cost;
    for method in [Method::Dual, Method::InexactDual] {
        let fast = run(&problem, method, "fast", "complete");
        let paper = run(&problem, method, "paper", "complete");
        assert!(paper.certified, "{}", method.name());
        assert!((paper.cost - optimum).abs() <= 1e-9, "{}", method.name());
        // The paper's message is n + m = 24 multipliers, the fast one m prices, m
        // potentials and the m claims packed into one value (13 codes of 4 bits fit in
        // one): 25, and Case 1's finish: the m tags packed into one value, its window, its
        // alarm and its bound (its moves travel in the potentials' place): 4.
        let (fast_values, paper_values) = (12 + 12 + 1 + 4, 12 + 12);
        assert_eq!(
            fast.message_bytes - paper.message_bytes,
            8 * (fast_values - paper_values)
        );
    }
}
