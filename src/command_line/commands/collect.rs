//! `admm-ta collect`: the assignment of an independently started team, from its agents' results.

use crate::command_line::cli::CollectArgs;
use crate::command_line::exit::{NotOptimal, Outcome};
use crate::command_line::output::outln;
use crate::runtime::team::collect;
use anyhow::Result;

/// Prints the team's assignment. Ends as `solve` does: with `--check` the centralized
/// optimum decides (6 when not optimal); otherwise a team stopped by the round limit before
/// any certificate is [`Outcome::Uncertified`] (5). A CBAA team that completed its protocol
/// ends with 0, as `solve` does, while its text and JSON say it is not certified optimal.
pub fn run(args: CollectArgs) -> Result<Outcome> {
    // A bad team file, missing results or results of another team: bad input (2).
    let result = collect::collect(&args.team, args.check)?;
    if args.json {
        outln!("{}", serde_json::to_string(&result)?);
    } else {
        outln!(
            "team {}: assignment {:?}, {} {:.6}{}, {} rounds, {}{}",
            result.run,
            result.assignment,
            if result.maximize { "profit" } else { "cost" },
            result.cost,
            if result.repaired {
                " (robots' choices conflicted and were repaired)"
            } else {
                ""
            },
            result.iterations,
            match (result.certified, result.converged) {
                (true, _) => "certified optimal",
                (false, true) => "NOT certified optimal (CBAA is a heuristic)",
                (false, false) => "round limit reached: NOT certified optimal",
            },
            match (result.optimal, result.optimal_cost) {
                (Some(true), _) => ", optimal".to_string(),
                (Some(false), Some(o)) => format!(", NOT optimal (optimum {o:.6})"),
                _ => String::new(),
            }
        );
        if let (Some(path), Some(critical)) = (&result.timeline, &result.critical_path) {
            outln!(
                "timeline written to {}; critical path: {:.1}% of the agents' round time went to waiting for a late neighbour{}",
                path.display(),
                100.0 * critical.waiting_share,
                critical.top.first().map_or(String::new(), |a| format!(
                    ", most for agent {} ({:.1}%)",
                    a.agent,
                    100.0 * a.waiting_share
                ))
            );
            if let Some(clocks) = &result.host_clocks {
                outln!(
                    "clocks: {}",
                    crate::runtime::team::team_timeline::clock_note(clocks)
                );
            }
        }
        let round = result.round_latency_us.round;
        outln!(
            "round latency (µs, all agents): p50 {:.1}, p90 {:.1}, p99 {:.1}, max {:.1}",
            round.p50,
            round.p90,
            round.p99,
            round.max
        );
    }
    match result.optimal {
        Some(false) => Err(NotOptimal("the team's assignment is not optimal".into()).into()),
        Some(true) => Ok(Outcome::Success),
        None if !result.converged => Ok(Outcome::Uncertified),
        None => Ok(Outcome::Success),
    }
}
