//! The failing cases as files (`tests/fixtures/corpus/`, each with a comment line
//! saying what it was): every method on each, through the library on `sim`, and the command
//! line's exit codes and lines for a sample (the primal on `ipc` where it used to panic).

use crate::common;

use admm_ta::agents::problem::{IDLE, ProblemError};
use admm_ta::{CaseChoice, CostMatrix, Method, SolveError, TaskAssignmentProblem};
use common::solve_checked as solve;
use std::path::{Path, PathBuf};
use std::process::Command;

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/corpus")
}

fn load(name: &str) -> Result<TaskAssignmentProblem, ProblemError> {
    let costs = CostMatrix::read_csv(&corpus().join(name))?;
    if name.starts_with("profits") {
        TaskAssignmentProblem::maximizing(costs, CaseChoice::Auto)
    } else {
        TaskAssignmentProblem::new(costs, CaseChoice::Auto)
    }
}

#[test]
fn every_method_on_every_corpus_file() {
    let mut names: Vec<String> = std::fs::read_dir(corpus())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".csv"))
        .collect();
    names.sort();
    assert!(names.len() >= 10);
    for name in &names {
        let problem = match load(name) {
            Err(ProblemError::Infeasible(line)) => {
                assert!(
                    name.starts_with("infeasible") || name.starts_with("robot_without"),
                    "{name}: {line}"
                );
                continue;
            }
            Err(other) => panic!("{name}: {other}"),
            Ok(problem) => problem,
        };
        assert!(
            !name.starts_with("infeasible"),
            "{name} should be infeasible"
        );
        let unresolvable = name.starts_with("sentinel") || name.starts_with("log_uniform");
        // The 64×64 instance runs the fast methods here (the ADMM methods' round limit is
        // the command line test below).
        let methods: &[Method] = if name.starts_with("distance") {
            &[Method::Market, Method::DistHungarian, Method::Hungarian]
        } else {
            &Method::ALL
        };
        for &method in methods {
            let what = format!("{name} {}", method.name());
            match solve(&problem, method) {
                Ok(report) => {
                    assert!(problem.is_feasible(&report.assignment), "{what}");
                    for (robot, &task) in report.assignment.iter().enumerate() {
                        assert!(
                            task == IDLE || problem.costs().is_allowed(robot, task),
                            "{what}"
                        );
                    }
                    if method != Method::Cbaa {
                        let check = report.check.as_ref().unwrap();
                        assert!(check.optimal && report.certified, "{what}: {report:?}");
                    }
                    assert!(
                        !unresolvable
                            || matches!(method, Method::Hungarian | Method::DistHungarian),
                        "{what}"
                    );
                }
                Err(SolveError::Unresolvable(line)) => {
                    assert!(unresolvable, "{what}: {line}");
                    assert!(line.contains("--method hungarian"), "{line}");
                    if name.starts_with("sentinel") {
                        assert!(line.contains("write inf"), "{line}");
                    }
                }
                Err(other) => panic!("{what}: {other}"),
            }
        }
    }
}

fn cli(args: &[&str]) -> (Option<i32>, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_admm-ta"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn the_command_line_on_the_corpus() {
    let file = |name: &str| corpus().join(name).to_string_lossy().into_owned();
    // Near-equal costs on agent processes: no panic, no dropped robot, optimal.
    for name in ["ulp_10x10.csv", "one_plus_u_1e-15_12x12.csv"] {
        let (code, stdout, stderr) = cli(&[
            "solve",
            "--costs",
            &file(name),
            "--transport",
            "ipc",
            "--on-failure",
            "continue",
            "--check",
            "--json",
        ]);
        assert_eq!(code, Some(0), "{name}: {stderr}");
        let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
        assert_eq!(report["check"]["optimal"], true, "{name}");
        assert!(report.get("degraded").is_none(), "{name}");
    }
    assert!(common::leftovers_of(std::process::id()).is_empty());
    let (code, _, stderr) = cli(&["solve", "--costs", &file("infeasible_tasks_1_2.csv")]);
    assert_eq!(code, Some(3));
    assert_eq!(
        stderr.trim(),
        "error: infeasible: tasks 1, 2 can only be done by robot 2"
    );
    let (code, _, stderr) = cli(&["solve", "--costs", &file("sentinel_1e9_20x20.csv")]);
    assert_eq!(code, Some(2));
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    let (code, _, _) = cli(&[
        "solve",
        "--costs",
        &file("log_uniform_1e-150_1e155_10x10.csv"),
        "--method",
        "hungarian",
        "--check",
    ]);
    assert_eq!(code, Some(0));
    // The round limit without a certificate: exit 5, the assignment still printed and marked.
    let (code, stdout, _) = cli(&[
        "solve",
        "--costs",
        &file("distance_64x64.csv"),
        // The fast variant certifies this instance within 20 rounds; the paper's does not.
        "--primal-variant",
        "paper",
        "--max-iters",
        "20",
        "--json",
    ]);
    assert_eq!(code, Some(5));
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(report["certified"], false);
    assert_eq!(report["assignment"].as_array().unwrap().len(), 64);
}
