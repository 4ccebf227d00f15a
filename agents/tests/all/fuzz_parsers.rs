//! Fuzzing, as property tests that run in CI: the cost CSV parser and every method's payload
//! check must never panic, must refuse every NaN, and must accept what they are meant to.
//! (Tried with many more cases locally: `PROPTEST_CASES=100000 cargo test --release
//! --test fuzz_parsers`.)

use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::method::agent::MethodAgent;
use admm_ta_agents::method::team::{AgentInit, TeamContext, TeamParams};
use admm_ta_agents::methods::{Contender, Method};
use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use proptest::prelude::*;

/// Every method a team runs.
fn team_methods() -> Vec<Method> {
    Method::ALL
        .into_iter()
        .filter(|m| m.team().is_some())
        .collect()
}

/// Text that looks like a cost CSV: numbers, junk cells, separators and line breaks.
fn csv_like() -> impl Strategy<Value = String> {
    let cell = prop_oneof![
        any::<f64>().prop_map(|v| v.to_string()),
        (-1e6..1e6f64).prop_map(|v| format!("{v:.3}")),
        Just("NaN".to_string()),
        Just("inf".to_string()),
        Just("-inf".to_string()),
        Just(String::new()),
        Just("x".to_string()),
        Just("1e999".to_string()),
        Just(" 2 ".to_string()),
        Just("#".to_string()),
        "[ -~]{0,6}",
    ];
    let line = prop::collection::vec(cell, 0..6).prop_map(|cells| cells.join(","));
    (prop::collection::vec(line, 0..6), prop::bool::ANY)
        .prop_map(|(lines, crlf)| lines.join(if crlf { "\r\n" } else { "\n" }))
}

proptest! {
    #[test]
    fn csv_parser_never_panics_on_arbitrary_text(text in "\\PC{0,200}") {
        let _ = CostMatrix::from_csv_str(&text);
    }

    #[test]
    fn csv_parser_accepts_only_numeric_rectangular_matrices(text in csv_like()) {
        if let Ok(costs) = CostMatrix::from_csv_str(&text) {
            prop_assert!(costs.robots() >= 1 && costs.tasks() >= 1);
            for r in 0..costs.robots() {
                prop_assert_eq!(costs.row(r).len(), costs.tasks());
                // ±∞ mark forbidden pairs; NaN is never accepted.
                prop_assert!(costs.row(r).iter().all(|v| !v.is_nan()));
                for t in 0..costs.tasks() {
                    prop_assert_eq!(costs.is_allowed(r, t), costs.get(r, t).is_finite());
                }
            }
            // Building a problem never panics: it is a problem or one error.
            let _ = admm_ta_agents::problem::TaskAssignmentProblem::new(
                costs,
                admm_ta_agents::problem::CaseChoice::Auto,
            );
        }
    }

    #[test]
    fn csv_round_trips_every_finite_matrix(
        rows in 1usize..6,
        tasks in 1usize..6,
        seed in any::<u64>(),
    ) {
        let values: Vec<f64> = (0..rows * tasks)
            .map(|k| ((seed.wrapping_mul(k as u64 + 1) >> 11) as f64) * 1e-9 - 1e3)
            .collect();
        let text: String = values
            .chunks(tasks)
            .map(|row| row.iter().map(|v| format!("{v:e}")).collect::<Vec<_>>().join(",") + "\n")
            .collect();
        let parsed = CostMatrix::from_csv_str(&text).unwrap();
        prop_assert_eq!(parsed.robots(), rows);
        for r in 0..rows {
            prop_assert_eq!(parsed.row(r), &values[r * tasks..(r + 1) * tasks]);
        }
    }

    /// A neighbour's payload, corrupted anywhere: the check never panics, refuses any NaN and
    /// any wrong length, and accepts the payload a real agent of the method wrote.
    #[test]
    fn payload_checks_refuse_corruption_and_accept_real_payloads(
        method in prop::sample::select(team_methods()),
        robots in 1usize..7,
        position in any::<prop::sample::Index>(),
        garbage in any::<f64>(),
        resize in -2isize..3,
    ) {
        let tasks = robots;
        let costs = CostMatrix::uniform(robots, tasks, 7).unwrap();
        let problem = TaskAssignmentProblem::new(costs.clone(), CaseChoice::Auto).unwrap();
        let graph = admm_ta_topologies::generate::complete(robots).unwrap();
        let contender = Contender::as_in_paper(method).unwrap_or(Contender::of(method));
        let setup = method.setup(&contender.settings()).unwrap().unwrap();
        let params = TeamParams { rho: 0.5, diameter: robots.saturating_sub(1).max(1), tolerance: 1e-9 };
        let team = setup.team(TeamContext { problem: &problem, graph: &graph, params });
        let agents: Vec<MethodAgent> = (0..robots.min(2))
            .map(|i| MethodAgent::new(team.agent(AgentInit {
                index: i,
                costs: costs.row(i).to_vec(),
                robots,
                case: problem.case(),
                degree: robots - 1,
            })))
            .collect();
        let mut payload = vec![0.0; agents[0].payload_len()];
        agents[agents.len() - 1].write_initial_payload(&mut payload);
        prop_assert_eq!(agents[0].check_payload(&payload), Ok(()));
        let k = position.index(payload.len());
        let mut nan = payload.clone();
        nan[k] = f64::NAN;
        // The distributed Hungarian marks unknown rows with NaN: a NaN there is valid, a
        // NaN in a known row is not.
        let known_row = payload[k - k % tasks].is_finite();
        if method != Method::DistHungarian || (known_row && tasks > 1) {
            prop_assert!(agents[0].check_payload(&nan).is_err());
        }
        let mut corrupt = payload.clone();
        corrupt[k] = garbage;
        let _ = agents[0].check_payload(&corrupt);
        if resize != 0 {
            let len = (payload.len() as isize + resize).max(0) as usize;
            let mut wrong = payload.clone();
            wrong.resize(len, 0.0);
            prop_assert!(agents[0].check_payload(&wrong).is_err());
        }
    }
}
