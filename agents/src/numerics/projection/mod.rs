//! The x-update of primal consensus ADMM: a Euclidean projection onto the relaxed
//! assignment polytope
//!
//! `P = { X ∈ R^{m×n} : 0 ≤ X ≤ 1, 1ᵀX = 1ᵀ (each robot one task), X1 = 1 (Case 1) or
//! X1 ≥ 1 (Case 2) }`,
//!
//! where rows are tasks and columns are robots. Two interchangeable paths:
//!
//! * [`TransportPolytopeProjector`]: the fast path — a semismooth Newton method on the
//!   row/column multipliers with faer for the linear algebra, warm-started, allocation-free
//!   after construction;
//! * [`QpProjector`]: the general path — the same update (or the update of any
//!   Problem 2 instance, see [`crate::problem::general`]) as a clarabel QP.

mod clipped_root;
mod interior;
mod qp;
mod transport_polytope;

pub use clipped_root::clipped_sum_root;
pub use qp::{QpError, QpProjector};
pub use transport_polytope::{ProjectionSettings, ProjectionStats, TransportPolytopeProjector};

/// Largest violation of the constraints of `P` by `x` (column-major `m × n`): box, column
/// sums and row sums. Used by tests and by callers that audit a projection.
pub fn polytope_violation(
    x: &[f64],
    tasks: usize,
    robots: usize,
    case: crate::problem::AssignmentCase,
) -> f64 {
    let mut worst: f64 = 0.0;
    let mut rows = vec![0.0; tasks];
    for c in 0..robots {
        let column = &x[c * tasks..(c + 1) * tasks];
        let mut sum = 0.0;
        for (r, &value) in column.iter().enumerate() {
            worst = worst.max(-value).max(value - 1.0);
            rows[r] += value;
            sum += value;
        }
        worst = worst.max((sum - 1.0).abs());
    }
    for sum in rows {
        worst = worst.max(match case {
            crate::problem::AssignmentCase::One | crate::problem::AssignmentCase::Idle => {
                (sum - 1.0).abs()
            }
            crate::problem::AssignmentCase::Two => 1.0 - sum,
        });
    }
    worst
}
