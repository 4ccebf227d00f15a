//! Episode latency of a standing team with private costs on the `threads` transport (the
//! floor under `bench/standing_team.py`'s process rows), against a one-shot threads solve of
//! the same problem (team start included). Same workloads: N robots × N tasks, uniform
//! costs, `random:0.2`, drift (±1 % per episode) then redrawn, warm (the default) and cold.
//! An episode's latency is the slowest robot's time from its row to its answer.
//! `cargo run --release -p admm-ta-runtime --example standing_threads -- 10,20,50 [EPISODES]`.
use admm_ta_agents::problem::{CaseChoice, CostMatrix, TaskAssignmentProblem};
use admm_ta_runtime::options::SolveOptions;
use admm_ta_runtime::solve::solve;
use admm_ta_runtime::standing::one_process::{Input, run_on_threads};
use admm_ta_runtime::team::team_file::Team;
use admm_ta_topologies::TopologySpec;
use admm_ta_topologies::rng::SeededRng;
use admm_ta_transport::Transport;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn p99(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * 0.99).round() as usize]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let sizes: Vec<usize> = args
        .get(1)
        .map_or("10,20,50", String::as_str)
        .split(',')
        .map(|s| s.parse().unwrap())
        .collect();
    let episodes: usize = args.get(2).map_or(30, |a| a.parse().unwrap());
    let dir = std::env::temp_dir().join(format!("standing-threads-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    println!(
        "| robots | episode p50 / p99 (drift) | p50 (redrawn) | rounds warm / cold (drift) | rounds warm / cold (redrawn) | one-shot solve p50 | episode / one-shot |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for n in sizes {
        let mut rng = SeededRng::new(1000 + n as u64);
        let base: Vec<Vec<f64>> = (0..n)
            .map(|_| (0..n).map(|_| rng.uniform()).collect())
            .collect();
        // Episode 0: the base (untimed); then drift; then redrawn.
        let mut sequence = vec![base.clone()];
        let mut rows = base;
        for _ in 0..episodes {
            for row in &mut rows {
                for v in row.iter_mut() {
                    *v = (*v + 0.02 * (rng.uniform() - 0.5)).clamp(0.0, 1.0);
                }
            }
            sequence.push(rows.clone());
        }
        let drift_last = rows.clone();
        for _ in 0..episodes {
            sequence.push(
                (0..n)
                    .map(|_| (0..n).map(|_| rng.uniform()).collect())
                    .collect(),
            );
        }
        let mut results = Vec::new();
        for warm in [true, false] {
            let path = dir.join(format!("team-{n}-{warm}.toml"));
            std::fs::write(
                &path,
                format!(
                    "run = \"thr{n}{warm}\"\nrobots = {n}\ntasks = {n}\ncosts = \"private\"\ntopology = \"random:0.2\"\nseed = 1\nwarm_start = {warm}\n"
                ),
            )
            .unwrap();
            let team = Team::read(&path).unwrap();
            let answers = run_on_threads(&team, sequence.len() as u64, &|e, i| {
                Input::Row(sequence[e as usize][i].iter().map(|&c| Some(c)).collect())
            })
            .unwrap();
            let per_episode = |range: std::ops::Range<usize>| -> (Vec<f64>, Vec<f64>) {
                range
                    .map(|e| {
                        assert!(answers.iter().all(|a| a[e].certified), "episode {e}");
                        let ms = answers.iter().map(|a| a[e].ms).fold(0.0, f64::max);
                        (ms, answers[0][e].rounds as f64)
                    })
                    .unzip()
            };
            results.push((
                per_episode(1..episodes + 1),
                per_episode(episodes + 1..2 * episodes + 1),
            ));
        }
        let costs = CostMatrix::new(n, n, drift_last.concat()).unwrap();
        let problem = TaskAssignmentProblem::new(costs, CaseChoice::Auto).unwrap();
        let graph = "random:0.2"
            .parse::<TopologySpec>()
            .unwrap()
            .build(n, 1)
            .unwrap();
        let options = SolveOptions::builder()
            .transport(Transport::Threads)
            .seed(1)
            .build()
            .unwrap();
        let solves: Vec<f64> = (0..5)
            .map(|_| {
                let started = Instant::now();
                let report = solve(&problem, &graph, &options).unwrap();
                assert!(report.converged);
                started.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        let ((warm_drift, warm_drift_rounds), (warm_redrawn, warm_redrawn_rounds)) =
            results[0].clone();
        let ((_, cold_drift_rounds), (_, cold_redrawn_rounds)) = results[1].clone();
        let solve_p50 = median(solves);
        println!(
            "| {n} | {:.2} ms / {:.2} ms | {:.2} ms | {:.0} / {:.0} | {:.0} / {:.0} | {:.2} ms | {:.3} |",
            median(warm_drift.clone()),
            p99(warm_drift.clone()),
            median(warm_redrawn),
            median(warm_drift_rounds),
            median(cold_drift_rounds),
            median(warm_redrawn_rounds),
            median(cold_redrawn_rounds),
            solve_p50,
            median(warm_drift) / solve_p50,
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
