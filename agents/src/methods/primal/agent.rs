//! Primal consensus ADMM (Algorithm 1 of the paper), one robot's state machine.
//!
//! Robot `i` keeps `X_i, Q_i ∈ R^{m×n}` (tasks × robots, column-major; column `j` is its
//! estimate of robot `j`'s assignment vector) and exchanges `X_i` with its neighbours. With
//! the neighbours' round-`k` matrices `X_j^k`, one step is
//!
//! ```text
//! Q_i^{k+1} = Q_i^k + ρ Σ_{j∈N(i)} (X_i^k − X_j^k)                                    (7)
//! X_i^{k+1} = argmin_{X ∈ P} α_iᵀ X e_i + ⟨Q_i^{k+1}, X⟩ + ρ|N(i)| ‖X‖² − ρ ⟨S_i, X⟩   (8)
//!           = Π_P( S_i / (2|N(i)|) − (Q_i^{k+1} + α_i e_iᵀ) / (2ρ|N(i)|) ),
//! S_i = Σ_{j∈N(i)} (X_i^k + X_j^k),
//! ```
//!
//! with `P` the relaxed assignment polytope with *all* entries in [0, 1] (as the paper
//! does). (8) uses the freshly updated `Q^{k+1}`: it matches the edge-based derivation and
//! settles about twice as fast as the literal `Q^k` (docs/notes.md, note 8). `X_i^0 = Q_i^0 = 0`.
//! A robot without neighbours (n = 1) uses its own iterate in place of a neighbour's, which
//! turns the step into a proximal-point iteration on its local LP.
//!
//! With [`PrimalParams::fast`] set, the same agent runs the fast variant of
//! [`crate::methods::primal::settings`]: the consensus step of [`crate::methods::primal::fast_consensus`] and the
//! readout of [`crate::methods::primal::readout`] replace the steps above and the per-column rounding.
//!
//! The step works in buffers allocated at construction: one fused pass accumulates the
//! neighbours' sum, updates `Q` and forms the projection input, then the projection writes
//! the new iterate straight into the outgoing payload.

use crate::agent::{AgentAlgorithm, ConsensusAgent, Inbox, NewCostsError, StepReport};
use crate::certify::rounding;
use crate::methods::primal::fast_consensus::FastConsensus;
use crate::methods::primal::readout::GReadout;
use crate::methods::primal::readout_filter::ReadoutFilter;
pub use crate::methods::primal::settings::{PrimalParams, ProjectionPath};
use crate::numerics::projection::{ProjectionStats, QpProjector, TransportPolytopeProjector};
use crate::problem::AssignmentCase;
use crate::problem::general::GeneralProblem;
use faer::{MatMut, MatRef};
use std::cell::RefCell;
use std::sync::Arc;

enum Projector {
    Fast(Box<TransportPolytopeProjector>),
    Qp(QpProjector),
}

/// Robot `index`'s primal consensus ADMM state.
pub struct PrimalAgent {
    index: usize,
    tasks: usize,
    robots: usize,
    degree: usize,
    case: AssignmentCase,
    settings: PrimalParams,
    costs: Vec<f64>,
    x: Vec<f64>,
    q: Vec<f64>,
    z: Vec<f64>,
    projector: Projector,
    rounded: Vec<usize>,
    load: Vec<u32>,
    last_projection: ProjectionStats,
    /// The fast variant's state (`None`: Algorithm 1).
    fast: Option<Box<FastConsensus>>,
    /// Scratch of [`PrimalAgent::certificate_slack_for`]: its assignment problem is solved
    /// in buffers allocated here, not per check (it runs inside the round loop).
    certificate: RefCell<CertificateScratch>,
}

/// The minimiser of `G_i` over the polytope (a readout without tie-break) and room for it.
#[derive(Debug, Clone)]
struct CertificateScratch {
    readout: GReadout,
    best: Vec<usize>,
    load: Vec<u32>,
}

impl PrimalAgent {
    /// Robot `index` of `robots`, with its own costs `α_i` (one per task), `degree = |N(i)|`.
    pub fn new(
        index: usize,
        costs: Vec<f64>,
        robots: usize,
        case: AssignmentCase,
        degree: usize,
        settings: PrimalParams,
    ) -> Self {
        let tasks = costs.len();
        assert!(index < robots && tasks >= 1 && robots >= tasks);
        assert!(
            settings.rho > 0.0 && settings.rho.is_finite(),
            "ρ must be positive"
        );
        let projector = match settings.projection {
            ProjectionPath::Fast => {
                let mut projector = TransportPolytopeProjector::new(tasks, robots, case);
                projector
                    .set_interior_fast_path(settings.fast.is_some_and(|f| f.interior_projection));
                Projector::Fast(Box::new(projector))
            }
            ProjectionPath::Qp => Projector::Qp(QpProjector::new(
                &GeneralProblem::assignment_constraints(robots, tasks, case),
            )),
        };
        Self {
            index,
            tasks,
            robots,
            degree,
            case,
            settings,
            costs,
            x: vec![0.0; tasks * robots],
            q: vec![0.0; tasks * robots],
            z: vec![0.0; tasks * robots],
            projector,
            rounded: vec![0; robots],
            load: vec![0; tasks],
            last_projection: ProjectionStats::default(),
            fast: settings
                .fast
                .map(|f| Box::new(FastConsensus::new(tasks, robots, case, degree, &f))),
            certificate: RefCell::new(CertificateScratch {
                readout: GReadout::new(tasks, robots, case, 0.0),
                best: vec![0; robots],
                load: vec![0; tasks],
            }),
        }
    }

    /// The current iterate `X_i` (column-major tasks × robots).
    pub fn iterate(&self) -> MatRef<'_, f64> {
        MatRef::from_column_major_slice(&self.x, self.tasks, self.robots)
    }

    /// Replaces the robot's own costs `α_i` for the next steps (a new episode of a repeated
    /// assignment). The iterate `X_i` and the multipliers `Q_i` are kept: that is the warm
    /// start. The certificate stays valid (it only needs `Σ_i Q_i = 0`, which no cost
    /// change breaks).
    pub fn set_costs(&mut self, costs: &[f64]) {
        assert_eq!(costs.len(), self.tasks, "one cost per task");
        self.costs.copy_from_slice(costs);
        if let Some(fast) = &mut self.fast {
            // The readout filter extrapolates from the episode's own rounds: a history of
            // the last episode's tail made warm episodes slower than cold ones (50 robots,
            // complete graph: 9 rounds against 3; with the history restarted, 3).
            fast.restart_readout();
        }
    }

    /// Forgets the iterate and the multipliers (a cold start of the next steps).
    pub fn reset(&mut self) {
        self.x.fill(0.0);
        self.q.fill(0.0);
        if let Some(fast) = &mut self.fast {
            fast.reset();
        }
    }

    /// Changes ρ from the next step on. `Q` is kept unscaled (`Q += ρ Σ (X_i − X_j)`), so it
    /// needs no rescaling; every robot must change ρ at the same round. (The fast variant
    /// keeps `Q` as integer multiples of `αρ`: a new ρ rescales it, which keeps
    /// `Σ_i Q_i = 0`; its options refuse schedules, see [`crate::methods::primal::settings`].)
    pub fn set_rho(&mut self, rho: f64) {
        assert!(rho > 0.0 && rho.is_finite(), "ρ must be positive");
        self.settings.rho = rho;
    }

    /// Optimality certificate of the assignment this robot currently rounds to (the
    /// per-column argmax `π` of its iterate).
    ///
    /// With `G_i = Q_i + α_i e_iᵀ`, the robots' `Q_i` sum to zero (each edge adds
    /// `ρ(X_i − X_j)` to one robot and its negative to the other), so `Σ_i G_i = C`, the whole
    /// cost matrix. Hence for any assignment `π`,
    /// `cost(π) − optimum ≤ Σ_i s_i` with `s_i = ⟨G_i, π⟩ − min_{X∈P} ⟨G_i, X⟩ ≥ 0`: if the
    /// robots agree on `π` and their slacks sum to (almost) zero, `π` is optimal — a bound,
    /// not a heuristic. This returns `s_i` (an `m × n` assignment problem, so call it when the
    /// robots agree, not every round), or `∞` when `π` is not a feasible assignment.
    ///
    /// In the fast variant the readout minimises `G_i + E` ([`crate::methods::primal::readout`]): its slack is
    /// at most `n ε` by construction, and nothing is solved here (before the first step,
    /// or when `Σ_i Q_i = 0` can no longer be guaranteed, the general rule applies).
    pub fn certificate_slack(&self) -> f64 {
        if let Some(fast) = &self.fast {
            if !fast.exact() {
                return f64::INFINITY;
            }
            if let Some(bound) = fast.readout.slack_bound() {
                return bound;
            }
        }
        self.certificate_slack_for(&self.rounded)
    }

    /// From the next step on, the fast variant reads its assignment (and its certificate)
    /// from the filtered certificate matrix of [`crate::methods::primal::readout_filter`]; every robot of the
    /// team must be given the same filter. No effect on the paper's variant.
    pub fn set_readout_filter(&mut self, filter: Arc<ReadoutFilter>) {
        if let Some(fast) = &mut self.fast {
            fast.set_filter(filter);
        }
    }

    /// The fast variant's multipliers `K_i` in integer units (`Q_i` is a fixed multiple of
    /// them; they sum to zero over the team exactly); `None` for Algorithm 1.
    pub fn exact_multipliers(&self) -> Option<&[i128]> {
        self.fast.as_ref().map(|f| f.units())
    }

    /// The consensus multipliers `Q_i` (column-major tasks × robots).
    pub fn multipliers(&self) -> &[f64] {
        &self.q
    }

    /// `s_i` of [`PrimalAgent::certificate_slack`] for any assignment (task per robot);
    /// `∞` when it is not feasible.
    pub fn certificate_slack_for(&self, assignment: &[usize]) -> f64 {
        let (m, n) = (self.tasks, self.robots);
        let mut scratch = self.certificate.borrow_mut();
        let CertificateScratch {
            readout,
            best,
            load,
        } = &mut *scratch;
        if assignment.len() != n
            || assignment.iter().any(|&t| t >= m)
            || !rounding::covers(assignment, self.case, load)
        {
            return f64::INFINITY;
        }
        // The certificate matrix's multipliers: `Q_i`, or the fast variant's filtered `Q̂_i`
        // (every robot of the team uses the same rule at every round).
        let q = match &self.fast {
            Some(fast) => fast.certificate_multipliers(&self.q),
            None => &self.q,
        };
        // The exact minimiser of `G_i` over the polytope (no tie-break: ε = 0).
        readout.read(q, &self.costs, self.index, best);
        if readout.slack_bound().is_none() {
            // A non-finite iterate: no certificate.
            return f64::INFINITY;
        }
        let g =
            |t: usize, j: usize| q[j * m + t] + if j == self.index { self.costs[t] } else { 0.0 };
        let value = |a: &[usize]| a.iter().enumerate().map(|(j, &t)| g(t, j)).sum::<f64>();
        (value(assignment) - value(best)).max(0.0)
    }

    /// Statistics of the last projection.
    pub fn last_projection(&self) -> ProjectionStats {
        self.last_projection
    }

    pub fn index(&self) -> usize {
        self.index
    }

    /// Builds the projection input `z` (and updates `Q`) from the neighbours' iterates;
    /// returns the consensus residual.
    fn prepare_projection_input(&mut self, inbox: &dyn Inbox) -> f64 {
        let mut disagreement: f64 = 0.0;
        self.z.fill(0.0);
        let neighbours = inbox.len();
        if neighbours == 0 {
            self.z.copy_from_slice(&self.x);
        }
        if let Some(fast) = &mut self.fast {
            fast.clear_neighbours();
        }
        for k in 0..neighbours {
            let theirs = inbox.payload(k);
            assert_eq!(
                theirs.len(),
                self.x.len(),
                "neighbour payload has the wrong length"
            );
            disagreement = disagreement.max(accumulate_and_compare(&mut self.z, &self.x, theirs));
            if let Some(fast) = &mut self.fast {
                fast.add_neighbour(theirs);
            }
        }
        let degree = neighbours.max(1) as f64;
        let rho = self.settings.rho;
        let (half_mean, half_scaled) = (0.5 / degree, 0.5 / (rho * degree));
        if let Some(fast) = &mut self.fast {
            fast.update(
                &mut self.z,
                &mut self.q,
                &self.x,
                neighbours,
                rho,
                self.tasks,
            );
        } else {
            for ((s, q), mine) in self.z.iter_mut().zip(&mut self.q).zip(&self.x) {
                let neighbour_sum = *s;
                *q += rho * (degree * mine - neighbour_sum);
                *s = (degree * mine + neighbour_sum) * half_mean - *q * half_scaled;
            }
        }
        let own = &mut self.z[self.index * self.tasks..(self.index + 1) * self.tasks];
        for (s, alpha) in own.iter_mut().zip(&self.costs) {
            *s -= alpha * half_scaled;
        }
        disagreement
    }

    /// Rounds the current iterate column by column (the fast variant: reads `G_i`); returns
    /// the distance of the iterate (whole, own column) from that rounding and a digest of it.
    fn inspect_rounding(&mut self) -> (f64, f64, u64) {
        match &mut self.fast {
            Some(fast) => fast.read(&self.q, &self.costs, self.index, &mut self.rounded),
            None => rounding::argmax_assignment(&self.x, self.tasks, &mut self.rounded),
        }
        let feasible = rounding::covers(&self.rounded, self.case, &mut self.load);
        // Robots whose readout filters differ read different matrices: they must not agree.
        let filter = self.fast.as_ref().map_or(0, |f| f.filter_digest());
        let mut digest: u64 = 0xcbf2_9ce4_8422_2325 ^ filter;
        let (mut gap, mut own_gap) = (0.0f64, 0.0f64);
        for (j, &task) in self.rounded.iter().enumerate() {
            digest = (digest ^ task as u64).wrapping_mul(0x0100_0000_01b3);
            let column = &self.x[j * self.tasks..(j + 1) * self.tasks];
            let distance = column
                .iter()
                .enumerate()
                .map(|(t, v)| (v - if t == task { 1.0 } else { 0.0 }).abs())
                .fold(0.0, f64::max);
            gap = gap.max(distance);
            if j == self.index {
                own_gap = distance;
            }
        }
        if !feasible {
            gap = f64::INFINITY;
        }
        (gap, own_gap, digest)
    }
}

/// `sum += theirs`, returning `max |mine − theirs|`; in lanes of 8 so it vectorises.
fn accumulate_and_compare(sum: &mut [f64], mine: &[f64], theirs: &[f64]) -> f64 {
    const LANES: usize = 8;
    let mut lane_max = [0.0f64; LANES];
    let mut sums = sum.chunks_exact_mut(LANES);
    let mut mines = mine.chunks_exact(LANES);
    let mut others = theirs.chunks_exact(LANES);
    for ((s, a), b) in (&mut sums).zip(&mut mines).zip(&mut others) {
        for l in 0..LANES {
            s[l] += b[l];
            let d = (a[l] - b[l]).abs();
            lane_max[l] = if d > lane_max[l] { d } else { lane_max[l] };
        }
    }
    let mut worst = lane_max.iter().fold(0.0f64, |w, &d| w.max(d));
    for ((s, a), b) in sums
        .into_remainder()
        .iter_mut()
        .zip(mines.remainder())
        .zip(others.remainder())
    {
        *s += b;
        worst = worst.max((a - b).abs());
    }
    worst
}

impl ConsensusAgent for PrimalAgent {
    fn payload_len(&self) -> usize {
        self.tasks * self.robots
    }

    fn write_initial_payload(&self, out: &mut [f64]) {
        out.copy_from_slice(&self.x);
    }

    fn step(&mut self, inbox: &dyn Inbox, out: &mut [f64]) -> StepReport {
        debug_assert_eq!(inbox.len(), self.degree, "inbox does not match the degree");
        let disagreement = self.prepare_projection_input(inbox);
        let (m, n) = (self.tasks, self.robots);
        let stats = match &mut self.projector {
            Projector::Fast(p) => p.project(
                MatRef::from_column_major_slice(&self.z, m, n),
                MatMut::from_column_major_slice_mut(out, m, n),
            ),
            Projector::Qp(p) => {
                let solved = p.project(&self.z, out).is_ok();
                ProjectionStats {
                    newton_steps: 0,
                    evaluations: 0,
                    residual: if solved { 0.0 } else { f64::INFINITY },
                    converged: solved,
                }
            }
        };
        self.last_projection = stats;
        if self.fast.is_some() {
            FastConsensus::snap(out);
        }
        let change = out
            .iter()
            .zip(&self.x)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        self.x.copy_from_slice(out);
        let (integrality_gap, own_integrality_gap, assignment_digest) = self.inspect_rounding();
        StepReport {
            disagreement,
            change,
            inner_iterations: stats.newton_steps,
            inner_converged: stats.converged,
            integrality_gap,
            own_integrality_gap,
            assignment_digest,
        }
    }

    fn decide(&self) -> usize {
        if let Some(fast) = &self.fast
            && fast.readout.slack_bound().is_some()
        {
            // The readout is a feasible assignment, the same at robots that agree (the
            // iterate stays near the polytope's centre in the fast variant).
            return self.rounded[self.index];
        }
        rounding::local_assignment(&self.x, self.tasks, self.robots, self.case)[self.index]
    }

    fn rounded_task(&self) -> usize {
        self.rounded[self.index]
    }

    fn certificate_slack(&self) -> f64 {
        PrimalAgent::certificate_slack(self)
    }

    fn own_column(&self) -> &[f64] {
        &self.x[self.index * self.tasks..(self.index + 1) * self.tasks]
    }
}

impl AgentAlgorithm for PrimalAgent {
    fn set_rho(&mut self, rho: f64) {
        PrimalAgent::set_rho(self, rho);
    }

    fn set_costs(&mut self, costs: &[f64], warm: bool) -> Result<(), NewCostsError> {
        if costs.len() != self.tasks {
            return Err(NewCostsError::WrongLength { got: costs.len() });
        }
        PrimalAgent::set_costs(self, costs);
        if !warm {
            self.reset();
        }
        Ok(())
    }
}
