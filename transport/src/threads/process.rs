//! Where the `threads` transport's agents run: each in a thread of the calling process,
//! spawned and joined here.

use crate::exchange::round_loop::{AgentOutcome, AgentPlan, run_agent};
use crate::exchange::{Exchange, ExchangeError, root_cause};
use crate::threads::exchange::{Fabric, ThreadExchange};
use crate::wait::{WaitPolicy, WaitStrategy};
use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_topologies::Graph;
use crossbeam::sync::Parker;

/// Runs every agent in its own thread, waiting by `wait`, until the stop protocol or the
/// round limit ends the run; `plans[i]` is agent `i`'s. Returns the outcomes in agent order,
/// or the first failure (the other agents then stop at once).
pub fn run_threads_waiting<A: ConsensusAgent + Send>(
    agents: &mut [A],
    graph: &Graph,
    plans: &[AgentPlan],
    wait: WaitStrategy,
) -> Result<Vec<AgentOutcome>, ExchangeError> {
    run_threads_with(agents, graph, plans, wait, &|agent, exchange, plan| {
        run_agent(agent, exchange, plan)
    })
}

/// What an agent thread runs: the round loop, or a longer life such as repeated episodes.
pub type AgentBody<'b, A, T> =
    &'b (dyn Fn(&mut A, &mut dyn Exchange, &AgentPlan) -> Result<T, ExchangeError> + Sync);

/// Runs `body` for every agent in its own thread over the threads transport (the round
/// loop of [`run_agent`], or a longer life such as repeated episodes).
pub fn run_threads_with<A: ConsensusAgent + Send, T: Send>(
    agents: &mut [A],
    graph: &Graph,
    plans: &[AgentPlan],
    wait: WaitStrategy,
    body: AgentBody<'_, A, T>,
) -> Result<Vec<T>, ExchangeError> {
    let n = agents.len();
    assert_eq!(n, graph.robots(), "one agent per robot");
    assert_eq!(n, plans.len(), "one plan per agent");
    let len = agents.first().map_or(0, |a| a.payload_len());
    let parkers: Vec<Parker> = (0..n).map(|_| Parker::new()).collect();
    let fabric = Fabric::new(
        graph,
        len,
        parkers.iter().map(|p| p.unparker().clone()).collect(),
    );
    let policy = WaitPolicy::new(wait, n);
    let results: Vec<Result<T, ExchangeError>> = std::thread::scope(|scope| {
        let fabric = &fabric;
        let handles: Vec<_> = agents
            .iter_mut()
            .zip(parkers)
            .zip(plans)
            .enumerate()
            .map(|(index, ((agent, parker), plan))| {
                std::thread::Builder::new()
                    .name(format!("agent-{index}"))
                    .spawn_scoped(scope, move || {
                        let mut exchange = ThreadExchange::new(fabric, index, parker, policy);
                        let result = body(agent, &mut exchange, plan);
                        if result.is_err() {
                            fabric.abort();
                        }
                        result
                    })
                    .expect("spawning an agent thread")
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("agent thread panicked"))
            .collect()
    });
    let mut outcomes = Vec::with_capacity(n);
    let mut errors = Vec::new();
    for result in results {
        match result {
            Ok(outcome) => outcomes.push(outcome),
            Err(e) => errors.push(e),
        }
    }
    match root_cause(errors) {
        Some(e) => Err(e),
        None => Ok(outcomes),
    }
}
