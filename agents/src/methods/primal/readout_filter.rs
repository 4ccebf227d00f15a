//! The fast primal variant's extrapolated readout: every robot reads its assignment from the
//! same fixed linear combination of its last `W` certificate matrices,
//! `Ĝ_i(k) = Σ_l γ_l(k) G_i(k − l)` with `Σ_l γ_l(k) = 1`, instead of from `G_i(k)` alone.
//!
//! # Why the certificate survives
//! The certificate needs a decomposition `C = Σ_i Ĝ_i` whose pieces share a minimiser
//! ([`crate::methods::primal::readout`]). `Σ_i G_i(k) = C` at every round and the weights are the same at
//! every robot and sum to one, so `Σ_i Ĝ_i(k) = Σ_l γ_l(k) C = C`: any common weights keep it
//! sound; good weights only make the readouts agree sooner. The weights are integers
//! `g_l = 2^B γ_l` summing to `2^B` exactly and act on the integer multipliers `K_i`, so the
//! sum is exact in `i128` as the multipliers' own ([`crate::methods::primal::fast_consensus`]).
//!
//! # Where the weights come from
//! In the fast variant's large-ρ regime the iteration is linear, the same in every tangent
//! direction of the polytope: per robot `x, y = Q/ρ, z` (one scalar each) and
//!
//! ```text
//! y_i += α (d_i x_i − Σ_j x_j)      z_i = α (d_i x_i + Σ_j x_j)/2 + (1 − α) z_i
//! x_i  = (1 − c) z_i / d_i − (y_i + a_i) / (2 d_i)
//! ```
//!
//! driven by each robot's own cost `a_i`; it converges to `y_i + a_i = d_i Σ_j a_j / Σ_j d_j`
//! (every robot holding a scaled copy of the whole cost matrix, whose minimiser is the
//! optimum). The residual `r(k) = y(k) + a − d Σa/Σd` is a fixed linear function of `a`
//! given the graph, so the weights that make `Σ_l γ_l r(k − l)` smallest (least squares with
//! `Σ γ = 1`, over the responses to [`PROBES`] fixed random inputs, or to every unit input
//! on small graphs) can be computed by every robot alone from the graph, the same at every
//! robot. On a 50-robot chain the consensus error of `Ĝ` five rounds after the diameter is
//! that of `G` about a hundred rounds later.
//!
//! The weights of round `k` use a window of `min(W, k + 1)` matrices; after
//! [`ReadoutFilter::designed_rounds`] rounds the last round's weights stay (they keep
//! cancelling the slow modes they were fitted to). A design whose weights would amplify by
//! more than [`MAX_GAIN`] is regularised more, and a round whose design fails keeps the plain
//! readout (`γ = [1]`): the certificate never depends on the design being good.

use crate::methods::primal::settings::FastTuning;
use admm_ta_topologies::Graph;
use admm_ta_topologies::rng::SeededRng;

/// Bits of the integer weights: `g_l = 2^B γ_l`, `Σ_l g_l = 2^B`.
pub const WEIGHT_BITS: u32 = 20;
/// Longest window (matrices of history).
pub const MAX_WINDOW: usize = 40;
/// History a robot may hold, in multiplier increments (`i64`, 4 MiB): larger problems get a
/// shorter window.
pub const HISTORY_BUDGET: usize = 1 << 19;
/// Largest `Σ_l |γ_l|` accepted.
pub const MAX_GAIN: f64 = 65536.0;
/// Random inputs of the design on graphs of more robots than this (unit inputs below).
pub const PROBES: usize = 32;
/// Stream of the probes (`"readout"`).
const PROBE_STREAM: u64 = 0x0072_6561_646f_7574;
/// Relative ridge of the least-squares design, raised ×100 while the gain is too large.
const RIDGE: f64 = 1e-12;

/// Integer weights per round, the same at every robot of a team.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadoutFilter {
    window: usize,
    /// `weights[k]`: the weights after the `(k + 1)`-th update, newest matrix first.
    weights: Vec<Vec<i64>>,
    digest: u64,
}

impl ReadoutFilter {
    /// The window a robot of a `tasks × robots` problem on a graph of `diameter` uses
    /// (0: none fits, or the graph is too small to need one).
    pub fn window_for(tasks: usize, robots: usize, diameter: usize) -> usize {
        let fits = HISTORY_BUDGET / (tasks * robots).max(1);
        let useful = 2 * (diameter + 1) + 2;
        let window = MAX_WINDOW.min(fits).min(useful);
        if window >= 2 && diameter >= 1 {
            window
        } else {
            0
        }
    }

    /// The filter of the fast variant with `tuning` on `graph`, for a window of `window`
    /// matrices (`None`: a window below 2 or a graph without edges).
    pub fn design(graph: &Graph, tuning: FastTuning, window: usize) -> Option<Self> {
        if window < 2 || graph.edge_count() == 0 {
            return None;
        }
        let diameter = graph.diameter()?;
        let rounds = 3 * (diameter + 1) + window;
        let mut model = Model::new(graph, tuning);
        let mut residuals = Residuals::new(window, model.len());
        // Inner products `⟨r(k), r(k − l)⟩`, `l < window`, per round.
        let mut products: Vec<Vec<f64>> = Vec::with_capacity(rounds);
        let mut weights = Vec::with_capacity(rounds);
        for k in 0..rounds {
            model.step();
            model.residual_into(residuals.next_slot());
            products.push(residuals.products());
            let w = window.min(k + 1);
            let gram = |a: usize, b: usize| {
                let (newer, lag) = (a.min(b), a.abs_diff(b));
                products[k - newer][lag]
            };
            weights.push(fit(w, gram).unwrap_or_else(|| plain(1)));
        }
        let mut digest: u64 = 0xcbf2_9ce4_8422_2325;
        for g in weights.iter().flatten() {
            digest = (digest ^ *g as u64).wrapping_mul(0x0100_0000_01b3);
        }
        Some(Self {
            window,
            weights,
            digest,
        })
    }

    /// The window (matrices of history the robot keeps).
    pub fn window(&self) -> usize {
        self.window
    }

    /// Rounds with their own weights; later rounds use the last ones.
    pub fn designed_rounds(&self) -> usize {
        self.weights.len()
    }

    /// The weights after update number `update` (1 for the first step), newest first;
    /// at most [`ReadoutFilter::window`] of them, summing to `2^WEIGHT_BITS`.
    pub fn weights(&self, update: u64) -> &[i64] {
        let k = (update.max(1) - 1) as usize;
        &self.weights[k.min(self.weights.len() - 1)]
    }

    /// A digest of every weight (robots whose filters differ must never agree).
    pub fn digest(&self) -> u64 {
        self.digest
    }
}

/// `γ = [1]` in `w`-long form.
fn plain(w: usize) -> Vec<i64> {
    let mut g = vec![0; w];
    g[0] = 1 << WEIGHT_BITS;
    g
}

/// Least-squares weights `min ‖Σ_l γ_l r_l‖² + λ‖γ‖²` with `Σ γ = 1` for the Gram matrix
/// `gram(a, b) = ⟨r_a, r_b⟩`, as integers; `None` when no ridge gives a gain below
/// [`MAX_GAIN`] (or the residuals vanish).
fn fit(w: usize, gram: impl Fn(usize, usize) -> f64) -> Option<Vec<i64>> {
    if w == 1 {
        return Some(plain(1));
    }
    let trace: f64 = (0..w).map(|a| gram(a, a)).sum();
    if !(trace > 0.0 && trace.is_finite()) {
        return None;
    }
    let mut ridge = RIDGE;
    for _ in 0..8 {
        let shift = ridge * trace / w as f64;
        let mut m: Vec<f64> = (0..w * w)
            .map(|e| gram(e / w, e % w) + if e / w == e % w { shift } else { 0.0 })
            .collect();
        if let Some(g) = cholesky_solve_ones(&mut m, w) {
            let sum: f64 = g.iter().sum();
            let gain: f64 = g.iter().map(|v| (v / sum).abs()).sum();
            if sum.is_finite() && sum != 0.0 && gain <= MAX_GAIN {
                return Some(quantise(&g, sum));
            }
        }
        ridge *= 100.0;
    }
    None
}

/// `γ = g / sum` as integers summing to `2^B` exactly (the rounding error goes to the
/// newest weight).
fn quantise(g: &[f64], sum: f64) -> Vec<i64> {
    let unit = (1u64 << WEIGHT_BITS) as f64;
    let mut q: Vec<i64> = g.iter().map(|v| (v / sum * unit).round() as i64).collect();
    let total: i64 = q.iter().sum();
    q[0] += (1i64 << WEIGHT_BITS) - total;
    q
}

/// Solves `M g = 1` for a symmetric positive definite `M` (row-major `w × w`, overwritten by
/// its Cholesky factor); `None` if it is not positive definite.
fn cholesky_solve_ones(m: &mut [f64], w: usize) -> Option<Vec<f64>> {
    for j in 0..w {
        let mut diag = m[j * w + j];
        for p in 0..j {
            diag -= m[j * w + p] * m[j * w + p];
        }
        if diag.is_nan() || diag <= 0.0 {
            return None;
        }
        let diag = diag.sqrt();
        m[j * w + j] = diag;
        for i in j + 1..w {
            let mut v = m[i * w + j];
            for p in 0..j {
                v -= m[i * w + p] * m[j * w + p];
            }
            m[i * w + j] = v / diag;
        }
    }
    let mut y = vec![1.0; w];
    for i in 0..w {
        for p in 0..i {
            y[i] -= m[i * w + p] * y[p];
        }
        y[i] /= m[i * w + i];
    }
    for i in (0..w).rev() {
        for p in i + 1..w {
            y[i] -= m[p * w + i] * y[p];
        }
        y[i] /= m[i * w + i];
    }
    Some(y)
}

/// The scalar linear model of the module docs, driven by `s` inputs at once (row-major
/// robots × inputs).
struct Model<'a> {
    graph: &'a Graph,
    inputs: usize,
    alpha: f64,
    anchor: f64,
    a: Vec<f64>,
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
    sums: Vec<f64>,
    /// `d_i Σ_j a_j / Σ_j d_j` per input: the limit of `y + a`.
    target: Vec<f64>,
}

impl<'a> Model<'a> {
    fn new(graph: &'a Graph, tuning: FastTuning) -> Self {
        let n = graph.robots();
        let (inputs, a) = if n <= PROBES {
            let mut a = vec![0.0; n * n];
            for i in 0..n {
                a[i * n + i] = 1.0;
            }
            (n, a)
        } else {
            let mut rng = SeededRng::for_stream(PROBE_STREAM, n as u64);
            let a = (0..n * PROBES)
                .map(|_| if rng.uniform() < 0.5 { -1.0 } else { 1.0 })
                .collect();
            (PROBES, a)
        };
        let total_degree: f64 = (0..n).map(|i| graph.degree(i) as f64).sum();
        let mut target = vec![0.0; n * inputs];
        for r in 0..inputs {
            let sum: f64 = (0..n).map(|j| a[j * inputs + r]).sum();
            for i in 0..n {
                target[i * inputs + r] = graph.degree(i) as f64 * sum / total_degree;
            }
        }
        Self {
            graph,
            inputs,
            alpha: tuning.relaxation,
            anchor: tuning.anchor,
            a,
            x: vec![0.0; n * inputs],
            y: vec![0.0; n * inputs],
            z: vec![0.0; n * inputs],
            sums: vec![0.0; n * inputs],
            target,
        }
    }

    fn len(&self) -> usize {
        self.x.len()
    }

    /// One round (the fast variant's update order: `y`, `z`, then `x`).
    fn step(&mut self) {
        let (n, s) = (self.graph.robots(), self.inputs);
        self.sums.fill(0.0);
        for i in 0..n {
            for &j in self.graph.neighbours(i) {
                for r in 0..s {
                    self.sums[i * s + r] += self.x[j * s + r];
                }
            }
        }
        let (alpha, c) = (self.alpha, self.anchor);
        for i in 0..n {
            let d = self.graph.degree(i).max(1) as f64;
            for r in 0..s {
                let e = i * s + r;
                let (x, sum) = (self.x[e], self.sums[e]);
                self.y[e] += alpha * (d * x - sum);
                self.z[e] = alpha * 0.5 * (d * x + sum) + (1.0 - alpha) * self.z[e];
                self.x[e] = (1.0 - c) * self.z[e] / d - (self.y[e] + self.a[e]) / (2.0 * d);
            }
        }
    }

    /// `r = y + a − target` into `out`.
    fn residual_into(&self, out: &mut [f64]) {
        for (e, r) in out.iter_mut().enumerate() {
            *r = self.y[e] + self.a[e] - self.target[e];
        }
    }
}

/// The last `window` residuals and their inner products.
struct Residuals {
    ring: Vec<Vec<f64>>,
    /// Index of the newest.
    newest: usize,
    count: usize,
}

impl Residuals {
    fn new(window: usize, len: usize) -> Self {
        Self {
            ring: vec![vec![0.0; len]; window],
            newest: 0,
            count: 0,
        }
    }

    /// The slot of the next residual, which becomes the newest.
    fn next_slot(&mut self) -> &mut [f64] {
        self.newest = (self.newest + 1) % self.ring.len();
        self.count += 1;
        &mut self.ring[self.newest]
    }

    /// `⟨r(k), r(k − l)⟩` for every lag held.
    fn products(&self) -> Vec<f64> {
        let w = self.ring.len();
        let newest = &self.ring[self.newest];
        (0..w.min(self.count))
            .map(|l| {
                let other = &self.ring[(self.newest + w - l) % w];
                newest.iter().zip(other).map(|(a, b)| a * b).sum()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use admm_ta_topologies::TopologySpec;

    fn graph(spec: &str, n: usize) -> Graph {
        let spec: TopologySpec = spec.parse().unwrap();
        spec.build(n, 1).unwrap()
    }

    #[test]
    fn weights_sum_to_one_exactly_and_stay_bounded() {
        let g = graph("chain", 20);
        let tuning = FastTuning::for_diameter(19);
        let filter = ReadoutFilter::design(&g, tuning, 16).unwrap();
        for k in 1..=filter.designed_rounds() as u64 + 5 {
            let w = filter.weights(k);
            assert!(w.len() <= 16 && !w.is_empty());
            assert_eq!(w.iter().sum::<i64>(), 1 << WEIGHT_BITS, "round {k}");
            let gain: f64 =
                w.iter().map(|&v| (v as f64).abs()).sum::<f64>() / (1u64 << WEIGHT_BITS) as f64;
            assert!(gain <= MAX_GAIN * 1.001);
        }
        assert_eq!(filter.weights(1), &[1 << WEIGHT_BITS]);
    }

    #[test]
    fn the_design_is_deterministic_and_depends_on_the_graph() {
        let tuning = FastTuning::for_diameter(9);
        let a = ReadoutFilter::design(&graph("chain", 10), tuning, 12).unwrap();
        let b = ReadoutFilter::design(&graph("chain", 10), tuning, 12).unwrap();
        assert_eq!(a, b);
        let ring = ReadoutFilter::design(&graph("ring", 10), tuning, 12).unwrap();
        assert_ne!(a.digest(), ring.digest());
    }

    /// The filtered model residual after a diameter and a few rounds is far below the plain
    /// one (the point of the filter), on a graph with more robots than probes.
    #[test]
    fn filtering_shrinks_the_consensus_error_of_the_model() {
        let n = 40;
        let g = graph("chain", n);
        let tuning = FastTuning::for_diameter(n - 1);
        let filter = ReadoutFilter::design(&g, tuning, 40).unwrap();
        let mut model = Model::new(&g, tuning);
        let mut history: Vec<Vec<f64>> = Vec::new();
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        for k in 1..=(n as u64 + 10) {
            model.step();
            let mut residual = vec![0.0; model.len()];
            model.residual_into(&mut residual);
            history.insert(0, residual);
            let w = filter.weights(k);
            let mut filtered = vec![0.0; model.len()];
            for (l, &g) in w.iter().enumerate() {
                for (f, r) in filtered.iter_mut().zip(&history[l]) {
                    *f += g as f64 / (1u64 << WEIGHT_BITS) as f64 * r;
                }
            }
            if k == n as u64 + 10 {
                let (plain, filtered) = (norm(&history[0]), norm(&filtered));
                assert!(filtered < 0.2 * plain, "{filtered} vs {plain}");
            }
        }
    }

    #[test]
    fn windows_follow_the_budget_and_the_diameter() {
        assert_eq!(ReadoutFilter::window_for(30, 50, 49), MAX_WINDOW);
        assert_eq!(ReadoutFilter::window_for(30, 50, 1), 6);
        assert_eq!(ReadoutFilter::window_for(30, 50, 0), 0);
        assert_eq!(ReadoutFilter::window_for(1000, 1000, 999), 0);
        assert!(ReadoutFilter::window_for(120, 120, 119) < MAX_WINDOW);
    }
}
