//! The interface between an agent's algorithm and whatever carries its messages.
//!
//! An agent is a state machine with a pure [`ConsensusAgent::step`]: given the round-`k`
//! payloads of its neighbours (an [`Inbox`]), it updates its own state and writes its
//! round-`k+1` payload into `out`. Transports (lockstep simulation, threads, processes)
//! differ only in how they fill the inbox and deliver `out`, so they all produce the same
//! iterates.

/// Read access to the neighbours' payloads of the current round, in neighbour-list order.
pub trait Inbox {
    /// Number of neighbours `|N(i)|`.
    fn len(&self) -> usize;
    /// Payload of the `k`-th neighbour.
    fn payload(&self, k: usize) -> &[f64];
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl Inbox for Vec<&[f64]> {
    fn len(&self) -> usize {
        Vec::len(self)
    }
    fn payload(&self, k: usize) -> &[f64] {
        self[k]
    }
}

/// Local facts an agent learns in one step: what stopping rules and observers may use.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepReport {
    /// `max_j ‖X_i^k − X_j^k‖∞` over the neighbours (consensus residual).
    pub disagreement: f64,
    /// `‖X_i^{k+1} − X_i^k‖∞`.
    pub change: f64,
    /// Inner iterations of the local solve (Newton steps of the projection).
    pub inner_iterations: usize,
    /// Whether the local inner solve met its tolerance.
    pub inner_converged: bool,
    /// Max-norm distance of the agent's whole iterate from its rounded view of the team's
    /// assignment (`∞` when that view is not a feasible assignment).
    pub integrality_gap: f64,
    /// The same distance over the agent's own column only.
    pub own_integrality_gap: f64,
    /// Hash of the agent's rounded view of the whole team's assignment.
    pub assignment_digest: u64,
}

/// Why a neighbour's payload is refused before a step reads it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PayloadError {
    #[error("{got} values, expected {expected}")]
    Length { got: usize, expected: usize },
    #[error("value {index} is {value}")]
    NotFinite { index: usize, value: f64 },
    /// A value outside what the method ever sends.
    #[error("{part} is {value}")]
    BadValue { part: PayloadPart, value: f64 },
    /// A block of values that is neither all known nor all unknown, or not finite.
    #[error("{part} is partly unknown or not finite")]
    BadBlock { part: PayloadPart },
}

/// A named part of a payload, for messages: `bid on task 3`, `price raise`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PayloadPart {
    pub name: &'static str,
    pub index: Option<usize>,
}

impl PayloadPart {
    /// Part `index` of the kind `name` (`bid on task`).
    pub fn at(name: &'static str, index: usize) -> Self {
        Self {
            name,
            index: Some(index),
        }
    }

    /// The one part called `name`.
    pub fn named(name: &'static str) -> Self {
        Self { name, index: None }
    }
}

impl std::fmt::Display for PayloadPart {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.index {
            Some(index) => write!(f, "{} {index}", self.name),
            None => f.write_str(self.name),
        }
    }
}

/// The index of the first value of `values` that is not finite, if any: one pass without
/// an early exit (the compiler makes it a vector loop: a neighbour's payload is checked
/// every round), and a second only when there is one to find.
pub fn first_not_finite(values: &[f64]) -> Option<usize> {
    let finite = values
        .iter()
        .fold(true, |all, v| all & (v.abs() < f64::INFINITY));
    if finite {
        None
    } else {
        values.iter().position(|v| !v.is_finite())
    }
}

/// `Err` unless `payload` has `expected` values.
pub fn check_length(payload: &[f64], expected: usize) -> Result<(), PayloadError> {
    if payload.len() == expected {
        Ok(())
    } else {
        Err(PayloadError::Length {
            got: payload.len(),
            expected,
        })
    }
}

/// Why an agent takes no new costs.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NewCostsError {
    #[error("the method takes no new costs between episodes")]
    Unsupported,
    #[error("{got} costs for a robot with another number of tasks")]
    WrongLength { got: usize },
    #[error("every task is forbidden to the robot")]
    NoAllowedTask,
}

/// One robot's algorithm.
pub trait ConsensusAgent {
    /// Length of the payload exchanged every round.
    fn payload_len(&self) -> usize;
    /// The round-0 payload.
    fn write_initial_payload(&self, out: &mut [f64]);
    /// Checks a neighbour's payload before [`ConsensusAgent::step`] reads it: a corrupted
    /// message (wrong length, NaN, a value outside what the method ever sends) is refused
    /// with a one-line reason instead of flowing into the solution. The default accepts
    /// `payload_len` finite numbers; methods with sentinels override it.
    fn check_payload(&self, payload: &[f64]) -> Result<(), PayloadError> {
        check_length(payload, self.payload_len())?;
        match first_not_finite(payload) {
            Some(index) => Err(PayloadError::NotFinite {
                index,
                value: payload[index],
            }),
            None => Ok(()),
        }
    }
    /// One iteration: read neighbours' round-`k` payloads, write the round-`k+1` payload.
    fn step(&mut self, inbox: &dyn Inbox, out: &mut [f64]) -> StepReport;
    /// The robot's own task, rounded from its current iterate so that robots holding the
    /// same iterate make consistent choices.
    fn decide(&self) -> usize;
    /// The robot's own task in the per-column rounding that
    /// [`StepReport::assignment_digest`] describes.
    fn rounded_task(&self) -> usize;
    /// Optimality-certificate slack `s_i ≥ 0` of the assignment the robot rounds to: if all
    /// robots round to the same assignment, its cost exceeds the optimum by at most `Σ_i s_i`
    /// (`∞` when there is no such certificate). Costs one `m × n` assignment problem.
    fn certificate_slack(&self) -> f64;
    /// The robot's own relaxed assignment vector `x_i ∈ [0, 1]^m` (its own column), for
    /// observers such as the paper's "within 0.1% of the optimum" criterion.
    fn own_column(&self) -> &[f64];
}

/// A method's agent as its registration in [`crate::methods`] builds it: a
/// [`ConsensusAgent`] whose penalty and costs may change between steps. Runners hold it as
/// `Box<dyn AgentAlgorithm>` inside a [`crate::method::agent::MethodAgent`], so a new method is
/// one module implementing this trait plus one registration, and no runner matches on
/// methods. The defaults suit a method without a penalty that solves one problem.
pub trait AgentAlgorithm: ConsensusAgent + Send + std::any::Any {
    /// Changes ρ from the next step on (every robot at the same round); methods without a
    /// penalty ignore it.
    fn set_rho(&mut self, _rho: f64) {}

    /// New own costs for the next episode of a repeated assignment (one per task of the
    /// agent's problem; `+∞` marks a forbidden pair for the methods that keep them apart,
    /// the others take the normalisation's penalty), warm-started from the current iterates
    /// or (`warm = false`) from zero.
    fn set_costs(&mut self, _costs: &[f64], _warm: bool) -> Result<(), NewCostsError> {
        Err(NewCostsError::Unsupported)
    }
}
