//! Repeats cold projections of one input, for `perf record`:
//! `cargo run --release -p admm-ta-bench --example projection_profile -- 50 2000`.
use admm_ta_agents::numerics::projection::TransportPolytopeProjector;
use admm_ta_agents::problem::AssignmentCase;
use admm_ta_bench::inputs;
use faer::Mat;

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse().unwrap())
        .collect();
    let (size, repeats) = (
        args.first().copied().unwrap_or(50),
        args.get(1).copied().unwrap_or(1000),
    );
    let z = inputs::uniform(size, size, 1);
    let mut out = Mat::<f64>::zeros(size, size);
    let (mut steps, mut evaluations) = (0, 0);
    let started = std::time::Instant::now();
    for _ in 0..repeats {
        let mut p = TransportPolytopeProjector::new(size, size, AssignmentCase::One);
        let stats = p.project(z.as_ref(), out.as_mut());
        steps += stats.newton_steps;
        evaluations += stats.evaluations;
    }
    let per = started.elapsed() / repeats as u32;
    println!(
        "{size}x{size}: {per:?} per cold projection, {} Newton steps, {} evaluations",
        steps / repeats,
        evaluations / repeats
    );
}
