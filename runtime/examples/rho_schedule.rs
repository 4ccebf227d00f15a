//! Explores ρ schedules `ρ_k = ρ_0 · g^k`, bounded by `limit` (a cap when g > 1, a floor
//! when g < 1), against the fixed default:
//! `cargo run --release -p admm-ta-runtime --example rho_schedule -- ROBOTS TASKS TOPOLOGY SEEDS GROWTH LIMIT`.
use admm_ta_agents::certify::oracle;
use admm_ta_agents::certify::rounding::argmax_assignment;
use admm_ta_agents::methods::primal::agent::PrimalParams;
use admm_ta_agents::methods::primal::team_agents;
use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_topologies::TopologySpec;
use admm_ta_transport::sim::process::LockstepSim;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args[1].parse().unwrap();
    let m: usize = args[2].parse().unwrap();
    let spec: TopologySpec = args[3].parse().unwrap();
    let seeds: u64 = args[4].parse().unwrap();
    let growth: f64 = args[5].parse().unwrap();
    let limit: f64 = args[6].parse().unwrap();
    let max_rounds = 2000;
    let (mut total, mut reached, mut integral_total, mut integral_reached) = (0, 0, 0, 0);
    for seed in 0..seeds {
        let problem =
            TaskAssignmentProblem::new(CostMatrix::uniform(n, m, seed).unwrap(), CaseChoice::Auto)
                .unwrap();
        let graph = spec.build(n, seed).unwrap();
        let optimum = oracle::solve(&problem).unwrap();
        let rho0 = admm_ta_agents::methods::rho::default_rho(problem.costs(), graph.mean_degree());
        let agents = team_agents(&problem, &graph, PrimalParams::new(rho0), None, seed);
        let mut sim = LockstepSim::new(agents, &graph);
        let mut decisions = vec![0; n];
        let (mut optimal_since, mut integral_at) = (None, None);
        for round in 1..=max_rounds {
            let factor = growth.powi(round);
            let rho = rho0
                * if growth >= 1.0 {
                    factor.min(limit)
                } else {
                    factor.max(limit)
                };
            sim.agents_mut().iter_mut().for_each(|a| a.set_rho(rho));
            let gap = sim
                .step_round()
                .iter()
                .map(|r| r.integrality_gap)
                .fold(0.0, f64::max);
            for i in 0..n {
                argmax_assignment(
                    &sim.payload(i)[i * m..(i + 1) * m],
                    m,
                    &mut decisions[i..i + 1],
                );
            }
            let optimal = problem.is_feasible(&decisions)
                && problem.cost_of(&decisions).unwrap() <= optimum.cost + 1e-9;
            if optimal {
                optimal_since.get_or_insert(round);
            } else {
                optimal_since = None;
            }
            if gap <= 0.2 && integral_at.is_none() {
                integral_at = Some((round, optimal));
            }
        }
        if let Some(r) = optimal_since {
            total += r;
            reached += 1;
        }
        if let Some((r, ok)) = integral_at {
            integral_total += r;
            integral_reached += 1;
            if !ok {
                println!("seed {seed}: integral at a wrong assignment");
            }
        }
    }
    println!(
        "{n}x{m} {spec:?} growth {growth} limit {limit}: optimal from {:.1} ({reached}/{seeds}), all within 0.2 of integral at {:.1} ({integral_reached}/{seeds})",
        total as f64 / reached.max(1) as f64,
        integral_total as f64 / integral_reached.max(1) as f64
    );
}
