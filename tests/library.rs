//! The library API a robot program embeds (`admm_ta::Solver`), run end to end: the team of
//! processes of the crate documentation's third example (a documentation test has no
//! `admm-ta` binary to start agents from; this test has), and the same problem on threads
//! and in the simulation, bit for bit.

mod common;

use admm_ta::{
    CaseChoice, CostMatrix, Error, SolveError, Solver, TaskAssignmentProblem, Transport,
};

fn problem() -> TaskAssignmentProblem {
    TaskAssignmentProblem::new(CostMatrix::uniform(8, 5, 1).unwrap(), CaseChoice::Auto).unwrap()
}

#[test]
fn a_team_of_processes_through_the_library() {
    let report = Solver::new(problem())
        .transport(Transport::Ipc)
        .agent_program(env!("CARGO_BIN_EXE_admm-ta"))
        .check(true)
        .solve()
        .unwrap();
    assert!(report.check.as_ref().unwrap().optimal);
    assert!(report.startup_ms.is_some(), "agent processes were started");
    assert!(common::leftovers_of(std::process::id()).is_empty());
    let sim = Solver::new(problem()).solve().unwrap();
    let threads = Solver::new(problem())
        .transport(Transport::Threads)
        .solve()
        .unwrap();
    for other in [&sim, &threads] {
        assert_eq!(other.iterate_digests, report.iterate_digests);
        assert_eq!(other.assignment, report.assignment);
    }
}

#[test]
fn invalid_options_are_refused_before_anything_runs() {
    let refused = Solver::new(problem())
        .configure(|o| o.max_iters(0))
        .solve()
        .unwrap_err();
    assert!(matches!(refused, Error::Solve(SolveError::Config(_))));
    assert_eq!(refused.to_string(), "--max-iters must be at least 1");
}
