//! The two-block ADMM on the lasso (Boyd et al. §6.4): `min ½‖D x − y‖² + κ‖z‖₁` with
//! `x − z = 0`. The x-update is a linear solve with `DᵀD + ρI` (factored once), the
//! z-update soft thresholding. The answer is checked against the lasso's optimality
//! conditions, not against another solver's output.

use admm_ta_agents::numerics::two_block::{Multipliers, TwoBlockAdmm, TwoBlockError};
use admm_ta_topologies::rng::SeededRng;
use faer::linalg::solvers::Solve;
use faer::{Mat, Side};

struct Lasso {
    d: Mat<f64>,
    y: Vec<f64>,
    kappa: f64,
}

fn instance(rows: usize, cols: usize, seed: u64) -> Lasso {
    let mut rng = SeededRng::new(seed);
    let d = Mat::from_fn(rows, cols, |_, _| rng.uniform() * 2.0 - 1.0);
    // A sparse ground truth plus noise.
    let truth: Vec<f64> = (0..cols)
        .map(|j| {
            if j % 4 == 0 {
                2.0 * rng.uniform() - 1.0
            } else {
                0.0
            }
        })
        .collect();
    let y = (0..rows)
        .map(|i| (0..cols).map(|j| d[(i, j)] * truth[j]).sum::<f64>() + 0.01 * rng.uniform())
        .collect();
    Lasso { d, y, kappa: 0.5 }
}

fn solve(lasso: &Lasso, multipliers: Multipliers, rho: f64) -> (Vec<f64>, usize) {
    let n = lasso.d.ncols();
    let mut gram = lasso.d.transpose() * &lasso.d;
    for j in 0..n {
        gram[(j, j)] += rho;
    }
    let factor = gram
        .llt(Side::Lower)
        .expect("DᵀD + ρI is positive definite");
    let dty: Vec<f64> = (0..n)
        .map(|j| {
            (0..lasso.d.nrows())
                .map(|i| lasso.d[(i, j)] * lasso.y[i])
                .sum()
        })
        .collect();
    let mut rhs = Mat::<f64>::zeros(n, 1);
    let mut admm = TwoBlockAdmm::builder(
        Mat::identity(n, n),
        -Mat::<f64>::identity(n, n),
        vec![0.0; n],
    )
    .rho(rho)
    .multipliers(multipliers)
    .tolerances(1e-9, 1e-8)
    .max_iterations(20_000)
    .build()
    .unwrap();
    let kappa = lasso.kappa;
    let result = admm.solve(
        // argmin ½‖Dx − y‖² + (ρ/2)‖x + v‖²: (DᵀD + ρI) x = Dᵀy − ρ v.
        |v, rho, x| {
            for j in 0..n {
                rhs[(j, 0)] = dty[j] - rho * v[j];
            }
            factor.solve_in_place(rhs.as_mut());
            for j in 0..n {
                x[j] = rhs[(j, 0)];
            }
        },
        // argmin κ‖z‖₁ + (ρ/2)‖−z + w‖²: soft thresholding of w at κ/ρ.
        |w, rho, z| {
            for j in 0..n {
                z[j] = w[j].signum() * (w[j].abs() - kappa / rho).max(0.0);
            }
        },
    );
    assert!(result.converged, "{result:?}");
    (admm.z().to_vec(), result.iterations)
}

/// Lasso optimality: `g = Dᵀ(y − D z)` has `g_j = κ sign(z_j)` where `z_j ≠ 0` and
/// `|g_j| ≤ κ` where `z_j = 0`.
fn assert_lasso_optimal(lasso: &Lasso, z: &[f64], tol: f64) {
    let (rows, cols) = (lasso.d.nrows(), lasso.d.ncols());
    let residual: Vec<f64> = (0..rows)
        .map(|i| lasso.y[i] - (0..cols).map(|j| lasso.d[(i, j)] * z[j]).sum::<f64>())
        .collect();
    for (j, &zj) in z.iter().enumerate().take(cols) {
        let g: f64 = (0..rows).map(|i| lasso.d[(i, j)] * residual[i]).sum();
        if zj != 0.0 {
            assert!(
                (g - lasso.kappa * zj.signum()).abs() <= tol,
                "coordinate {j}: g {g}, z {zj}"
            );
        } else {
            assert!(g.abs() <= lasso.kappa + tol, "coordinate {j}: |g| {g} > κ");
        }
    }
}

#[test]
fn lasso_meets_its_optimality_conditions_with_either_multiplier_form() {
    let lasso = instance(40, 20, 3);
    let (scaled, iterations) = solve(&lasso, Multipliers::Scaled, 1.0);
    assert_lasso_optimal(&lasso, &scaled, 1e-5);
    assert!(scaled.contains(&0.0), "the lasso solution is sparse");
    assert!(scaled.iter().any(|v| *v != 0.0));
    let (unscaled, _) = solve(&lasso, Multipliers::Unscaled, 1.0);
    let difference = scaled
        .iter()
        .zip(&unscaled)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        difference < 1e-9,
        "scaled and unscaled forms differ by {difference}"
    );
    eprintln!("lasso 40×20: {iterations} iterations");
}

#[test]
fn lasso_solution_does_not_depend_on_rho() {
    let lasso = instance(30, 12, 9);
    let (a, _) = solve(&lasso, Multipliers::Scaled, 0.3);
    let (b, _) = solve(&lasso, Multipliers::Scaled, 5.0);
    assert_lasso_optimal(&lasso, &a, 1e-5);
    assert_lasso_optimal(&lasso, &b, 1e-5);
    let difference = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(difference < 1e-6, "{difference}");
}

#[test]
fn bad_settings_are_refused() {
    let id = || Mat::<f64>::identity(2, 2);
    assert!(matches!(
        TwoBlockAdmm::builder(id(), Mat::identity(3, 3), vec![0.0; 2]).build(),
        Err(TwoBlockError::Shape { .. })
    ));
    assert_eq!(
        TwoBlockAdmm::builder(id(), id(), vec![0.0; 2])
            .rho(0.0)
            .build()
            .err(),
        Some(TwoBlockError::Rho(0.0))
    );
    assert_eq!(
        TwoBlockAdmm::builder(id(), id(), vec![f64::NAN, 0.0])
            .build()
            .err(),
        Some(TwoBlockError::NonFinite)
    );
    assert_eq!(
        TwoBlockAdmm::builder(id(), id(), vec![0.0; 2])
            .tolerances(0.0, 0.0)
            .build()
            .err(),
        Some(TwoBlockError::Tolerance)
    );
}
