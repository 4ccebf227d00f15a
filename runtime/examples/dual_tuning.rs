//! Sweeps ρ (and γ) of the dual and inexact-dual methods: mean rounds until the robots'
//! own columns are within 0.1% of the optimum, until every robot's argmax is optimal for
//! good, and until the certificate of the decentralized stop holds at every robot:
//! `cargo run --release -p admm-ta-runtime --example dual_tuning -- ROBOTS TASKS TOPOLOGY SEEDS exact|inexact RHO_FACTOR [GAMMA_FACTOR] [SHIFT]`.
//! ρ = RHO_FACTOR / (spread · mean degree).
use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::certify::oracle;
use admm_ta_agents::methods::dual::agent::{DualAgent, DualParams, DualUpdate};
use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_topologies::TopologySpec;
use admm_ta_transport::sim::process::LockstepSim;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args[1].parse().unwrap();
    let m: usize = args[2].parse().unwrap();
    let spec: TopologySpec = args[3].parse().unwrap();
    let seeds: u64 = args[4].parse().unwrap();
    let exact = args[5] == "exact";
    let factor: f64 = args[6].parse().unwrap();
    let gamma: f64 = args.get(7).map_or(
        admm_ta_agents::methods::dual::agent::DEFAULT_GAMMA_FACTOR,
        |a| a.parse().unwrap(),
    );
    let shift: f64 = args.get(8).map_or(0.0, |a| a.parse().unwrap());
    let rel_tol: f64 = args.get(9).map_or(1e-9, |a| a.parse().unwrap());
    let max_rounds = 3000;
    let (mut within, mut assign, mut cert) = (vec![], vec![], vec![]);
    let mut fails = 0;
    for seed in 0..seeds {
        let raw = CostMatrix::uniform(n, m, seed).unwrap();
        let costs =
            CostMatrix::new(n, m, raw.values().iter().map(|v| v + shift).collect()).unwrap();
        let problem = TaskAssignmentProblem::new(costs, CaseChoice::Auto).unwrap();
        let graph = spec.build(n, seed).unwrap();
        let optimum = oracle::solve(&problem).unwrap();
        let rho = factor / (problem.costs().spread() * graph.mean_degree().max(1.0));
        let diameter = graph.diameter().unwrap();
        let agents: Vec<DualAgent> = (0..n)
            .map(|i| {
                DualAgent::new(
                    i,
                    problem.costs().row(i).to_vec(),
                    n,
                    problem.case(),
                    graph.degree(i),
                    DualParams {
                        rho,
                        update: if exact {
                            DualUpdate::Exact
                        } else {
                            DualUpdate::Inexact {
                                gamma_factor: gamma,
                            }
                        },
                        diameter,
                        tolerance: rel_tol * problem.costs().spread() * n as f64,
                    },
                )
            })
            .collect();
        let mut sim = LockstepSim::new(agents, &graph);
        let tol = rel_tol * problem.costs().spread() * n as f64;
        let (mut first_within, mut optimal_since, mut cert_at) = (None, None, None);
        for round in 1..=max_rounds {
            sim.step_round();
            let agents = sim.agents();
            let relaxed: f64 = (0..n)
                .map(|i| {
                    agents[i]
                        .own_column()
                        .iter()
                        .zip(problem.costs().row(i))
                        .map(|(x, a)| x * a)
                        .sum::<f64>()
                })
                .sum();
            if ((relaxed - optimum.cost) / optimum.cost).abs() <= 1e-3 {
                first_within.get_or_insert(round);
            }
            let decisions: Vec<usize> = agents.iter().map(|a| a.decide()).collect();
            let optimal = problem.is_feasible(&decisions)
                && problem.cost_of(&decisions).unwrap() <= optimum.cost + 1e-9;
            if optimal {
                optimal_since.get_or_insert(round);
            } else {
                optimal_since = None;
            }
            if cert_at.is_none()
                && agents
                    .iter()
                    .all(|a| a.certificate_slack() <= tol / n as f64)
            {
                cert_at = Some(round);
                if !optimal {
                    println!("seed {seed}: WRONG certificate at {round}");
                }
            }
            if cert_at.is_some() && first_within.is_some() && round > cert_at.unwrap() + 20 {
                break;
            }
        }
        match (first_within, optimal_since, cert_at) {
            (Some(w), Some(a), Some(c)) => {
                within.push(w as f64);
                assign.push(a as f64);
                cert.push(c as f64);
            }
            _ => {
                fails += 1;
                println!(
                    "seed {seed}: within {first_within:?} assign {optimal_since:?} cert {cert_at:?}"
                );
            }
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    println!(
        "{} ρ-factor {factor} γ-factor {gamma}: within0.1% {:.1}  assign {:.1}  certified {:.1}  fails {fails}/{seeds}",
        if exact { "exact" } else { "inexact" },
        mean(&within),
        mean(&assign),
        mean(&cert)
    );
}
