//! The fast primal variant's consensus step: over-relaxed, anchored, with consensus
//! multipliers that sum to zero *exactly*.
//!
//! # Exact antisymmetry
//! The certificate needs `Σ_i Q_i = 0`. In floating point every robot rounds its own
//! `Q_i += ρ Σ_j (X_i − X_j)` differently, and with the fast variant's ρ (about 10⁴ times
//! the paper's) that rounding error grows with the rounds. Here the payloads are snapped to
//! the grid `2^-52` after the projection (at most the last bit of an entry in `[0.5, 1]`
//! changes), so every entry is an integer number of grid steps (at most `2^52`). A robot
//! adds its neighbours' entries in those integer units (`i64`: exact below 2048
//! neighbours) and accumulates `d_i X_i − Σ_j X_j` in `i128` units `K_i`. Every edge
//! adds `k` to one robot and `−k` to the other in the same round, so `Σ_i K_i = 0`
//! exactly, whatever the number of rounds (`i128` cannot overflow before `2^64` rounds).
//! `Q_i = (αρ / 2^52) · K_i` is rounded once per entry: the team's `|Σ_i Q_i|` stays
//! below `2u Σ_i |Q_i|` (`u = 2^-53`) per entry, at round 10 as at round 10⁶, instead of
//! growing with the rounds. The grid is as fine as `f64` on `[0.5, 1]`: a coarser one
//! (`2^-38`, which would keep the sums exact in `f64`) jitters `Q` by more than the
//! tie-break matrix and duplicate robots then never agree.
//!
//! # The step
//! With `s_i = Σ_j X_j` (exact), over-relaxation `α` and anchor `c`
//! ([`crate::methods::primal::settings::FastTuning`]):
//!
//! ```text
//! K_i += 2^52 (d_i X_i − s_i),        Q_i = αρ 2^-52 K_i
//! Z̄_i = α (d_i X_i + s_i)/2 + (1 − α) Z̄_i          (Σ_j of the edge variables z_ij)
//! input = (1 − c) Z̄_i / d_i + c/m − G_i / (2ρ d_i)   (G_i = Q_i + α_i e_iᵀ)
//! ```
//!
//! With `α = 1` and `c = 0` this is Algorithm 1's step (up to the grid).

use crate::methods::primal::readout::GReadout;
use crate::methods::primal::readout_filter::{MAX_WINDOW, ReadoutFilter, WEIGHT_BITS};
use crate::methods::primal::settings::{FastParams, FastTuning};
use crate::problem::AssignmentCase;
use std::sync::Arc;

/// `2^52`: the grid of the payloads and the unit of the integer multipliers.
const GRID: f64 = (1u64 << 52) as f64;
/// Neighbour counts whose unit sums stay exact in `i64` (`2^11 · 2^52 = 2^63`).
const MAX_EXACT_DEGREE: usize = 2047;

/// The fast variant's state besides `X_i` and `Q_i`.
#[derive(Debug, Clone)]
pub struct FastConsensus {
    tuning: FastTuning,
    /// `Z̄_i`, the sum of the edge consensus variables (column-major tasks × robots).
    zbar: Vec<f64>,
    /// `K_i`: `Q_i` in units of `αρ 2^-52`.
    units: Vec<i128>,
    /// `Σ_j X_j` of this round in grid units.
    neighbour_units: Vec<i64>,
    exact: bool,
    /// The readout (the team's assignment as this robot reads it).
    pub readout: GReadout,
    /// The extrapolated readout's weights and history ([`crate::methods::primal::readout_filter`]).
    filter: Option<Filtered>,
}

/// `Q̂_i` when the robot filters its readout, else `q` (its `Q_i`).
fn filtered_or<'a>(filter: &'a Option<Filtered>, q: &'a [f64]) -> &'a [f64] {
    filter.as_ref().map_or(q, |f| &f.q)
}

/// A robot's side of the extrapolated readout.
#[derive(Debug, Clone)]
struct Filtered {
    weights: Arc<ReadoutFilter>,
    /// The last `W − 1` increments of `K_i`, entry-major: entry `e`'s increment of update `u`
    /// at `e (W − 1) + (u − 1) mod (W − 1)`, so that one entry's history is contiguous.
    increments: Vec<i64>,
    /// Updates since the start (or the last reset).
    updates: u64,
    /// `Q̂_i`, the certificate multipliers of this round.
    q: Vec<f64>,
}

impl FastConsensus {
    /// The state of a robot with `degree` neighbours.
    pub fn new(
        tasks: usize,
        robots: usize,
        case: AssignmentCase,
        degree: usize,
        settings: &FastParams,
    ) -> Self {
        Self {
            tuning: settings.tuning,
            zbar: vec![0.0; tasks * robots],
            units: vec![0; tasks * robots],
            neighbour_units: vec![0; tasks * robots],
            exact: degree <= MAX_EXACT_DEGREE,
            readout: GReadout::new(tasks, robots, case, settings.tie_break),
            filter: None,
        }
    }

    /// Reads the assignment from `Σ_l γ_l G_i(k − l)` with `filter`'s weights from the next
    /// step on (every robot of the team must use the same filter).
    pub fn set_filter(&mut self, filter: Arc<ReadoutFilter>) {
        let len = self.units.len();
        self.filter = Some(Filtered {
            increments: vec![0; (filter.window() - 1) * len],
            weights: filter,
            updates: 0,
            q: vec![0.0; len],
        });
        self.readout.invalidate();
    }

    /// The digest of the filter's weights (0 without one).
    pub fn filter_digest(&self) -> u64 {
        self.filter.as_ref().map_or(0, |f| f.weights.digest())
    }

    /// The multipliers of the certificate matrix `Ĝ_i = Q̂_i + α_i e_iᵀ` this round: `Q_i`
    /// itself, or its filtered combination.
    pub fn certificate_multipliers<'a>(&'a self, q: &'a [f64]) -> &'a [f64] {
        filtered_or(&self.filter, q)
    }

    /// Reads robot `index`'s assignment from its certificate matrix into `out`
    /// ([`GReadout::read`] on [`FastConsensus::certificate_multipliers`]).
    pub fn read(&mut self, q: &[f64], costs: &[f64], index: usize, out: &mut [usize]) {
        self.readout
            .read(filtered_or(&self.filter, q), costs, index, out);
    }

    /// Forgets the multipliers and the edge variables (a cold start).
    pub fn reset(&mut self) {
        self.zbar.fill(0.0);
        self.units.fill(0);
        if let Some(f) = &mut self.filter {
            f.updates = 0;
            f.q.fill(0.0);
        }
        self.readout.invalidate();
    }

    /// Restarts the readout filter's history (a warm start: the multipliers and edge
    /// variables are kept, the extrapolation starts over from the new episode's rounds).
    pub fn restart_readout(&mut self) {
        if let Some(f) = &mut self.filter {
            f.updates = 0;
            f.increments.fill(0);
            f.q.fill(0.0);
        }
        self.readout.invalidate();
    }

    /// `Σ_i Q_i = 0` holds exactly (the robot's neighbour sums are exact).
    pub fn exact(&self) -> bool {
        self.exact
    }

    /// `K_i`, the multipliers in integer units (column-major tasks × robots).
    pub fn units(&self) -> &[i128] {
        &self.units
    }

    /// Starts a round's neighbour sum.
    pub fn clear_neighbours(&mut self) {
        self.neighbour_units.fill(0);
    }

    /// Adds a neighbour's payload (grid values) to the round's sum.
    pub fn add_neighbour(&mut self, theirs: &[f64]) {
        for (sum, &v) in self.neighbour_units.iter_mut().zip(theirs) {
            *sum = sum.wrapping_add((v * GRID) as i64);
        }
    }

    /// One consensus update: `z` holds `s_i = Σ_j X_j` on entry (in `f64`; the exact sum
    /// is the one of [`FastConsensus::add_neighbour`]) and the projection input without the
    /// own costs on exit; `q` receives `Q_i`. `neighbours` is the number of payloads
    /// gathered (none: the robot is alone, and `Q_i` stays 0).
    #[allow(clippy::too_many_arguments)]
    pub fn update(
        &mut self,
        z: &mut [f64],
        q: &mut [f64],
        x: &[f64],
        neighbours: usize,
        rho: f64,
        tasks: usize,
    ) {
        let degree = neighbours.max(1) as f64;
        let FastTuning {
            relaxation: alpha,
            anchor: c,
        } = self.tuning;
        let scale = alpha * rho / GRID;
        let half_scaled = 0.5 / (rho * degree);
        let (keep, centre) = ((1.0 - c) / degree, c / tasks as f64);
        let own_weight = neighbours as i64;
        let history = self.filter.as_mut().map(|f| {
            f.updates += 1;
            let slots = f.weights.window() - 1;
            let slot = ((f.updates - 1) % slots as u64) as usize;
            (&mut f.increments[slot..], slots)
        });
        let mut increments = history
            .into_iter()
            .flat_map(|(tail, slots)| tail.iter_mut().step_by(slots));
        for (((((s, q), k), zb), &mine), &theirs) in z
            .iter_mut()
            .zip(q.iter_mut())
            .zip(self.units.iter_mut())
            .zip(self.zbar.iter_mut())
            .zip(x)
            .zip(&self.neighbour_units)
        {
            let neighbour_sum = *s;
            // Exact: grid values in integer units.
            let difference = own_weight
                .wrapping_mul((mine * GRID) as i64)
                .wrapping_sub(theirs);
            *k += i128::from(difference);
            if let Some(slot) = increments.next() {
                *slot = difference;
            }
            // `i64 → f64` is one instruction, `i128 → f64` a library call; both round to
            // nearest, so the value is the same.
            let units = i64::try_from(*k).map_or(*k as f64, |k| k as f64);
            *q = scale * units;
            *zb = alpha * 0.5 * (degree * mine + neighbour_sum) + (1.0 - alpha) * *zb;
            *s = keep * *zb + centre - *q * half_scaled;
        }
        self.filter_multipliers(scale);
    }

    /// `Q̂_i = scale · 2^-B Σ_l g_l K_i(k − l)`, from `K_i(k − l) = K_i(k) − Σ_{s<l} ΔK_i(k − s)`:
    /// `Σ_l g_l K_i(k − l) = 2^B K_i(k) − Σ_s ΔK_i(k − s) Σ_{l>s} g_l`, exact in `i128`
    /// (`|g| ≤ 2^36`, increments below `2^63`, multipliers below `2^83` for 2^20 rounds).
    fn filter_multipliers(&mut self, scale: f64) {
        let Some(f) = &mut self.filter else {
            return;
        };
        let weights = f.weights.weights(f.updates);
        let slots = f.weights.window() - 1;
        // `Σ_{l>s} g_l` by history slot (0 for slots the window does not reach).
        let mut coefficients = [0i64; MAX_WINDOW];
        let mut tail: i64 = weights.iter().skip(1).sum();
        for (s, g) in weights.iter().enumerate().skip(1) {
            // The increment of update `updates − (s − 1)`.
            coefficients[((f.updates - s as u64) % slots as u64) as usize] = tail;
            tail -= g;
        }
        let coefficients = &coefficients[..slots];
        let unit_scale = scale / f64::from(1u32 << WEIGHT_BITS);
        for ((out, &k), history) in
            f.q.iter_mut()
                .zip(&self.units)
                .zip(f.increments.chunks_exact(slots))
        {
            let mut sum = k << WEIGHT_BITS;
            for (&c, &inc) in coefficients.iter().zip(history) {
                sum -= i128::from(c) * i128::from(inc);
            }
            *out = unit_scale * sum as f64;
        }
    }

    /// Snaps a new payload to the grid `2^-52` (entries in `[0, 1]` stay in it).
    pub fn snap(payload: &mut [f64]) {
        for v in payload {
            *v = (*v * GRID).round() / GRID;
        }
    }
}
