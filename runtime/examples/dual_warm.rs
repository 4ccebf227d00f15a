//! Rounds of a fast dual standing team's episodes in the lockstep sim, warm against cold:
//! the first episode's costs are seed `SEED`'s of the cost model, each next episode's the
//! last's with every cost moved by up to ±`DRIFT` (default 0.01) and clipped to the first
//! episode's range (as `bench/standing_team.py` does for uniform costs); `ROWS=file` gives
//! the episodes' matrices instead (a JSON list of row lists, the first episode's first).
//! The robots' agents are kept from episode to episode (`set_costs`, then every robot's
//! iterate sent again, as a standing team starts an episode); every episode must certify
//! the oracle's optimum. Prints each episode's rounds and how many robots' optimal tasks
//! moved since the last. `RHO_SCALE=F` multiplies the one-shot default ρ; `RHO0=shape`
//! takes a standing team's instead (its robots see no other row: spread 1, no structure
//! factor; for uniform costs about `RHO_SCALE=0.333`). `HEDGE=K`: a warm episode not
//! certified within `K` times the first (cold) episode's rounds starts again from zero
//! (its rounds count both). `bench/dual_warm_stats.py` sums runs up over seeds. Each
//! episode also prints the bytes a robot sent, as Zenoh codes the messages (against the
//! robot's last, `admm_ta_transport::exchange::codec`) and as they are.
//! `cargo run --release -p admm-ta-runtime --example dual_warm -- ROBOTS TASKS TOPOLOGY uniform|distance EPISODES SEED [ROUNDS]`.
mod common;

use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::certify::oracle;
use admm_ta_agents::method::agent::MethodAgent;
use admm_ta_agents::method::settings::GivenSettings;
use admm_ta_agents::methods::Method;
use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_topologies::Graph;
use admm_ta_topologies::rng::SeededRng;
use admm_ta_transport::exchange::codec::Coder;
use admm_ta_transport::sim::process::LockstepSim;
use common::Problems;

/// Every robot's messages as Zenoh codes them: the coders, and the bytes sent coded and as
/// they are since the last [`Wire::reset`].
struct Wire {
    coders: Vec<Coder>,
    out: Vec<u8>,
    coded: u64,
    raw: u64,
}

impl Wire {
    fn new(robots: usize, words: usize) -> Self {
        let coders = (0..robots).map(|_| Coder::new(words)).collect();
        Self {
            coders,
            out: Vec::new(),
            coded: 0,
            raw: 0,
        }
    }

    /// Every robot sends its current payload.
    fn send(&mut self, sim: &LockstepSim<MethodAgent>) {
        for (i, coder) in self.coders.iter_mut().enumerate() {
            self.out.clear();
            coder.encode(sim.payload(i), &mut self.out);
            self.coded += self.out.len() as u64;
            self.raw += 8 * sim.payload(i).len() as u64;
        }
    }

    /// The kB a robot sent, coded and as they are, since the last reset.
    fn reset(&mut self) -> (f64, f64) {
        let n = self.coders.len() as f64;
        let sent = (self.coded as f64 / n / 1e3, self.raw as f64 / n / 1e3);
        (self.coded, self.raw) = (0, 0);
        sent
    }
}

/// Runs the team to every robot's certificate; the rounds it took (None: not within
/// `max_rounds`). Panics if the certified assignment costs more than `optimum`.
fn episode(
    agents: Vec<MethodAgent>,
    wire: &mut Wire,
    graph: &Graph,
    problem: &TaskAssignmentProblem,
    optimum: f64,
    tol: f64,
    max_rounds: usize,
) -> (Vec<MethodAgent>, Option<usize>) {
    let mut sim = LockstepSim::new(agents, graph);
    wire.send(&sim);
    for round in 1..=max_rounds {
        sim.step_round();
        wire.send(&sim);
        if sim.agents().iter().all(|a| a.certificate_slack() <= tol) {
            let decisions: Vec<usize> = sim.agents().iter().map(|a| a.decide()).collect();
            assert!(
                problem.is_feasible(&decisions)
                    && problem.cost_of(&decisions).unwrap() <= optimum + 1e-9,
                "wrong certificate at round {round}"
            );
            return (sim.into_agents(), Some(round));
        }
    }
    (sim.into_agents(), None)
}

/// Every robot's row of `problem`, warm-started or from zero.
fn set_costs(agents: &mut [MethodAgent], problem: &TaskAssignmentProblem, warm: bool) {
    for (i, agent) in agents.iter_mut().enumerate() {
        agent.set_costs(problem.costs().row(i), warm).unwrap();
    }
}

/// The episodes' cost matrices: `ROWS`, or `first` drifted `episodes` times.
fn matrices(first: &CostMatrix, episodes: usize, seed: u64) -> Vec<CostMatrix> {
    if let Ok(file) = std::env::var("ROWS") {
        let rows: Vec<Vec<Vec<f64>>> =
            serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
        let (n, m) = (rows[0].len(), rows[0][0].len());
        return rows
            .iter()
            .map(|r| CostMatrix::new(n, m, r.concat()).unwrap())
            .collect();
    }
    let drift: f64 = std::env::var("DRIFT").map_or(0.01, |v| v.parse().unwrap());
    let values = first.values();
    let low = values.iter().copied().fold(f64::INFINITY, f64::min);
    let high = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut rng = SeededRng::new(seed * 7 + 1);
    let mut all = vec![first.clone()];
    for _ in 0..episodes {
        let moved = all[all.len() - 1]
            .values()
            .iter()
            .map(|v| (v + drift * (2.0 * rng.uniform() - 1.0)).clamp(low, high))
            .collect();
        all.push(CostMatrix::new(first.robots(), first.tasks(), moved).unwrap());
    }
    all
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let problems = Problems::from_args(&args);
    let episodes: usize = args[5].parse().unwrap();
    let seed: u64 = args[6].parse().unwrap();
    let max_rounds: usize = args.get(7).map_or(5000, |a| a.parse().unwrap());
    let (generated, graph) = problems.instance(seed);
    let problems: Vec<TaskAssignmentProblem> = matrices(generated.costs(), episodes, seed)
        .into_iter()
        .map(|costs| TaskAssignmentProblem::new(costs, CaseChoice::Auto).unwrap())
        .collect();
    let setup = Method::Dual.setup(&GivenSettings::default()).unwrap();
    let setup = setup.unwrap();
    let scale: f64 = std::env::var("RHO_SCALE").map_or(1.0, |v| v.parse().unwrap());
    let first = &problems[0];
    // `RHO0=shape`: the ρ₀ of a standing team of private costs, which reads nothing of the
    // rows (a matrix of their shape: spread 1, no structure factor).
    let shape;
    let costs = match std::env::var("RHO0").as_deref() {
        Ok("shape") => {
            let zeros = vec![0.0; first.costs().values().len()];
            shape = CostMatrix::new(first.robots(), first.tasks(), zeros).unwrap();
            &shape
        }
        _ => first.costs(),
    };
    let rho = setup.default_rho(costs, graph.mean_degree()).unwrap() * scale;
    let params = common::params(first, &graph, rho);
    let tol = params.tolerance / first.robots() as f64;
    // The oracle's optimum of every episode, once for the warm and the cold team.
    let optima: Vec<_> = problems.iter().map(|p| oracle::solve(p).unwrap()).collect();
    println!("ρ₀ {rho:.4e}");
    let hedge: Option<f64> = std::env::var("HEDGE").ok().map(|v| v.parse().unwrap());
    for warm in [true, false] {
        let agents = common::agents(setup.as_ref(), first, &graph, params);
        let mut wire = Wire::new(agents.len(), agents[0].payload_len());
        let w = &mut wire;
        let (mut agents, rounds) =
            episode(agents, w, &graph, first, optima[0].cost, tol, max_rounds);
        let first_rounds = rounds;
        println!(
            "{}: first episode {}",
            if warm { "warm" } else { "cold" },
            rounds.map_or("none".to_string(), |r| r.to_string())
        );
        let mut all = Vec::new();
        let mut coded = Vec::new();
        wire.reset();
        for (k, problem) in problems.iter().enumerate().skip(1) {
            set_costs(&mut agents, problem, warm);
            let optimum = optima[k].cost;
            let cap = match (warm, hedge, first_rounds) {
                (true, Some(h), Some(r)) => ((h * r as f64) as usize).max(1),
                _ => max_rounds,
            };
            let (next, mut rounds) = episode(agents, &mut wire, &graph, problem, optimum, tol, cap);
            agents = next;
            if rounds.is_none() && cap < max_rounds {
                set_costs(&mut agents, problem, false);
                let w = &mut wire;
                let (next, more) = episode(agents, w, &graph, problem, optimum, tol, max_rounds);
                agents = next;
                rounds = more.map(|r| r + cap);
            }
            let (now, before) = (&optima[k].assignment, &optima[k - 1].assignment);
            let moved = now.iter().zip(before).filter(|(a, b)| a != b).count();
            let shown = rounds.map_or("none".to_string(), |r| r.to_string());
            let (sent, raw) = wire.reset();
            println!(
                "  episode {k}: rounds {shown}, optimal tasks moved {moved}, sent {sent:.1} kB coded ({raw:.1} kB as they are)"
            );
            coded.push(sent);
            all.push(rounds.unwrap_or(max_rounds) as f64);
        }
        all.sort_by(f64::total_cmp);
        coded.sort_by(f64::total_cmp);
        if let (Some(median), Some(sent)) = (all.get(all.len() / 2), coded.get(coded.len() / 2)) {
            println!("  median {median}, sent {sent:.1} kB coded");
        }
    }
}
