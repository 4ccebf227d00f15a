//! The library API a robot program embeds (`admm_ta::Solver`), run end to end: the team of
//! processes of the crate documentation's third example (a documentation test has no
//! `admm-ta` binary to start agents from; this test has), and the same problem on threads
//! and in the simulation, bit for bit.

use crate::common;

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
    // An option the method never reads is refused as on the command line, not ignored.
    let unread = Solver::new(problem())
        .method(admm_ta::Method::Market)
        .configure(|o| o.rho(Some(3.0)))
        .solve()
        .unwrap_err();
    assert!(matches!(
        unread,
        Error::Solve(SolveError::Config(
            admm_ta::ConfigError::NotForMethod { .. }
        ))
    ));
}

#[test]
fn the_readme_example_runs() -> Result<(), Box<dyn std::error::Error>> {
    use admm_ta::{Method, generate};
    let costs = CostMatrix::from_csv_str("0.9,0.1\n0.4,0.3\n0.2,0.8\n")?;
    let problem = TaskAssignmentProblem::new(costs, CaseChoice::Auto)?;
    let report = Solver::new(problem)
        .topology(generate::chain(3)?)
        .method(Method::Dual)
        .transport(Transport::Threads)
        .check(true)
        .solve()?;
    assert_eq!(report.assignment, [1, 1, 0]);
    assert!(report.check.unwrap().optimal);
    Ok(())
}
