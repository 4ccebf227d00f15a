//! `admm-ta collect --team FILE`: the assignment of an independently started team,
//! assembled from its agents' results (checked for being one team's, complete and feasible),
//! and the team's timeline when its agents recorded one.

use crate::process::agent::{AgentReport, result_path};
use crate::process::team_digest::TeamDigest;
use crate::team::errors::{CollectError, PrivateTeamError, TeamFileError};
use crate::team::membership::team_scenario;
use crate::team::team_file::Team;
use crate::team::team_timeline::write_timeline;
use admm_ta_agents::certify::stopping::StopRule;
use admm_ta_agents::certify::{oracle, rounding};
use admm_ta_transport::exchange::round_loop::merge_outcomes;
use admm_ta_transport::latency::LatencySummary;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The team's assignment, assembled from the agents' results.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TeamResult {
    pub run: String,
    pub assignment: Vec<usize>,
    /// The assignment's total in the user's numbers (a profit with `maximize`).
    pub cost: f64,
    /// The team file's `maximize`: `cost` is a profit.
    pub maximize: bool,
    /// The agents' choices conflicted (the round limit stopped them) and were repaired.
    pub repaired: bool,
    /// The method proved the assignment optimal: every agent certified the same round
    /// (CBAA, a heuristic, never does).
    pub certified: bool,
    /// Rounds every agent ran.
    pub iterations: u64,
    /// Every agent certified the same round.
    pub converged: bool,
    pub certified_round: Option<u64>,
    /// With `check`: the centralized optimum and whether the team found it.
    pub optimal_cost: Option<f64>,
    pub optimal: Option<bool>,
    /// Round latency over all agents' rounds (µs), on whatever carried the messages.
    pub round_latency_us: LatencySummary,
    /// The team file's `timeline`: whom the team waited for, round by round.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub critical_path: Option<admm_ta_transport::timeline::CriticalPath>,
    /// A team across hosts with a timeline: every host's clock offset to the first host's,
    /// estimated from the round messages ([`admm_ta_transport::timeline::clocks`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub host_clocks: Option<Vec<crate::team::team_timeline::NamedHostClock>>,
    /// Where the timeline was written (Chrome trace JSON).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timeline: Option<PathBuf>,
}

/// Every agent's result in the team's results directory, each checked to be that agent's of
/// this team (its `digest`).
fn read_results(team: &Team, digest: &str) -> Result<Vec<AgentReport>, CollectError> {
    let n = team.file.robots;
    let results = team.results_dir();
    let mut reports = Vec::with_capacity(n);
    let mut missing = Vec::new();
    for id in 0..n {
        let path = result_path(&results, id);
        match std::fs::read_to_string(&path) {
            Ok(text) => reports.push(serde_json::from_str::<AgentReport>(&text).map_err(
                |source| CollectError::NotAResult {
                    path: path.clone(),
                    source,
                },
            )?),
            Err(_) => missing.push(id),
        }
    }
    if !missing.is_empty() {
        return Err(CollectError::Missing {
            missing,
            dir: results,
        });
    }
    if let Some((id, report)) = reports
        .iter()
        .enumerate()
        .find(|(id, r)| r.outcome.index != *id)
    {
        return Err(CollectError::WrongAgent {
            path: result_path(&results, id),
            found: report.outcome.index,
            id,
        });
    }
    if let Some(id) = reports
        .iter()
        .position(|r| r.team.as_deref() != Some(digest))
    {
        return Err(CollectError::OtherTeam {
            path: result_path(&results, id),
        });
    }
    Ok(reports)
}

/// Reads every agent's result and checks they describe one feasible assignment.
pub fn collect(team_path: &Path, check: bool) -> Result<TeamResult, CollectError> {
    let team = Team::read(team_path)?;
    if team.is_private() {
        return Err(TeamFileError::Private(PrivateTeamError::NothingToCollect).into());
    }
    let (problem, graph) = team.problem_and_graph()?;
    let digest = TeamDigest::of(&team_scenario(&team)?).to_hex();
    let reports = read_results(&team, &digest)?;
    let rounds: Vec<u64> = reports.iter().map(|r| r.outcome.rounds).collect();
    let certified: Vec<Option<u64>> = reports.iter().map(|r| r.outcome.certified_round).collect();
    if rounds.iter().any(|&r| r != rounds[0]) || certified.iter().any(|c| *c != certified[0]) {
        return Err(CollectError::DifferentRuns {
            dir: team.results_dir(),
            rounds,
        });
    }
    let (latency, _) = merge_outcomes(reports.iter().map(|r| &r.outcome)).map_err(|e| {
        CollectError::Unreadable {
            agent: e.agent,
            source: e.source,
        }
    })?;
    let internal: Vec<usize> = reports.iter().map(|r| r.outcome.task).collect();
    let decisions = problem.from_internal(&internal);
    let (assignment, repaired) = if problem.is_feasible(&decisions) {
        (decisions, false)
    } else if certified[0].is_none() {
        // The round limit stopped the team before its choices agreed: the feasible
        // assignment that changes the fewest robots, as `solve` reports (uncertified).
        rounding::repair(&problem, &decisions)
    } else {
        return Err(CollectError::Infeasible(decisions));
    };
    let cost = problem.cost_of(&assignment)?;
    let timelines = reports.iter().map(|r| r.outcome.timeline.clone()).collect();
    let (timeline, critical_path, host_clocks) = write_timeline(&team, &graph, timelines)?;
    let optimum = if check {
        Some(oracle::solve(&problem)?.cost)
    } else {
        None
    };
    Ok(TeamResult {
        run: team.file.run.clone(),
        assignment,
        cost,
        maximize: team.file.maximize,
        repaired,
        certified: team
            .file
            .method
            .info()
            .certification
            .certifies(certified[0].is_some(), StopRule::Local),
        iterations: rounds[0],
        converged: certified[0].is_some(),
        certified_round: certified[0],
        optimal_cost: optimum,
        optimal: optimum.map(|o| (cost - o).abs() <= 1e-9 * o.abs().max(1.0)),
        round_latency_us: latency.summary(),
        critical_path,
        host_clocks,
        timeline,
    })
}
