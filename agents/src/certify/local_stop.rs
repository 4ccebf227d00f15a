//! Decentralized stopping: a certified stop that every robot takes at the same round while
//! seeing only its neighbours.
//!
//! # The local predicate
//! After gathering the round-`r` messages, robot `i` holds its own state `(X_i^r, Q_i^r)` and
//! its neighbours' assignment digests. Its predicate `p_i(r)` is true when
//! * `r` is a check round (`r % every == 0`: a schedule every robot shares, so the
//!   certificate is evaluated by all robots on the *same* round),
//! * its rounded assignment has equalled every neighbour's for at least `after` rounds, and
//! * its optimality-certificate slack `s_i(r)` ([`ConsensusAgent::certificate_slack`]) is at
//!   most `tolerance / n`.
//!
//! If `p_j(r)` holds for every robot `j`, the graph is connected so all robots round to one
//! assignment `π`, and `Σ_j s_j(r) ≤ tolerance` proves `π` optimal to that tolerance (the
//! certificate is a bound, see the primal agent). So the team may stop once everybody knows
//! that *all* predicates held at one round.
//!
//! # The agreement protocol (header bit window)
//! Each message carries a window `V_i(r)` of bits; bit `s` of the window sent with round `r`
//! is the AND of `p_j(r − 1 − s)` over all robots `j` within `s` hops of `i`:
//!
//! ```text
//! V_i(r+1) = p_i(r)  |  ( (V_i(r) & AND_{j ∈ N(i)} V_j(r)) << 1 )
//! ```
//!
//! After gathering round `r`, `T = V_i(r) & AND_j V_j(r)` has in bit `D − 1` (`D` the graph
//! diameter) the AND of `p_j(r − D)` over *all* robots — the same bit at every robot. So every
//! robot stops after gathering the same round `r`, having certified the assignment of round
//! `r − D`; nobody publishes round `r + 1`, so nobody waits for a neighbour that stopped.
//! The price is `D` extra rounds (plus up to `every − 1` for the schedule) over a centralized
//! check. Each robot remembers its own rounded task of the last `D + 1` rounds and reports the
//! one of the certified round. A window holds [`MAX_DIAMETER`] bits.
//!
//! [`ConsensusAgent::certificate_slack`]: crate::agent::ConsensusAgent::certificate_slack

/// Bits of the agreement window carried in every message header.
pub type Window = [u64; 4];

/// Largest graph diameter the window can carry.
pub const MAX_DIAMETER: usize = 256;

/// Check rounds happen every this many rounds.
pub const CHECK_EVERY: u64 = 5;
/// A robot checks its certificate once it has agreed with its neighbours this many rounds.
pub const CHECK_AFTER: u32 = 3;

/// What a robot knows of one neighbour's latest message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NeighbourState {
    pub digest: u64,
    pub window: Window,
}

/// The verdict after a gathered round.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    Continue,
    /// Every robot certified the assignment of `certified_round`; this robot's task in it.
    Certified {
        certified_round: u64,
        task: usize,
    },
}

/// One robot's side of the decentralized certified stop.
#[derive(Debug, Clone)]
pub struct LocalCertifiedStop {
    diameter: usize,
    tolerance: f64,
    every: u64,
    after: u32,
    streak: u32,
    /// Own task of rounds `r − D ..= r`, indexed by `r % (D + 1)`.
    own_tasks: Vec<usize>,
    next_window: Window,
}

/// Reasons the protocol cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LocalStopError {
    #[error(
        "the graph diameter {0} exceeds the {MAX_DIAMETER} rounds the stop protocol's header window carries"
    )]
    DiameterTooLarge(usize),
    #[error("the stop tolerance must be positive and finite, got {0}")]
    BadTolerance(f64),
}

impl LocalCertifiedStop {
    /// A robot of a team of `robots` on a graph of `diameter`, certifying to an absolute total
    /// cost `tolerance`.
    pub fn new(diameter: usize, robots: usize, tolerance: f64) -> Result<Self, LocalStopError> {
        if diameter > MAX_DIAMETER {
            return Err(LocalStopError::DiameterTooLarge(diameter));
        }
        if !(tolerance > 0.0 && tolerance.is_finite()) {
            return Err(LocalStopError::BadTolerance(tolerance));
        }
        Ok(Self {
            diameter,
            tolerance: tolerance / robots.max(1) as f64,
            every: CHECK_EVERY,
            after: CHECK_AFTER,
            streak: 0,
            own_tasks: vec![usize::MAX; diameter + 1],
            next_window: Window::default(),
        })
    }

    /// Checks the certificate on rounds that are multiples of `every` once the robot has
    /// agreed with its neighbours for more than `after` rounds (defaults [`CHECK_EVERY`],
    /// [`CHECK_AFTER`]; a method's cadence is
    /// [`crate::method::team::TeamMethod::stop_cadence`]). Every robot must use the same.
    pub fn with_cadence(mut self, (every, after): (u64, u32)) -> Self {
        self.every = every.max(1);
        self.after = after;
        self
    }

    /// The window to send with the next round's message.
    pub fn next_window(&self) -> Window {
        self.next_window
    }

    /// After gathering round `round`: `mine` is this robot's round-`round` message,
    /// `theirs` its neighbours'; `own_task` its rounded task now; `slack` evaluates its
    /// certificate (called only on check rounds after enough agreement).
    pub fn observe(
        &mut self,
        round: u64,
        mine: NeighbourState,
        theirs: impl Iterator<Item = NeighbourState> + Clone,
        own_task: usize,
        slack: impl FnOnce() -> f64,
    ) -> Verdict {
        let agreed = theirs.clone().all(|t| t.digest == mine.digest);
        self.streak = if agreed { self.streak + 1 } else { 0 };
        let slot = |r: u64| (r % (self.diameter as u64 + 1)) as usize;
        self.own_tasks[slot(round)] = own_task;
        let predicate = round.is_multiple_of(self.every)
            && self.streak > self.after
            && slack() <= self.tolerance;
        let mut combined = mine.window;
        for t in theirs {
            for (c, w) in combined.iter_mut().zip(t.window) {
                *c &= w;
            }
        }
        self.next_window = shift_left(combined);
        self.next_window[0] |= predicate as u64;
        let everyone = if self.diameter == 0 {
            predicate
        } else {
            bit(&combined, self.diameter - 1)
        };
        let certified_round = round.saturating_sub(self.diameter as u64);
        if everyone && round >= self.diameter as u64 {
            Verdict::Certified {
                certified_round,
                task: self.own_tasks[slot(certified_round)],
            }
        } else {
            Verdict::Continue
        }
    }
}

fn shift_left(w: Window) -> Window {
    let mut out = Window::default();
    for k in 0..w.len() {
        out[k] = (w[k] << 1) | if k > 0 { w[k - 1] >> 63 } else { 0 };
    }
    out
}

fn bit(w: &Window, s: usize) -> bool {
    (w[s / 64] >> (s % 64)) & 1 == 1
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs the protocol in lockstep on a chain with given predicate patterns (slack 0 or ∞
    /// per robot and round) and returns each robot's first verdict round.
    fn stops(robots: usize, ok: impl Fn(usize, u64) -> bool, rounds: u64) -> Vec<Option<u64>> {
        let diameter = robots - 1;
        let mut stops: Vec<_> = (0..robots)
            .map(|_| LocalCertifiedStop::new(diameter, robots, 1e-9).unwrap())
            .collect();
        let mut states = vec![NeighbourState::default(); robots];
        let mut first = vec![None; robots];
        for r in 0..rounds {
            let mut next = states.clone();
            for i in 0..robots {
                let neighbours: Vec<NeighbourState> = [i.wrapping_sub(1), i + 1]
                    .into_iter()
                    .filter(|&j| j < robots)
                    .map(|j| states[j])
                    .collect();
                let verdict = stops[i].observe(r, states[i], neighbours.iter().copied(), 7, || {
                    if ok(i, r) { 0.0 } else { f64::INFINITY }
                });
                if let Verdict::Certified {
                    certified_round, ..
                } = verdict
                {
                    first[i].get_or_insert(r);
                    assert_eq!(certified_round, r - diameter as u64);
                    assert!((0..robots).all(|j| ok(j, certified_round)));
                }
                next[i].window = stops[i].next_window();
            }
            states = next;
        }
        first
    }

    #[test]
    fn everybody_stops_at_the_same_round_diameter_later() {
        let first = stops(6, |_, r| r >= 20, 60);
        // First check round with a long enough streak is 20; the window then needs D = 5
        // more rounds to cross the chain.
        assert_eq!(first, vec![Some(25); 6]);
    }

    #[test]
    fn one_robot_failing_once_delays_everybody_equally() {
        let first = stops(5, |i, r| r >= 10 && !(i == 3 && r == 10), 60);
        assert_eq!(first, vec![Some(19); 5]);
    }

    #[test]
    fn no_stop_when_some_robot_never_certifies() {
        let first = stops(4, |i, r| i != 2 && r > 0, 80);
        assert_eq!(first, vec![None; 4]);
    }

    #[test]
    fn diameter_beyond_the_window_is_refused() {
        assert!(matches!(
            LocalCertifiedStop::new(MAX_DIAMETER + 1, 300, 1.0),
            Err(LocalStopError::DiameterTooLarge(_))
        ));
    }
}
