//! The normalised problem the agents solve: unit-interval costs, penalties for forbidden
//! pairs, the idle task; Hall's condition with a blocking set; the resolution refusal.

use admm_ta_agents::problem::{
    AssignmentCase, CaseChoice, CostMatrix, ProblemError, TaskAssignmentProblem,
};

fn problem(text: &str, choice: CaseChoice) -> Result<TaskAssignmentProblem, ProblemError> {
    TaskAssignmentProblem::new(CostMatrix::from_csv_str(text).unwrap(), choice)
}

#[test]
fn normalises_to_the_unit_interval_with_penalties_and_idle_tasks() {
    let p = problem("10,inf\n30,20\n50,40\n", CaseChoice::Auto).unwrap();
    let norm = p.normalised().unwrap();
    assert_eq!((norm.shift, norm.scale), (10.0, 40.0));
    let internal = p.internal();
    assert_eq!(
        internal.costs().values(),
        &[0.0, 10.0, 0.5, 0.25, 1.0, 0.75]
    );
    assert!(!internal.costs().is_allowed(0, 1));
    assert_eq!(internal.costs().spread(), p.costs().spread() / 40.0);

    let idle = problem("1,2\n3,4\n5,6\n", CaseChoice::Forced(AssignmentCase::Idle)).unwrap();
    assert_eq!(idle.internal().tasks(), 3);
    assert_eq!(idle.internal().case(), AssignmentCase::Two);
    assert_eq!(idle.internal().costs().row(2), &[1.8, 2.0, 0.0]);
    let constant = problem("7,7\n7,7\n", CaseChoice::Auto).unwrap();
    assert!(
        constant
            .internal()
            .costs()
            .values()
            .iter()
            .all(|&v| v == 0.0)
    );
}

#[test]
fn infeasible_problems_name_a_blocking_set() {
    let err = problem("1,inf,inf\n2,inf,inf\n3,4,5\n", CaseChoice::Auto).unwrap_err();
    assert_eq!(
        err.to_string(),
        "infeasible: tasks 1, 2 can only be done by robot 2"
    );
    let err = problem("inf,inf\n1,2\n3,4\n", CaseChoice::Auto).unwrap_err();
    assert_eq!(err.to_string(), "infeasible: robot 0 has no allowed task");
}

#[test]
fn refuses_unresolvable_spreads_only() {
    let mut rng = admm_ta_topologies::rng::SeededRng::new(3);
    let wide: Vec<String> = (0..100)
        .map(|_| format!("{:e}", 10f64.powf(-150.0 + 305.0 * rng.uniform())))
        .collect();
    let text: String = wide.chunks(10).map(|r| r.join(",") + "\n").collect();
    assert!(
        problem(&text, CaseChoice::Auto)
            .unwrap()
            .normalised()
            .unwrap()
            .unresolved
            .is_some()
    );
    let sentinel: String = (0..10)
        .map(|i| {
            (0..10)
                .map(|j| {
                    if (i + j) % 3 == 0 {
                        "1e9".into()
                    } else {
                        format!("{}", rng.uniform())
                    }
                })
                .collect::<Vec<_>>()
                .join(",")
                + "\n"
        })
        .collect();
    let why = problem(&sentinel, CaseChoice::Auto)
        .unwrap()
        .normalised()
        .unwrap()
        .unresolved
        .clone();
    assert!(why.unwrap().contains("write inf"));
    for text in [
        "1,1.0000000000000002\n1.0000000000000004,1\n",
        "1,2\n3,4\n",
        "1e6,2e6\n3e6,4e6\n",
    ] {
        assert!(
            problem(text, CaseChoice::Auto)
                .unwrap()
                .normalised()
                .unwrap()
                .unresolved
                .is_none()
        );
    }
}
