//! A standing team in one process, every robot a thread of the `threads` transport (for
//! benchmarks and simulations): the same episodes as the sidecars', each robot's row from
//! its own call of a row source, and its answers back.
//!
//! ```
//! use admm_ta_runtime::standing::one_process::{Input, run_on_threads};
//! use admm_ta_runtime::team::team_file::Team;
//! let dir = std::env::temp_dir().join(format!("standing-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir).unwrap();
//! let path = dir.join("team.toml");
//! std::fs::write(&path, "run = \"doc\"\nrobots = 4\ntasks = 4\ncosts = \"private\"\ntopology = \"ring\"\n").unwrap();
//! let team = Team::read(&path).unwrap();
//! let costs = [[4.0, 1.0, 3.0, 2.0], [2.0, 0.0, 5.0, 3.0], [3.0, 2.0, 2.0, 1.0], [1.0, 4.0, 2.0, 5.0]];
//! let answers = run_on_threads(&team, 2, &|_episode, robot| {
//!     Input::Row(costs[robot].iter().map(|&c| Some(c)).collect())
//! })
//! .unwrap();
//! assert!(answers.iter().all(|robot| robot.iter().all(|a| a.certified)));
//! assert_eq!(answers[0][1].total_cost, Some(5.0));
//! std::fs::remove_dir_all(&dir).unwrap();
//! ```

use crate::process::member_error::MemberError;
use crate::standing::agreement::{Participation, RosterNews};
use crate::standing::answer::{Answer, check_row};
use crate::standing::episode::{EpisodeError, Episodes, Settings};
use crate::standing::roster::Roster;
use crate::team::errors::{PrivateTeamError, TeamFileError};
use crate::team::membership::team_scenario;
use crate::team::team_file::Team;
use admm_ta_agents::methods::probe::{ProbeAgent, ProbeStep};
use admm_ta_transport::exchange::ExchangeError;
use std::time::Instant;

/// What a robot gives in an episode.
#[derive(Debug, Clone, PartialEq)]
pub enum Input {
    /// Its row (`None`: a task it may not take).
    Row(Vec<Option<f64>>),
    /// It takes no task this episode and relays.
    Unavailable,
    /// It has no row this episode (the team file's `on_failure` decides).
    Missing,
}

/// Runs `episodes` episodes of the private team in `team` on threads; `rows(episode, robot)`
/// is robot `robot`'s input of an episode (called on its thread). Per robot, its answers.
pub fn run_on_threads(
    team: &Team,
    episodes: u64,
    rows: &(dyn Fn(u64, usize) -> Input + Sync),
) -> Result<Vec<Vec<Answer>>, MemberError> {
    if !team.is_private() {
        return Err(MemberError::refused(TeamFileError::Private(
            PrivateTeamError::NotPrivate,
        )));
    }
    let scenario = team_scenario(team).map_err(MemberError::refused)?;
    let options = team.solve_options().map_err(MemberError::refused)?;
    let graph = scenario.graph().map_err(MemberError::refused)?;
    let n = scenario.robots;
    let plans = (0..n)
        .map(|i| scenario.plan(i))
        .collect::<Result<Vec<_>, _>>()
        .map_err(MemberError::refused)?;
    let payload_len = scenario.payload_len();
    // Stand-ins that size the messages: each thread runs its robot's episodes.
    let mut slots: Vec<ProbeAgent> = (0..n)
        .map(|i| ProbeAgent::new(i, payload_len, ProbeStep::Touch))
        .collect();
    let failure = std::sync::Mutex::new(None);
    let body = |_: &mut ProbeAgent,
                exchange: &mut dyn admm_ta_transport::exchange::Exchange,
                plan: &admm_ta_transport::exchange::round_loop::AgentPlan|
     -> Result<Vec<Answer>, ExchangeError> {
        let id = plan.index;
        let settings = Settings::new(team, id, &scenario, options.clone(), graph.clone());
        let mut robot = Episodes::new(settings, Roster::all(n), plan.clone(), payload_len);
        let mut answers = Vec::with_capacity(episodes as usize);
        for episode in 0..episodes {
            let input = rows(episode, id);
            if let Input::Row(row) = &input
                && let Err(e) = check_row(row, scenario.tasks)
            {
                let text = format!("robot {id}, episode {episode}: {e}");
                *failure.lock().unwrap_or_else(|p| p.into_inner()) = Some(MemberError::refused(e));
                return Err(ExchangeError::Transport {
                    agent: id,
                    what: text,
                });
            }
            let began = Instant::now();
            let (row, part) = match &input {
                Input::Row(row) => (Some(row.as_slice()), Participation::Row { len: row.len() }),
                Input::Unavailable => (None, Participation::Unavailable),
                Input::Missing => (None, Participation::Missing),
            };
            let outcome = match robot.run(exchange, row, part, &[]) {
                Ok(outcome) => outcome,
                Err(EpisodeError::Exchange(e)) => return Err(e),
                Err(e) => {
                    let text = e.to_string();
                    *failure.lock().unwrap_or_else(|p| p.into_inner()) =
                        Some(MemberError::failed(e));
                    return Err(ExchangeError::Transport {
                        agent: id,
                        what: text,
                    });
                }
            };
            answers.push(outcome.answer(episode, id, row, began.elapsed(), RosterNews::default()));
        }
        Ok(answers)
    };
    let ran = admm_ta_transport::threads::process::run_threads_with(
        &mut slots,
        &graph,
        &plans,
        options.run().wait(),
        &body,
    );
    if let Some(e) = failure.into_inner().unwrap_or_else(|p| p.into_inner()) {
        return Err(e);
    }
    ran.map_err(MemberError::failed)
}
