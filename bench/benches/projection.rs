//! The x-update projection: fast Newton path against the clarabel QP path.
//!
//! `cargo bench -p admm-ta-bench --bench projection`. Both paths solve the same projection
//! of the same inputs; the fast path is timed cold (fresh projector, no warm start) so the
//! comparison with clarabel is like for like, and warm (the ADMM situation: the previous
//! round's multipliers, input perturbed slightly).

use admm_ta_agents::numerics::projection::{QpProjector, TransportPolytopeProjector};
use admm_ta_agents::problem::AssignmentCase;
use admm_ta_agents::problem::general::GeneralProblem;
use admm_ta_bench::inputs;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use faer::Mat;
use std::hint::black_box;
use std::time::Duration;

fn column_major(z: &Mat<f64>) -> Vec<f64> {
    (0..z.ncols())
        .flat_map(|c| (0..z.nrows()).map(move |r| z[(r, c)]))
        .collect()
}

fn projection(c: &mut Criterion) {
    let mut group = c.benchmark_group("projection");
    group
        .sample_size(20)
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(500));
    let mut slow = Vec::new();
    for &(m, n) in &[(20usize, 20usize), (50, 50), (200, 200)] {
        for (kind, z) in [
            ("uniform", inputs::uniform(m, n, 1)),
            ("near-vertex", inputs::near_vertex(m, n, 1)),
        ] {
            let label = format!("{m}x{n}/{kind}");
            let mut out = Mat::<f64>::zeros(m, n);
            group.bench_function(BenchmarkId::new("fast-cold", &label), |b| {
                b.iter(|| {
                    let mut p = TransportPolytopeProjector::new(m, n, AssignmentCase::One);
                    black_box(p.project(black_box(z.as_ref()), out.as_mut()));
                })
            });
            let mut warm = TransportPolytopeProjector::new(m, n, AssignmentCase::One);
            warm.project(z.as_ref(), out.as_mut());
            let nudged = Mat::from_fn(m, n, |r, col| {
                z[(r, col)] + 1e-3 * (((r * 31 + col * 17) % 7) as f64 - 3.0)
            });
            let mut flip = false;
            group.bench_function(BenchmarkId::new("fast-warm", &label), |b| {
                b.iter(|| {
                    flip = !flip;
                    let input = if flip { nudged.as_ref() } else { z.as_ref() };
                    black_box(warm.project(input, out.as_mut()));
                })
            });
            // 200×200 is 40,000 variables: seconds per solve, so only the uniform input, in
            // its own group with the fewest samples criterion takes.
            if m <= 50 || kind == "uniform" {
                let qp = QpProjector::new(&GeneralProblem::assignment_constraints(
                    n,
                    m,
                    AssignmentCase::One,
                ));
                let zv = column_major(&z);
                let mut xv = vec![0.0; m * n];
                if m <= 50 {
                    group.bench_function(BenchmarkId::new("clarabel", &label), |b| {
                        b.iter(|| qp.project(black_box(&zv), &mut xv).unwrap())
                    });
                } else {
                    slow.push((label.clone(), qp, zv, xv));
                }
            }
        }
    }
    group.finish();
    let mut group = c.benchmark_group("projection");
    group
        .sample_size(10)
        .sampling_mode(criterion::SamplingMode::Flat)
        .measurement_time(Duration::from_secs(30))
        .warm_up_time(Duration::from_millis(1));
    for (label, qp, zv, mut xv) in slow {
        group.bench_function(BenchmarkId::new("clarabel", &label), |b| {
            b.iter(|| qp.project(black_box(&zv), &mut xv).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, projection);
criterion_main!(benches);
