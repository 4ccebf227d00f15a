//! Measures candidate stop rules against the oracle on many seeded instances:
//! `cargo run --release -p admm-ta-runtime --example stop_rules -- ROBOTS TASKS TOPOLOGY SEEDS [RHO_MULTIPLIER] [MAX_ROUNDS]
//! (the multiplier scales the default ρ rule)`.
use admm_ta_agents::certify::oracle;
use admm_ta_agents::certify::rounding::argmax_assignment;
use admm_ta_agents::certify::stopping::NeverStop;
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
    let factor: f64 = args.get(5).map_or(1.0, |f| f.parse().unwrap());
    let max_rounds: usize = args.get(6).map_or(3000, |r| r.parse().unwrap());
    let taus = [0.05, 0.1, 0.2, 0.3];
    let k = 10;
    let mut rows = Vec::new();
    for seed in 0..seeds {
        let problem =
            TaskAssignmentProblem::new(CostMatrix::uniform(n, m, seed).unwrap(), CaseChoice::Auto)
                .unwrap();
        let graph = spec.build(n, seed).unwrap();
        let optimum = oracle::solve(&problem).unwrap();
        let rho =
            factor * problem.costs().spread() / (2.0 * graph.mean_degree().max(1.0) * n as f64);
        let agents = team_agents(&problem, &graph, PrimalParams::new(rho), None, seed);
        let mut sim = LockstepSim::new(agents, &graph);
        // per rule (all-entries τ, own-column τ): streak, stop round, stop optimal
        let mut streak = vec![[0usize; 2]; taus.len()];
        let mut stop: Vec<[Option<(usize, bool)>; 2]> = vec![[None, None]; taus.len()];
        let mut optimal_since = None;
        let mut first_within = None;
        let mut decisions = vec![0; n];
        let mut agreed = vec![0; n];
        let mut last_digest = 0u64;
        let mut observer = |view: &admm_ta_transport::sim::process::RoundView<'_>| {
            let len = view.payload_len;
            let mut relaxed = 0.0;
            for i in 0..n {
                let own = &view.payloads[i * len + i * m..][..m];
                argmax_assignment(own, m, &mut decisions[i..i + 1]);
                relaxed += own
                    .iter()
                    .zip(problem.costs().row(i))
                    .map(|(x, a)| x * a)
                    .sum::<f64>();
            }
            if (relaxed - optimum.cost).abs() <= 1e-3 * optimum.cost {
                first_within.get_or_insert(view.round);
            }
            let opt = problem.is_feasible(&decisions)
                && problem.cost_of(&decisions).unwrap() <= optimum.cost + 1e-9;
            if opt {
                optimal_since.get_or_insert(view.round);
            } else {
                optimal_since = None;
            }
            argmax_assignment(&view.payloads[..len], m, &mut agreed);
            let agreed_optimal = problem.is_feasible(&agreed)
                && problem.cost_of(&agreed).unwrap() <= optimum.cost + 1e-9;
            let d0 = view.reports[0].assignment_digest;
            let same = view.reports.iter().all(|r| r.assignment_digest == d0);
            for (t, tau) in taus.iter().enumerate() {
                let all_ok = same && view.reports.iter().all(|r| r.integrality_gap <= *tau);
                let own_ok = same
                    && view
                        .reports
                        .iter()
                        .all(|r| r.own_integrality_gap <= *tau && r.integrality_gap.is_finite());
                for (kind, ok) in [all_ok, own_ok].into_iter().enumerate() {
                    streak[t][kind] = if ok && (streak[t][kind] == 0 || d0 == last_digest) {
                        streak[t][kind] + 1
                    } else if ok {
                        1
                    } else {
                        0
                    };
                    if streak[t][kind] >= k && stop[t][kind].is_none() {
                        stop[t][kind] = Some((view.round, agreed_optimal));
                    }
                }
            }
            last_digest = d0;
        };
        sim.run(max_rounds, &mut NeverStop, &mut observer);
        rows.push((seed, optimal_since, first_within, stop));
    }
    let mean = |v: Vec<usize>| v.iter().sum::<usize>() as f64 / v.len().max(1) as f64;
    let opt: Vec<usize> = rows.iter().filter_map(|r| r.1).collect();
    let within: Vec<usize> = rows.iter().filter_map(|r| r.2).collect();
    println!(
        "{n}x{m} {:?} ρ × {factor}: optimal-assignment round mean {:.1} (reached {}/{}), within 0.1% mean {:.1}",
        spec,
        mean(opt.clone()),
        opt.len(),
        rows.len(),
        mean(within)
    );
    for (t, tau) in taus.iter().enumerate() {
        for (kind, name) in ["all", "own"].iter().enumerate() {
            let stops: Vec<(usize, bool)> = rows.iter().filter_map(|r| r.3[t][kind]).collect();
            let wrong = stops.iter().filter(|s| !s.1).count();
            println!(
                "  τ={tau} {name}: stopped {}/{}, wrong {wrong}, mean stop round {:.1}",
                stops.len(),
                rows.len(),
                mean(stops.iter().map(|s| s.0).collect())
            );
        }
    }
}
