//! Where the dual methods' rounds go: per seed, the first round from which the robots'
//! rounded tasks stay optimal, the neighbours' largest disagreement at that point, and the
//! round every robot's certificate holds. `RHO_SCALE=F` multiplies the default ρ,
//! `VARIANT=paper` runs the paper variant, `GAMMA=G` sets the inexact dual's γ factor,
//! `SCHED=start,rate,min,max` adds an `--adaptive-rho`-style schedule on top (its ρ is the
//! fast variant's `ρ₀`), `STAT=1` prints the costs' median gap between each robot's two
//! cheapest tasks, `TRACE=1` prints every 25th (`EVERY=K`: every K-th) round why the
//! certificate does not hold yet, how many robots hold a task other than the optimum's
//! (`wrong`) and how many a column whose largest entry is below 0.99 (`fractional`), and
//! `FRAC=R` lists, from round R on at each traced round, every fractional robot's three
//! largest entries, its optimal task and its decision; the trace also counts the *pieces*
//! of the decisions' difference from the optimum (how many are cycles, and the robots of
//! the largest). `DUMP=DIR` writes each seed's costs
//! to `DIR/costs-ROBOTS-SEED.csv` (for `bench/margins.py`'s `margin`).
//! `cargo run --release -p admm-ta-runtime --example dual_anatomy -- ROBOTS TASKS TOPOLOGY uniform|distance SEEDS exact|inexact [ROUNDS]`.
mod common;

use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::certify::oracle;
use admm_ta_agents::method::settings::{GivenSettings, SettingValue};
use admm_ta_agents::methods::Method;
use admm_ta_agents::methods::dual::VARIANT;
use admm_ta_transport::sim::process::LockstepSim;
use common::Problems;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let problems = Problems::from_args(&args);
    let n = problems.robots;
    let seeds: u64 = args[5].parse().unwrap();
    let method = if args[6] == "exact" {
        Method::Dual
    } else {
        Method::InexactDual
    };
    let max_rounds: usize = args.get(7).map_or(5000, |a| a.parse().unwrap());
    let mut certified = Vec::new();
    let mut settled = Vec::new();
    for seed in 1..=seeds {
        let (problem, graph) = problems.instance(seed);
        if std::env::var("STAT").is_ok() {
            let c = problem.costs();
            let mut gaps: Vec<f64> = (0..n)
                .map(|i| {
                    let mut row = c.row(i).to_vec();
                    row.sort_by(f64::total_cmp);
                    (row[1] - row[0]) / c.spread()
                })
                .collect();
            gaps.sort_by(f64::total_cmp);
            println!(
                "seed {seed}: median gap {:.4} mean gap {:.4}",
                gaps[n / 2],
                gaps.iter().sum::<f64>() / n as f64
            );
        }
        if let Ok(dir) = std::env::var("DUMP") {
            let c = problem.costs();
            let rows: Vec<String> = (0..n)
                .map(|i| {
                    c.row(i)
                        .iter()
                        .map(|v| format!("{v:e}"))
                        .collect::<Vec<_>>()
                        .join(",")
                })
                .collect();
            std::fs::write(format!("{dir}/costs-{n}-{seed}.csv"), rows.join("\n")).unwrap();
        }
        let optimum = oracle::solve(&problem).unwrap();
        let given = match std::env::var("VARIANT") {
            Ok(variant) => GivenSettings::default().set(&VARIANT, SettingValue::Name(variant)),
            Err(_) => GivenSettings::default(),
        };
        let given = match std::env::var("GAMMA") {
            Ok(g) => given.set(
                &admm_ta_agents::methods::dual::GAMMA_FACTOR,
                SettingValue::Number(g.parse().unwrap()),
            ),
            Err(_) => given,
        };
        let setup = method.setup(&given).unwrap().unwrap();
        let rho = setup
            .default_rho(problem.costs(), graph.mean_degree())
            .unwrap()
            * std::env::var("RHO_SCALE").map_or(1.0, |v| v.parse().unwrap());
        let params = common::params(&problem, &graph, rho);
        let schedule = std::env::var("SCHED").ok().map(|v| {
            let f: Vec<f64> = v.split(',').map(|x| x.parse().unwrap()).collect();
            admm_ta_agents::methods::rho::RhoSchedule {
                initial: rho,
                start: f[0],
                rate: f[1],
                min: f[2],
                max: f[3],
            }
        });
        let agents: Vec<_> = common::agents(setup.as_ref(), &problem, &graph, params)
            .into_iter()
            .map(|agent| agent.with_schedule(schedule))
            .collect();
        let mut sim = LockstepSim::new(agents, &graph);
        let tol = params.tolerance / n as f64;
        let trace = std::env::var("TRACE").is_ok();
        let every: usize =
            std::env::var("EVERY").map_or(25, |v| v.parse::<usize>().unwrap().max(1));
        let list_from: Option<usize> = std::env::var("FRAC").ok().map(|v| v.parse().unwrap());
        // The largest entry of a robot's column: below 0.99 it is fractional.
        let largest = |col: &[f64]| col.iter().fold(0.0, |m: f64, &v| m.max(v));
        let (mut since, mut cert_at) = (None, None);
        let mut at_settle = (0.0, 0.0);
        for round in 1..=max_rounds {
            let reports = sim.step_round().to_vec();
            let agents = sim.agents();
            let decisions: Vec<usize> = agents.iter().map(|a| a.decide()).collect();
            let optimal = problem.is_feasible(&decisions)
                && problem.cost_of(&decisions).unwrap() <= optimum.cost + 1e-9;
            let disagreement = reports.iter().map(|r| r.disagreement).fold(0.0, f64::max);
            if optimal {
                if since.is_none() {
                    since = Some(round);
                    at_settle = (disagreement, 0.0);
                }
            } else {
                since = None;
            }
            if trace && round % every == 0 {
                let inf = agents
                    .iter()
                    .filter(|a| a.certificate_slack().is_infinite())
                    .count();
                let big = agents
                    .iter()
                    .filter(|a| a.certificate_slack().is_finite() && a.certificate_slack() > tol)
                    .count();
                let worst = agents
                    .iter()
                    .map(|a| a.certificate_slack())
                    .filter(|s| s.is_finite())
                    .fold(0.0, f64::max);
                let wrong = decisions
                    .iter()
                    .zip(&optimum.assignment)
                    .filter(|(a, b)| a != b)
                    .count();
                let fractional = agents
                    .iter()
                    .filter(|a| largest(a.own_column()) < 0.99)
                    .count();
                if list_from.is_some_and(|from| from <= round) {
                    for (i, a) in agents.iter().enumerate() {
                        let col = a.own_column();
                        if largest(col) < 0.99 {
                            let mut idx: Vec<usize> = (0..col.len()).collect();
                            idx.sort_by(|&x, &y| col[y].total_cmp(&col[x]));
                            let largest: Vec<String> = idx
                                .iter()
                                .take(3)
                                .map(|&t| format!("{t}:{:.3}", col[t]))
                                .collect();
                            println!(
                                "    robot {i}: {} optimal {} decided {}",
                                largest.join(" "),
                                optimum.assignment[i],
                                decisions[i]
                            );
                        }
                    }
                }
                let (apart, cycles) = exchanges(&decisions, &optimum.assignment);
                println!(
                    "  round {round}: wrong {wrong} fractional {fractional} optimal {optimal} infeasible {inf} price-slack {big} worst {worst:.2e} tol {tol:.1e} dis {disagreement:.1e} pieces {} cycles {cycles} largest {:?}",
                    apart.len(),
                    &apart[..apart.len().min(5)]
                );
            }
            if cert_at.is_none() && agents.iter().all(|a| a.certificate_slack() <= tol) {
                cert_at = Some(round);
                if !optimal {
                    println!("seed {seed}: WRONG certificate at {round}");
                }
                break;
            }
        }
        println!(
            "seed {seed}: optimal from {since:?} (disagreement then {:.2e}), certified {cert_at:?}",
            at_settle.0
        );
        certified.push(cert_at.unwrap_or(max_rounds) as f64);
        settled.push(since.unwrap_or(max_rounds) as f64);
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "median: optimal from {}, certified {}",
        median(&mut settled),
        median(&mut certified)
    );
}

/// How the decisions differ from the optimum: the robots of each connected piece of the
/// difference (robots and tasks joined by the robots' decided and optimal tasks), largest
/// first, and how many pieces are cycles (as many tasks as robots: an exchange of tasks
/// among its robots; the others are chains that end at a task claimed twice). The cycle
/// count means that in Case 1 only: in Case 2 robots share tasks.
fn exchanges(decisions: &[usize], optimal: &[usize]) -> (Vec<usize>, usize) {
    let robots = decisions.len();
    let tasks = optimal.iter().chain(decisions).max().map_or(0, |t| t + 1);
    let mut parent: Vec<usize> = (0..robots + tasks).collect();
    fn root(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    let wrong: Vec<usize> = (0..robots)
        .filter(|&i| decisions[i] != optimal[i])
        .collect();
    for &i in &wrong {
        for task in [decisions[i], optimal[i]] {
            let (a, b) = (root(&mut parent, i), root(&mut parent, robots + task));
            parent[a] = b;
        }
    }
    // Per piece: its robots and its tasks.
    let mut pieces = std::collections::HashMap::new();
    for &i in &wrong {
        pieces.entry(root(&mut parent, i)).or_insert((0, 0)).0 += 1;
    }
    let mut seen = vec![false; tasks];
    for &i in &wrong {
        for task in [decisions[i], optimal[i]] {
            if !std::mem::replace(&mut seen[task], true) {
                pieces.get_mut(&root(&mut parent, robots + task)).unwrap().1 += 1;
            }
        }
    }
    let cycles = pieces.values().filter(|(r, t)| r == t).count();
    let mut sizes: Vec<usize> = pieces.into_values().map(|(r, _)| r).collect();
    sizes.sort_unstable_by(|a, b| b.cmp(a));
    (sizes, cycles)
}
