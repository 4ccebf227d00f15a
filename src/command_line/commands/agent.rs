//! `admm-ta agent`: one agent process, of an independently started team or of a launcher's run.

use crate::agents::problem::ProblemError;
use crate::command_line::cli::AgentArgs;
use crate::command_line::exit::{Outcome, usage_bail};
use crate::command_line::output::outln;
use crate::runtime::process::agent;
use crate::runtime::standing::serve;
use crate::runtime::team::membership;
use crate::runtime::team::team_file::Team;
use crate::topologies::RobotRef;
use anyhow::{Context, Result};

/// The number of robot `robot` of the team in `team` (a name looked up in its cost file).
fn robot_number(team: &std::path::Path, robot: RobotRef) -> Result<usize> {
    Ok(match robot {
        RobotRef::Index(id) => id,
        named => Team::read(team)
            .and_then(|t| t.robot(&named))
            .with_context(|| format!("agent {named}"))?,
    })
}

/// Runs the agent. An independently started agent whose team reached the round limit before
/// any certificate ends with [`Outcome::Uncertified`] (5), as `solve` and `collect` do; an
/// agent of a launcher's run leaves that to the launcher.
pub fn run(args: AgentArgs) -> Result<Outcome> {
    let mut outcome = Outcome::Success;
    let (index, result) = match args {
        AgentArgs {
            team: Some(team),
            robot: Some(robot),
            serve: true,
            ..
        } => {
            let id = robot_number(&team, robot)?;
            let stdin = std::io::BufReader::new(std::io::stdin());
            let served = serve::serve(&team, id, stdin, &mut std::io::stdout());
            (id, served.map(|_| ()))
        }
        AgentArgs {
            team: Some(team),
            robot: Some(robot),
            row: Some(row),
            ..
        } => {
            let id = robot_number(&team, robot)?;
            let answer = serve::one_episode(&team, id, &row);
            if let Ok(a) = &answer {
                outln!("{}", serde_json::to_string(a)?);
                if !a.feasible {
                    return Err(anyhow::Error::from(ProblemError::Infeasible(
                        a.unsolved.clone().unwrap_or_default(),
                    )));
                }
                if !a.certified {
                    outcome = Outcome::Uncertified;
                }
            }
            (id, answer.map(|_| ()))
        }
        AgentArgs {
            team: Some(team),
            robot: Some(robot),
            ..
        } => {
            let id = robot_number(&team, robot)?;
            let report = membership::run_member(&team, id);
            if let Ok(r) = &report {
                if !r.outcome.converged {
                    outcome = Outcome::Uncertified;
                }
                outln!(
                    "{}",
                    serde_json::json!({
                        "id": id,
                        "task": r.outcome.task,
                        "rounds": r.outcome.rounds,
                        "converged": r.outcome.converged,
                    })
                );
            }
            (id, report.map(|_| ()))
        }
        AgentArgs {
            team: None,
            robot: Some(robot),
            run: Some(run),
            scenario: Some(scenario),
            scenario_digest: Some(digest),
            serve: false,
            row: None,
        } => {
            let RobotRef::Index(index) = robot else {
                usage_bail!(
                    "--robot: an agent of a launcher's run is given its number, not a name"
                );
            };
            (index, agent::run(&run, index, &scenario, &digest))
        }
        _ => usage_bail!("agent needs --team FILE --robot I (or --run, --robot and --scenario)"),
    };
    result.map(|()| outcome).map_err(|e| {
        // Exchange errors already start with "agent N:".
        let text = e.text();
        if text.starts_with(&format!("agent {index}:"))
            || text.starts_with(&format!("agent {index}'s"))
        {
            anyhow::Error::from(e)
        } else {
            anyhow::Error::from(e.prefixed(&format!("agent {index}: ")))
        }
    })
}
