use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::primal::{PrimalAgent, PrimalSettings};
use admm_ta_agents::problem::*;
fn main() {
    let n = 50;
    let costs = CostMatrix::read_csv(std::path::Path::new(
        "/work/shared/oracle/case1_uniform_50x50.csv",
    ))
    .unwrap();
    let rho = admm_ta_agents::rho::default_rho(&costs, (n - 1) as f64);
    let mut agents: Vec<PrimalAgent> = (0..n)
        .map(|i| {
            PrimalAgent::new(
                i,
                costs.row(i).to_vec(),
                n,
                AssignmentCase::One,
                n - 1,
                PrimalSettings::new(rho),
            )
        })
        .collect();
    let len = n * n;
    let mut cur = vec![0.0; len * n];
    let mut next = vec![0.0; len * n];
    let (mut maxs, mut total, mut evals) = (0, 0, 0);
    let t = std::time::Instant::now();
    for k in 0..300 {
        for i in 0..n {
            let inbox: Vec<&[f64]> = (0..n)
                .filter(|&j| j != i)
                .map(|j| &cur[j * len..(j + 1) * len])
                .collect();
            let r = agents[i].step(&inbox, &mut next[i * len..(i + 1) * len]);
            if !next[i * len..(i + 1) * len].iter().all(|v| v.is_finite()) || !r.inner_converged {
                println!(
                    "round {k} agent {i}: {:?} {:?}",
                    r,
                    agents[i].last_projection()
                );
                return;
            }
            maxs = maxs.max(r.inner_iterations);
            total += r.inner_iterations;
            evals += agents[i].last_projection().evaluations;
        }
        std::mem::swap(&mut cur, &mut next);
    }
    println!(
        "max steps {maxs}, mean {}, evals/proj {} time {:?}",
        total as f64 / 50000.0,
        evals as f64 / 50000.0,
        t.elapsed()
    );
}
