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

/// Serves robot `id` over ROS 2 topics.
#[cfg(feature = "ros2")]
fn serve_ros2(
    team: &std::path::Path,
    id: usize,
    namespace: Option<&str>,
) -> Result<Result<(), crate::runtime::process::member_error::MemberError>> {
    Ok(crate::runtime::standing::ros2::serve_ros2(team, id, namespace).map(|_| ()))
}

/// Without the feature, `--ros2` is a usage error that says how to get it.
#[cfg(not(feature = "ros2"))]
fn serve_ros2(
    _team: &std::path::Path,
    _id: usize,
    _namespace: Option<&str>,
) -> Result<Result<(), crate::runtime::process::member_error::MemberError>> {
    usage_bail!("--ros2: this admm-ta was built without ROS 2 (build it with --features ros2)")
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
            ros2: true,
            ros2_namespace,
            ..
        } => {
            let id = robot_number(&team, robot)?;
            (id, serve_ros2(&team, id, ros2_namespace.as_deref())?)
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
            ros2: false,
            ros2_namespace: None,
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
