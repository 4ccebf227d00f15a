//! The projection onto the polytope when no entry is clipped, in closed form: the affine
//! projection onto the sum constraints, `X = Z − u1ᵀ − 1vᵀ` with
//! Case 1 (`n = m`): `u = (Z1 − 1)/n`, `v = (Zᵀ1 − 1 − Σu)/m`; Case 2: `u = 0`,
//! `v = (Zᵀ1 − 1)/m`, valid while every row sum stays `≥ 1`. If the result lies in
//! `[0, 1]` it satisfies the KKT conditions of the projection exactly. The fast primal
//! variant's iterates stay inside the polytope, so this replaces the Newton method there.
//! Preallocated: nothing is allocated per call.

use crate::problem::AssignmentCase;
use faer::reborrow::ReborrowMut;
use faer::{MatMut, MatRef};

fn column<'a>(z: MatRef<'a, f64>, c: usize) -> &'a [f64] {
    z.col(c)
        .try_as_col_major()
        .expect("projection inputs must have unit row stride (column-major)")
        .as_slice()
}

/// Scratch of the closed-form projection.
#[derive(Debug, Clone)]
pub(super) struct InteriorProjection {
    pub u: Vec<f64>,
    pub v: Vec<f64>,
    row_sums: Vec<f64>,
}

impl InteriorProjection {
    pub fn new(tasks: usize, robots: usize) -> Self {
        Self {
            u: vec![0.0; tasks],
            v: vec![0.0; robots],
            row_sums: vec![0.0; tasks],
        }
    }

    /// Writes the projection of `z` (column-major `m × n`) into `out` and returns `true`
    /// if no entry is clipped; otherwise `false` (`out` may have been written).
    pub fn try_project(
        &mut self,
        z: MatRef<'_, f64>,
        mut out: MatMut<'_, f64>,
        case: AssignmentCase,
    ) -> bool {
        let (m, n) = (self.u.len(), self.v.len());
        let one_case = case == AssignmentCase::One || m == n;
        self.u.fill(0.0);
        let mut shift = 0.0;
        if one_case {
            for c in 0..n {
                for (u, &zr) in self.u.iter_mut().zip(column(z, c)) {
                    *u += zr;
                }
            }
            for u in self.u.iter_mut() {
                *u = (*u - 1.0) / n as f64;
            }
            shift = self.u.iter().sum::<f64>();
        }
        for (c, v) in self.v.iter_mut().enumerate() {
            *v = (column(z, c).iter().sum::<f64>() - 1.0 - shift) / m as f64;
        }
        self.row_sums.fill(0.0);
        for (c, &v) in self.v.iter().enumerate() {
            let out = out
                .rb_mut()
                .col_mut(c)
                .try_as_col_major_mut()
                .expect("projection outputs must have unit row stride (column-major)")
                .as_slice_mut();
            for (((o, &zr), &u), sum) in out
                .iter_mut()
                .zip(column(z, c))
                .zip(&self.u)
                .zip(self.row_sums.iter_mut())
            {
                let x = zr - (u + v);
                if !(0.0..=1.0).contains(&x) {
                    return false;
                }
                *o = x;
                *sum += x;
            }
        }
        one_case || self.row_sums.iter().all(|&s| s >= 1.0)
    }
}
