//! `admm-ta collect`: the assignment of an independently started team, from its agents' results.

use crate::cli::CollectArgs;
use crate::exit::NotOptimal;
use admm_ta::runtime::process::member;
use anyhow::Result;

pub fn run(args: CollectArgs) -> Result<()> {
    let result = member::collect(&args.team, args.check).map_err(anyhow::Error::msg)?;
    if args.json {
        println!("{}", serde_json::to_string(&result)?);
    } else {
        println!(
            "team {}: assignment {:?}, cost {:.6}, {} rounds, {}{}",
            result.run,
            result.assignment,
            result.cost,
            result.iterations,
            if result.converged {
                "certified"
            } else {
                "round limit reached (not certified)"
            },
            match (result.optimal, result.optimal_cost) {
                (Some(true), _) => ", optimal".to_string(),
                (Some(false), Some(o)) => format!(", NOT optimal (optimum {o:.6})"),
                _ => String::new(),
            }
        );
        let round = result.round_latency_us.round;
        println!(
            "round latency (µs, all agents): p50 {:.1}, p90 {:.1}, p99 {:.1}, max {:.1}",
            round.p50, round.p90, round.p99, round.max
        );
    }
    if result.optimal == Some(false) {
        return Err(NotOptimal("the team's assignment is not optimal".into()).into());
    }
    Ok(())
}
