//! The fast primal variant's readout: robot `i` reads the team's assignment from its
//! certificate matrix `G_i = Q_i + α_i e_iᵀ` (tasks × robots, `α_i` its own costs in its
//! own column) by solving a local linear sum assignment on `G_i + E`, with `E` a tie-break
//! matrix shared by every robot.
//!
//! The certificate of [`crate::methods::primal::agent::PrimalAgent::certificate_slack`] asks exactly that
//! every `G_i` be minimised over the polytope by the same assignment (`Σ_i G_i = C`). A
//! readout that minimises `G_i + E` (entries of `E` in `[0, ε)`) has slack at most `n ε`
//! for `G_i` (`⟨E, σ − π⟩ ≤ ⟨E, σ⟩ < n ε` for the minimiser `σ` of `G_i`), so robots that
//! agree on their readouts hold a certified assignment: no second assignment problem is
//! needed. Without `E`, exact ties (duplicate robots, integer costs) would let robots pick
//! different optima forever.
//!
//! Case 2 (`n > m`): every task needs one *covering* robot and every other robot takes its
//! cheapest task (the expansion of [`crate::certify::oracle`]), so the minimum is
//! `Σ_j f_j + min_cover Σ_t (G[t, c(t)] − f_{c(t)})`, `f_j` robot `j`'s cheapest entry: an
//! `m × n` problem over injective covers, `O(m² n)` instead of the `n × n` expansion's
//! `O(n³)` (100 robots × 4 tasks: the difference between a stress run in seconds and in
//! minutes). Case 1 warm-starts each round's solve from the previous round's
//! ([`LsapWorkspace::solve_warm`]). Everything is preallocated: a readout allocates nothing.

use crate::numerics::lsap_workspace::LsapWorkspace;
use crate::problem::AssignmentCase;
use admm_ta_topologies::rng::SeededRng;

/// Stream of the tie-break matrix (the same at every robot: `"tiebreak"`).
const TIE_BREAK_STREAM: u64 = 0x7469_6562_7265_616b;

/// One robot's readout state.
#[derive(Debug, Clone)]
pub struct GReadout {
    tasks: usize,
    robots: usize,
    case: AssignmentCase,
    /// `ε · U[0, 1)` per entry (column-major tasks × robots); empty when `ε = 0`.
    tie_break: Vec<f64>,
    epsilon: f64,
    /// `G_i + E` of the current readout (column-major tasks × robots, as `Q_i`).
    g: Vec<f64>,
    workspace: LsapWorkspace,
    /// Case 2: each robot's cheapest entry of `G_i + E` and its task.
    free_cost: Vec<f64>,
    cheapest: Vec<usize>,
    /// The last readout minimises `G_i + E` for the current `Q_i` and costs.
    current: bool,
}

impl GReadout {
    /// A readout for `tasks × robots` with tie-break size `epsilon` (0: none). The matrix is
    /// drawn from a fixed stream and the shape, so every robot holds the same one.
    pub fn new(tasks: usize, robots: usize, case: AssignmentCase, epsilon: f64) -> Self {
        let tie_break = if epsilon > 0.0 {
            let mut rng = SeededRng::for_stream(TIE_BREAK_STREAM, (tasks * robots) as u64);
            (0..tasks * robots)
                .map(|_| epsilon * rng.uniform())
                .collect()
        } else {
            Vec::new()
        };
        // Case 1: robots × tasks (square); Case 2: tasks × robots (covers).
        let (rows, cols) = if Self::square(case, robots, tasks) {
            (robots, tasks.max(robots))
        } else {
            (tasks, robots)
        };
        Self {
            tasks,
            robots,
            case,
            tie_break,
            epsilon,
            g: vec![0.0; tasks * robots],
            workspace: LsapWorkspace::new(rows, cols),
            free_cost: vec![0.0; robots],
            cheapest: vec![0; robots],
            current: false,
        }
    }

    fn square(case: AssignmentCase, robots: usize, tasks: usize) -> bool {
        case == AssignmentCase::One || robots == tasks
    }

    /// Reads robot `index`'s assignment (task per robot) from `q` (its `Q_i`) and `costs`
    /// (its `α_i`) into `out`.
    pub fn read(&mut self, q: &[f64], costs: &[f64], index: usize, out: &mut [usize]) {
        let (m, n) = (self.tasks, self.robots);
        // `G_i + E` once per round: the solver reads entries many times.
        self.g.copy_from_slice(q);
        for (g, tie) in self.g.iter_mut().zip(&self.tie_break) {
            *g += tie;
        }
        for (g, cost) in self.g[index * m..(index + 1) * m].iter_mut().zip(costs) {
            *g += cost;
        }
        let values = &self.g;
        let g = |t: usize, j: usize| values[j * m + t];
        // Finite iterates always have an assignment; a non-finite one leaves the readout
        // stale (`out` unchanged, no certificate slack) rather than stopping the robot.
        self.current = false;
        if Self::square(self.case, n, m) {
            // Warm: the previous round's potentials and assignment (an exact minimiser all
            // the same, in `O(n²)` when few robots' best tasks moved).
            let Some(rows) = self.workspace.solve_warm(|j, t| g(t, j)) else {
                return;
            };
            out.copy_from_slice(rows);
        } else {
            for j in 0..n {
                let (mut best, mut value) = (0, g(0, j));
                for t in 1..m {
                    let v = g(t, j);
                    if v < value {
                        (best, value) = (t, v);
                    }
                }
                self.cheapest[j] = best;
                self.free_cost[j] = value;
            }
            let free = &self.free_cost;
            let Some(covers) = self.workspace.solve(|t, j| g(t, j) - free[j]) else {
                return;
            };
            out.copy_from_slice(&self.cheapest);
            for (t, &j) in covers.iter().enumerate() {
                out[j] = t;
            }
        }
        self.current = true;
    }

    /// The state changed since the last readout (new costs, a reset).
    pub fn invalidate(&mut self) {
        self.current = false;
    }

    /// `n ε`, the certificate slack the last readout has by construction, if it was read
    /// from the current state.
    pub fn slack_bound(&self) -> Option<f64> {
        self.current.then_some(self.robots as f64 * self.epsilon)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::CostMatrix;

    #[test]
    fn the_readout_is_the_oracle_s_assignment_for_g() {
        let mut rng = SeededRng::new(4);
        for (n, m) in [(4, 4), (6, 3), (5, 1), (12, 4)] {
            let case = if n == m {
                AssignmentCase::One
            } else {
                AssignmentCase::Two
            };
            let mut readout = GReadout::new(m, n, case, 0.0);
            for index in 0..n {
                let q: Vec<f64> = (0..m * n).map(|_| rng.uniform() - 0.5).collect();
                let costs: Vec<f64> = (0..m).map(|_| rng.uniform()).collect();
                let mut out = vec![0; n];
                readout.read(&q, &costs, index, &mut out);
                let values = (0..n)
                    .flat_map(|j| {
                        let (q, costs) = (&q, &costs);
                        (0..m).map(move |t| q[j * m + t] + if j == index { costs[t] } else { 0.0 })
                    })
                    .collect();
                let g = CostMatrix::new(n, m, values).unwrap();
                let best = crate::certify::oracle::solve_costs(&g, case).unwrap();
                let value =
                    |a: &[usize]| a.iter().enumerate().map(|(j, &t)| g.get(j, t)).sum::<f64>();
                assert!((value(&out) - value(&best)).abs() < 1e-12, "{n}×{m}");
                assert_eq!(readout.slack_bound(), Some(0.0));
            }
        }
    }
}
