//! scipy's own `linear_sum_assignment` test matrices (from `scipy/optimize/tests/
//! test_linear_assignment.py` and the cases it shares with `min_weight_full_bipartite_matching`),
//! ported: each matrix, its transpose, as costs and as profits (`maximize`), solved with
//! `--case idle` (scipy's rectangular meaning) by every method (more tasks than robots
//! too), must give scipy's optimal cost, certified. Input
//! validation (NaN, `-inf`, an infeasible `inf` pattern, empty matrices) is refused.
//!
//! Empty matrices: scipy returns an empty assignment; here a problem needs at least one robot
//! and one task, so an empty matrix is refused as bad input ("the cost file is empty" or "the
//! problem has zero robots/tasks").

use crate::common;
use admm_ta::agents::problem::{AssignmentCase, IDLE, ProblemError};

use admm_ta::{CaseChoice, CostMatrix, Method, TaskAssignmentProblem};
use common::solve_checked as solve;

const INF: f64 = f64::INFINITY;

/// The shared test cases: matrix rows and scipy's expected per-row costs.
fn cases() -> Vec<(Vec<Vec<f64>>, Vec<f64>)> {
    vec![
        (
            vec![
                vec![400.0, 150.0, 400.0],
                vec![400.0, 450.0, 600.0],
                vec![300.0, 225.0, 300.0],
            ],
            vec![150.0, 400.0, 300.0],
        ),
        (
            vec![
                vec![400.0, 150.0, 400.0, 1.0],
                vec![400.0, 450.0, 600.0, 2.0],
                vec![300.0, 225.0, 300.0, 3.0],
            ],
            vec![150.0, 2.0, 300.0],
        ),
        (
            vec![
                vec![10.0, 10.0, 8.0],
                vec![9.0, 8.0, 1.0],
                vec![9.0, 7.0, 4.0],
            ],
            vec![10.0, 1.0, 7.0],
        ),
        (
            vec![
                vec![10.0, 10.0, 8.0, 11.0],
                vec![9.0, 8.0, 1.0, 1.0],
                vec![9.0, 7.0, 4.0, 10.0],
            ],
            vec![10.0, 1.0, 4.0],
        ),
        (
            vec![
                vec![10.0, INF, INF],
                vec![INF, INF, 1.0],
                vec![INF, 7.0, INF],
            ],
            vec![10.0, 1.0, 7.0],
        ),
    ]
}

fn matrix(rows: &[Vec<f64>]) -> CostMatrix {
    CostMatrix::new(rows.len(), rows[0].len(), rows.concat()).unwrap()
}

fn transpose(rows: &[Vec<f64>]) -> Vec<Vec<f64>> {
    (0..rows[0].len())
        .map(|c| rows.iter().map(|r| r[c]).collect())
        .collect()
}

fn problem(rows: &[Vec<f64>], maximize: bool) -> TaskAssignmentProblem {
    let sign = if maximize { -1.0 } else { 1.0 };
    let signed: Vec<Vec<f64>> = rows
        .iter()
        .map(|r| r.iter().map(|v| sign * v).collect())
        .collect();
    let costs = matrix(&signed);
    let idle = CaseChoice::Forced(AssignmentCase::Idle);
    if maximize {
        TaskAssignmentProblem::maximizing(costs, idle).unwrap()
    } else {
        TaskAssignmentProblem::new(costs, idle).unwrap()
    }
}

#[test]
fn scipys_matrices_give_scipys_optimal_cost_with_every_method() {
    let mut solved = 0;
    for (rows, expected) in cases() {
        for transposed in [false, true] {
            let rows = if transposed {
                transpose(&rows)
            } else {
                rows.clone()
            };
            for maximize in [false, true] {
                let p = problem(&rows, maximize);
                let sign = if maximize { -1.0 } else { 1.0 };
                let want: f64 = sign * expected.iter().sum::<f64>();
                for method in Method::ALL {
                    let what = format!("{rows:?} maximize {maximize} {}", method.name());
                    match solve(&p, method) {
                        Ok(report) => {
                            assert!(p.is_feasible(&report.assignment), "{what}");
                            let check = report.check.as_ref().unwrap();
                            assert_eq!(check.optimal_cost, want, "{what}");
                            if method != Method::Cbaa {
                                assert_eq!(report.cost, want, "{what}");
                                assert!(check.optimal && report.certified, "{what}");
                                solved += 1;
                            }
                            let served = report.assignment.iter().filter(|&&t| t != IDLE);
                            assert_eq!(served.count(), rows.len().min(rows[0].len()), "{what}");
                        }
                        Err(other) => panic!("{what}: {other}"),
                    }
                }
            }
        }
    }
    eprintln!("{solved} optimal solves of scipy's matrices");
}

#[test]
fn scipys_constant_matrix_and_input_validation() {
    let ones = vec![vec![1.0; 8]; 8];
    for method in Method::ALL {
        let report = solve(&problem(&ones, false), method).unwrap();
        assert_eq!(report.cost, 8.0, "{}", method.name());
    }
    // NaN and -inf are refused; a column of +inf makes the problem infeasible.
    let mut nan = vec![vec![0.0; 3]; 3];
    nan[0][0] = f64::NAN;
    assert!(CostMatrix::new(3, 3, nan.concat()).is_err());
    let mut identity: Vec<Vec<f64>> = (0..3)
        .map(|i| (0..3).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
        .collect();
    identity[1][1] = -INF;
    assert!(matches!(
        TaskAssignmentProblem::new(matrix(&identity), CaseChoice::Auto),
        Err(ProblemError::NonFinite { .. })
    ));
    let mut column = vec![
        vec![1.0, 0.0, 0.0],
        vec![0.0, 1.0, 0.0],
        vec![0.0, 0.0, 1.0],
    ];
    for row in &mut column {
        row[0] = INF;
    }
    let err = TaskAssignmentProblem::new(matrix(&column), CaseChoice::Auto).unwrap_err();
    assert_eq!(err.to_string(), "infeasible: task 0 has no allowed robot");
    // Empty matrices are refused (see the module docs).
    assert!(CostMatrix::new(0, 0, vec![]).is_err());
    assert!(CostMatrix::new(2, 0, vec![]).is_err());
    assert!(CostMatrix::new(0, 3, vec![]).is_err());
    assert!(CostMatrix::from_csv_str("").is_err());
}

/// Uniform `[0, 1)` numbers from a seeded linear congruential generator (no RNG crate).
fn uniforms(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// scipy's sparse comparison: 100 × 100 with 6% allowed integer costs in 1..100, `inf`
/// elsewhere; about a third are infeasible. The feasibility check (Hall's condition) must agree
/// with the exact solver, and a sample of the feasible ones is solved by every optimal method.
#[test]
fn sparse_random_matrices_feasibility_agrees_with_the_exact_solver() {
    let mut next = uniforms(1234);
    let (mut feasible, mut infeasible) = (0, 0);
    for trial in 0..100 {
        let values: Vec<f64> = (0..100 * 100)
            .map(|_| {
                if next() < 0.06 {
                    (1.0 + (next() * 99.0).floor()).min(99.0)
                } else {
                    INF
                }
            })
            .collect();
        let exact = admm_ta::agents::numerics::lsap::solve(&values, 100, 100);
        let costs = CostMatrix::new(100, 100, values).unwrap();
        match TaskAssignmentProblem::new(costs, CaseChoice::Auto) {
            Err(ProblemError::Infeasible(line)) => {
                assert!(exact.is_err(), "trial {trial}: {line}");
                infeasible += 1;
            }
            Err(other) => panic!("{other}"),
            Ok(p) => {
                let exact = exact.unwrap();
                let cost: f64 = exact
                    .iter()
                    .enumerate()
                    .map(|(r, c)| p.costs().get(r, c.unwrap()))
                    .sum();
                feasible += 1;
                let methods: &[Method] = if feasible <= 2 {
                    &[Method::Hungarian, Method::DistHungarian, Method::Market]
                } else {
                    &[Method::Hungarian]
                };
                for &method in methods {
                    let report = solve(&p, method).unwrap();
                    assert_eq!(report.cost, cost, "trial {trial} {}", method.name());
                }
            }
        }
    }
    eprintln!("{feasible} feasible, {infeasible} infeasible");
    assert!(feasible > 10 && infeasible > 10);
}

/// Sparse 40 × 40 integer matrices in which most pairs are forbidden (15% allowed, plus a
/// hidden permutation that keeps them feasible): both dual methods certify the exact optimum
/// (forbidden pairs are bounds of each robot's own problem, not a penalty its multipliers
/// must climb to — before, every one ended at the round limit, repaired and not optimal).
#[test]
fn dual_methods_certify_sparse_forbidden_matrices() {
    let mut next = uniforms(4321);
    let n = 40;
    for trial in 0..3 {
        let mut permutation: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            permutation.swap(i, (next() * (i + 1) as f64) as usize % (i + 1));
        }
        let values: Vec<f64> = (0..n * n)
            .map(|k| {
                if permutation[k / n] == k % n || next() < 0.15 {
                    (next() * 101.0).floor().min(100.0)
                } else {
                    INF
                }
            })
            .collect();
        let exact = admm_ta::agents::numerics::lsap::solve(&values, n, n).unwrap();
        let optimum: f64 = exact
            .iter()
            .enumerate()
            .map(|(r, c)| values[r * n + c.unwrap()])
            .sum();
        let p =
            TaskAssignmentProblem::new(CostMatrix::new(n, n, values).unwrap(), CaseChoice::Auto)
                .unwrap();
        for method in [Method::Dual, Method::InexactDual] {
            let report = solve(&p, method).unwrap();
            assert!(
                report.certified,
                "trial {trial} {}: {report:?}",
                method.name()
            );
            assert_eq!(report.cost, optimum, "trial {trial} {}", method.name());
        }
    }
}
