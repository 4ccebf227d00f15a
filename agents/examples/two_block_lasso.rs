//! The generic two-block ADMM (`admm_ta_agents::numerics::two_block`) on a small lasso, Boyd et al.
//! §6.4: `min ½‖D x − y‖² + κ‖z‖₁` subject to `x − z = 0`.
//!
//! `cargo run -p admm-ta-agents --example two_block_lasso`
//!
//! The x-update is a linear solve with `DᵀD + ρI` (factored once), the z-update soft
//! thresholding. Prints the recovered coefficients next to the sparse ground truth the
//! measurements came from, the residuals, and the lasso's optimality conditions.

use admm_ta_agents::numerics::two_block::{Multipliers, TwoBlockAdmm};
use admm_ta_topologies::rng::SeededRng;
use faer::linalg::solvers::Solve;
use faer::{Mat, Side};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (rows, cols, kappa, rho) = (30, 8, 0.5, 1.0);
    // Measurements y = D·truth + noise of a sparse truth (every other coefficient is 0).
    let mut rng = SeededRng::new(7);
    let d = Mat::from_fn(rows, cols, |_, _| 2.0 * rng.uniform() - 1.0);
    let truth: Vec<f64> = (0..cols)
        .map(|j| {
            if j % 2 == 0 {
                1.0 + j as f64 / 4.0
            } else {
                0.0
            }
        })
        .collect();
    let y: Vec<f64> = (0..rows)
        .map(|i| (0..cols).map(|j| d[(i, j)] * truth[j]).sum::<f64>() + 0.01 * rng.uniform())
        .collect();
    let dty: Vec<f64> = (0..cols)
        .map(|j| (0..rows).map(|i| d[(i, j)] * y[i]).sum())
        .collect();
    let mut gram = d.transpose() * &d;
    for j in 0..cols {
        gram[(j, j)] += rho;
    }
    let factor = gram.llt(Side::Lower)?;

    // A = I, B = −I, c = 0: the constraint x − z = 0.
    let mut admm = TwoBlockAdmm::builder(
        Mat::identity(cols, cols),
        -Mat::<f64>::identity(cols, cols),
        vec![0.0; cols],
    )
    .rho(rho)
    .multipliers(Multipliers::Scaled)
    .tolerances(1e-9, 1e-8)
    .max_iterations(10_000)
    .build()?;
    let mut rhs = Mat::<f64>::zeros(cols, 1);
    let result = admm.solve(
        // argmin ½‖Dx − y‖² + (ρ/2)‖x + v‖²: (DᵀD + ρI) x = Dᵀy − ρ v.
        |v, rho, x| {
            for j in 0..cols {
                rhs[(j, 0)] = dty[j] - rho * v[j];
            }
            factor.solve_in_place(rhs.as_mut());
            for (j, x) in x.iter_mut().enumerate() {
                *x = rhs[(j, 0)];
            }
        },
        // argmin κ‖z‖₁ + (ρ/2)‖−z + w‖²: soft thresholding of w at κ/ρ.
        |w, rho, z| {
            for (z, w) in z.iter_mut().zip(w) {
                *z = w.signum() * (w.abs() - kappa / rho).max(0.0);
            }
        },
    );
    println!(
        "lasso, {rows} measurements of {cols} coefficients, κ = {kappa}, ρ = {rho}: {} after {} iterations (primal residual {:.1e}, dual residual {:.1e})",
        if result.converged {
            "converged"
        } else {
            "iteration limit reached"
        },
        result.iterations,
        result.residuals.primal,
        result.residuals.dual,
    );
    // Optimality: g = Dᵀ(y − D z) is κ·sign(z_j) where z_j ≠ 0 and within [−κ, κ] where
    // z_j = 0; at the optimum the multiplier λ of x − z = 0 is that same g.
    let z = admm.z();
    let lambda = admm.lambda();
    let residual: Vec<f64> = (0..rows)
        .map(|i| y[i] - (0..cols).map(|j| d[(i, j)] * z[j]).sum::<f64>())
        .collect();
    println!("  j   truth   lasso z   Dᵀ(y − Dz)        λ");
    for j in 0..cols {
        let g: f64 = (0..rows).map(|i| d[(i, j)] * residual[i]).sum();
        println!(
            "{j:>3} {:>7.3} {:>9.4} {g:>12.4} {:>8.4}",
            truth[j],
            z[j] + 0.0,
            lambda[j]
        );
    }
    Ok(())
}
