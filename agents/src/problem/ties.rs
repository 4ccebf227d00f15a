//! Breaking ties between optimal assignments.
//!
//! With several optimal assignments (integer costs, say) the consensus iterate converges to
//! a fractional point of the optimal face, and robots that round it independently may pick
//! different optima. Each robot therefore adds its own small perturbation `ε·U[0, 1)` to its
//! costs (drawn from the run seed and its index, so every transport sees the same numbers).
//! When all costs lie on a lattice of step `δ` (any two assignment costs differ by 0 or at
//! least `δ`), `ε = δ / (n + 1)` keeps the total perturbation below `δ`: the perturbed
//! optimum is unique (almost surely) and optimal for the original costs.

use crate::problem::CostMatrix;
use admm_ta_topologies::rng::SeededRng;

/// How to perturb costs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Perturbation {
    /// Perturb only when the costs lie on a lattice (where ties are likely).
    #[default]
    Auto,
    Off,
    /// A fixed `ε`.
    Fixed(f64),
}

/// Step `δ` of the lattice the costs lie on, when they lie on one with fewer distinct
/// values than entries (integer or fixed-point data); `None` for generic real costs. Only
/// allowed pairs count; constant costs have step 1.
pub fn lattice_step(costs: &CostMatrix) -> Option<f64> {
    let mut values: Vec<f64> = costs.allowed_values().collect();
    let entries = values.len();
    values.sort_unstable_by(f64::total_cmp);
    values.dedup();
    if values.len() == 1 && entries > 1 {
        // Constant costs: every assignment is optimal and lies on every lattice; step 1 (the
        // normalised spread) lets the perturbation pick one the robots agree on.
        return Some(1.0);
    }
    if values.len() < 2 || values.len() == entries {
        return None;
    }
    let step = values
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min);
    let base = values[0];
    let on_lattice = values.iter().all(|v| {
        let k = (v - base) / step;
        (k - k.round()).abs() <= 1e-9 * k.abs().max(1.0)
    });
    on_lattice.then_some(step)
}

/// The `ε` to use for these costs, or `None` for no perturbation.
pub fn epsilon(costs: &CostMatrix, rule: Perturbation) -> Option<f64> {
    match rule {
        Perturbation::Off => None,
        Perturbation::Fixed(eps) => (eps > 0.0).then_some(eps),
        Perturbation::Auto => lattice_step(costs).map(|step| step / (costs.robots() + 1) as f64),
    }
}

/// Robot `robot`'s costs with its own perturbation added.
pub fn perturbed_row(
    costs: &CostMatrix,
    robot: usize,
    epsilon: Option<f64>,
    seed: u64,
) -> Vec<f64> {
    let mut row = costs.row(robot).to_vec();
    perturb(&mut row, robot, epsilon, seed);
    row
}

/// Adds robot `robot`'s own perturbation to its `row` in place (what [`perturbed_row`]
/// adds; a robot that holds only its own row calls this).
pub fn perturb(row: &mut [f64], robot: usize, epsilon: Option<f64>, seed: u64) {
    if let Some(eps) = epsilon {
        let mut rng = SeededRng::for_stream(seed ^ 0x7469_6573, robot as u64);
        for value in row {
            *value += eps * rng.uniform();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detects_integer_costs_only() {
        let ints =
            CostMatrix::new(3, 3, vec![1.0, 3.0, 2.0, 2.0, 1.0, 3.0, 5.0, 1.0, 1.0]).unwrap();
        assert_eq!(lattice_step(&ints), Some(1.0));
        assert_eq!(epsilon(&ints, Perturbation::Auto), Some(0.25));
        let constant = CostMatrix::new(2, 2, vec![3.0; 4]).unwrap();
        assert_eq!(lattice_step(&constant), Some(1.0));
        let reals = CostMatrix::uniform(5, 5, 1).unwrap();
        assert_eq!(lattice_step(&reals), None);
        assert_eq!(epsilon(&reals, Perturbation::Auto), None);
        let row = perturbed_row(&ints, 1, Some(0.25), 7);
        assert!(
            row.iter()
                .zip(ints.row(1))
                .all(|(p, o)| *p >= *o && *p < o + 0.25)
        );
        assert_eq!(row, perturbed_row(&ints, 1, Some(0.25), 7));
    }
}
