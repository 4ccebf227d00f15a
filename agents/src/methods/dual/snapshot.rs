//! The fast dual variant's certificate: the team's claims, flooded in snapshots, and common
//! prices that price them, computed by a distributed Bellman–Ford beside the multipliers.
//!
//! # What has to be proved
//! A robot sees its own cost row only, so optimality has to be proved by prices: weak
//! duality needs *one* price vector `ȳ` for the whole team. Let `π` be the team's
//! assignment, `α_i` robot `i`'s costs and `r_{i,t} = α_{i,t} + ȳ_t` its reduced costs
//! (Case 2's coverage prices are `λ = −ȳ ≥ 0`). Relaxing the task constraints with `ȳ`
//! (each robot keeps "exactly one allowed task" as its own constraint) bounds
//!
//! ```text
//! cost(π) − OPT ≤ Σ_i [ r_{i,π_i} − min_t r_{i,t} ]  +  Σ_t λ_t (cover_t − 1)   (Case 2)
//! ```
//!
//! when `π` covers every task (once, in Case 1).
//!
//! # Claims
//! Every `P = max(D, 1)` rounds (`D` the diameter) every robot puts its rounded task into a
//! snapshot that the messages flood, each task keeping its smallest claimer; `P ≥ D` rounds
//! later every robot holds the same claims: the snapshot *settles*, at the same round
//! everywhere. A robot then knows whether every task is claimed, and whether it is its
//! task's smallest claimer: the *other* claimers of a task number exactly `cover_t − 1`, so
//! each of them charges its task's `λ` to its own slack and the slacks sum to the bound.
//!
//! # Prices that price the claims
//! `π` is optimal exactly when prices exist with `r_{i,π_i} ≤ r_{i,t}` for every robot and
//! task: difference constraints `ȳ_{π_i} ≤ ȳ_t + (α_{i,t} − α_{i,π_i})`, whose greatest
//! solution below 0 is a shortest-path potential. The robots compute it together: each
//! keeps a potential vector, takes the elementwise minimum with its neighbours' (a
//! min-flood: exact, idempotent) and lowers its own task's entry where one of its own
//! constraints is violated by more than `ε` (a Bellman–Ford relaxation). Values only fall,
//! so once `π` is optimal and fixed they stop falling after finitely many rounds, the same
//! at every robot; while `π` is not optimal a negative cycle keeps them falling.
//!
//! In Case 2 an extra claimer's task must end at `λ = 0`, which the greatest solution gives
//! (an optimal dual with `λ = 0` on over-covered tasks exists, and the greatest solution is
//! above it) but potentials lowered while `π` was still changing may not. So in Case 2 all
//! robots set their potentials back to 0 at the same round (and count as moved in it) when
//! a settling snapshot's claims differ from the last settled ones (every robot sees the
//! same claims at the same round), and in any case every `(m + 2) P` rounds — a claimer
//! that moved between two tasks others claim first leaves the claims unchanged, and the
//! relaxations may need up to `m` hops of up to `D` rounds each to settle, so a shorter
//! period could cut them off for good. Case 1 needs any solution and never resets.
//!
//! A robot whose potentials did not change in a round held, the round before, potentials no
//! larger than any neighbour's, and meets its own constraints within `ε`. So if *every*
//! robot's potentials stood still in the same round, all held the same vector (the graph is
//! connected) and every slack is at most `ε`: the decentralized stop
//! ([`crate::certify::local_stop`]) asks exactly that every robot's predicate holds at one
//! round. A robot's slack is therefore `r_{π_i} − min_t r_t` (+ `λ_{π_i}` when it is an extra
//! claimer in Case 2) when its potentials stood still, every task is claimed in the settled
//! snapshot (once in Case 1) and its task is the one it claimed; ∞ otherwise. The multipliers
//! of the ADMM iteration do not enter the proof at all: they only steer the robots to an
//! optimal `π`, and the proof follows within a few rounds of the claims settling.
//!
//! # Lent potentials
//! In Case 1 the augmenting finish ([`crate::methods::dual::finish`]) sends its moves in
//! the potentials' place while it computes its labels: every robot knows those steps, keeps its
//! potentials standing (neither merged nor relaxed) and proves nothing meanwhile; a finish
//! that reaches a full assignment hands over prices that price it ([`Snapshot::seed`]).
//!
//! # Layout of the payload section
//! `[ȳ_0 … ȳ_{m−1}, packed claims]`. A claim is a code: 0 when nobody claimed the task yet,
//! `r + 1` for robot `r`. Codes take `b` bits, enough for `n` (`b` = 7 for 100 robots), and
//! [`claims_per_word`] of them share one value as the integer `Σ_j code_j 2^{jb} < 2^53`
//! (exact in an `f64`, finite, the same on every transport): `⌈m/k⌉` values instead of `m`
//! (15 instead of 100 for 100 robots and tasks).
//!
//! Size: one certificate — the packing, the claims and the potentials share one robot's
//! state; about 150 lines are its unit tests.

use crate::agent::first_not_finite;
use crate::problem::AssignmentCase;

/// Values of the certificate's payload section for `robots` robots and `tasks` tasks.
pub const fn words(robots: usize, tasks: usize) -> usize {
    tasks + tasks.div_ceil(claims_per_word(robots))
}

/// Bits of one claim code (`0..=robots`).
const fn code_bits(robots: usize) -> u32 {
    let bits = usize::BITS - robots.leading_zeros();
    if bits == 0 { 1 } else { bits }
}

/// Claims packed into one payload value for a team of `robots`: as many codes as fit in
/// the 53 bits an `f64` holds exactly.
pub const fn claims_per_word(robots: usize) -> usize {
    let per = (f64::MANTISSA_DIGITS / code_bits(robots)) as usize;
    if per == 0 { 1 } else { per }
}

/// No claim yet (claims of robot `r` are `r + 1`).
const UNCLAIMED: u64 = 0;

/// How codes `0..=max` are packed into payload values (a team's claims: `max` = robots).
#[derive(Debug, Clone, Copy)]
pub(super) struct Packing {
    robots: usize,
    bits: u32,
    per_word: usize,
}

impl Packing {
    /// Whether codes up to `max` fit the 53 bits of an `f64` at all.
    pub(super) const fn fits(max: usize) -> bool {
        code_bits(max) <= f64::MANTISSA_DIGITS
    }

    /// Values needed for `codes` codes up to `max`.
    pub(super) const fn words(max: usize, codes: usize) -> usize {
        codes.div_ceil(claims_per_word(max))
    }

    pub(super) fn new(robots: usize) -> Self {
        assert!(
            code_bits(robots) <= f64::MANTISSA_DIGITS,
            "claim codes of {robots} robots do not fit an f64"
        );
        Self {
            robots,
            bits: code_bits(robots),
            per_word: claims_per_word(robots),
        }
    }

    /// Code `j` of a packed value (read as an integer; `as` saturates, never panics).
    pub(super) fn code(self, word: u64, j: usize) -> u64 {
        (word >> (j as u32 * self.bits)) & ((1u64 << self.bits) - 1)
    }

    /// `word` with its code `j` replaced by `code`.
    pub(super) fn with_code(self, word: u64, j: usize, code: u64) -> u64 {
        let shift = j as u32 * self.bits;
        (word & !(((1u64 << self.bits) - 1) << shift)) | code << shift
    }

    /// Sets code `index` of the packed `words` (as [`Packing::pack`] writes them) to `code`.
    pub(super) fn set(self, words: &mut [u64], index: usize, code: u64) {
        let word = &mut words[index / self.per_word];
        *word = self.with_code(*word, index % self.per_word, code);
    }

    /// The packed value of up to `per_word` codes: an integer below 2^53, exact.
    pub(super) fn pack(self, codes: &[u64]) -> f64 {
        let word = codes
            .iter()
            .enumerate()
            .fold(0u64, |w, (j, &code)| w | code << (j as u32 * self.bits));
        word as f64
    }

    /// Codes in one value.
    pub(super) fn per_word(self) -> usize {
        self.per_word
    }

    /// Whether `word` is what [`Packing::pack`] writes for `codes` codes of this team.
    pub(super) fn holds(self, word: f64, codes: usize) -> bool {
        let used = codes as u32 * self.bits;
        debug_assert!(used <= f64::MANTISSA_DIGITS, "{codes} codes in one value");
        // An integer below 2^64 survives the round trip; `as` saturates (2^64 and above
        // come back as 2^64, refused by the shift below) and makes NaN 0.
        let bits = word as u64;
        if bits as f64 != word || bits.checked_shr(used).is_some_and(|above| above != 0) {
            return false;
        }
        // Every code of `bits` bits is one of this team's when the largest is.
        let all_codes = (1u64 << self.bits) - 1 <= self.robots as u64;
        all_codes || (0..codes).all(|j| self.code(bits, j) <= self.robots as u64)
    }
}

/// One robot's side of the certificate.
#[derive(Debug, Clone)]
pub struct Snapshot {
    index: usize,
    packing: Packing,
    period: u64,
    /// Case 2: potentials restart when the settling claims change, and every this many
    /// rounds.
    reset: Option<u64>,
    /// Relaxations smaller than this are not made (rounding never cycles; every slack of a
    /// stable potential is at most `ε`).
    epsilon: f64,
    potentials: Vec<f64>,
    before: Vec<f64>,
    stable: bool,
    /// This step's messages carry something else in the potentials' place (Case 1's
    /// finish, [`crate::methods::dual::finish`]): the potentials stand, unproven.
    lent: bool,
    flooding: Claims,
    settled: Claims,
}

/// The claims of one snapshot.
#[derive(Debug, Clone)]
struct Claims {
    /// Per task the smallest claimer's code (robot + 1), or [`UNCLAIMED`].
    claims: Vec<u64>,
    /// The claims packed as they are sent (merging skips a neighbour's equal value).
    packed: Vec<u64>,
    /// The robot's own task when the snapshot started.
    task: Option<usize>,
}

impl Claims {
    fn empty(tasks: usize, packing: Packing) -> Self {
        Self {
            claims: vec![UNCLAIMED; tasks],
            packed: vec![0; tasks.div_ceil(packing.per_word)],
            task: None,
        }
    }

    /// Claims nothing but `task`, with the robot's `code`.
    fn start(&mut self, task: Option<usize>, code: u64, packing: Packing) {
        self.claims.fill(UNCLAIMED);
        self.packed.fill(0);
        if let Some(task) = task {
            self.claims[task] = code;
            packing.set(&mut self.packed, task, code);
        }
        self.task = task;
    }
}

impl Snapshot {
    /// Robot `index` of `robots`' side, on a graph of diameter `diameter`, relaxing by more
    /// than `epsilon` only.
    pub fn new(
        index: usize,
        robots: usize,
        tasks: usize,
        case: AssignmentCase,
        diameter: usize,
        epsilon: f64,
    ) -> Self {
        assert!(epsilon > 0.0 && epsilon.is_finite(), "ε must be positive");
        assert!(index < robots, "robot {index} of {robots}");
        let period = diameter.max(1) as u64;
        let packing = Packing::new(robots);
        Self {
            index,
            packing,
            period,
            reset: (case == AssignmentCase::Two).then_some(period * (tasks as u64 + 2)),
            epsilon,
            potentials: vec![0.0; tasks],
            before: vec![0.0; tasks],
            stable: false,
            lent: false,
            flooding: Claims::empty(tasks, packing),
            settled: Claims::empty(tasks, packing),
        }
    }

    /// The section of a message sent before any step: potentials 0, nothing claimed.
    pub fn write_empty(out: &mut [f64]) {
        out.fill(0.0);
    }

    /// The robot's own claim code.
    fn own_code(&self) -> u64 {
        self.index as u64 + 1
    }

    /// Starts a step: remembers the potentials the neighbours saw. `lent`: the messages of
    /// this step carry the finish's moves in the potentials' place (every robot lends at
    /// the same steps): the potentials are neither merged nor relaxed, and prove nothing.
    pub fn begin(&mut self, lent: bool) {
        self.before.copy_from_slice(&self.potentials);
        self.lent = lent;
    }

    /// Checks a neighbour's section: finite potentials, and packed claims that are integers
    /// holding codes of this team (`0..=robots`) only. Returns the offending value's index
    /// within the section.
    pub fn check(&self, theirs: &[f64]) -> Result<(), usize> {
        let tasks = self.potentials.len();
        if let Some(t) = first_not_finite(&theirs[..tasks]) {
            return Err(t);
        }
        let per_word = self.packing.per_word;
        for (w, &word) in theirs[tasks..].iter().enumerate() {
            let codes = tasks.saturating_sub(w * per_word).min(per_word);
            if !self.packing.holds(word, codes) {
                return Err(tasks + w);
            }
        }
        Ok(())
    }

    /// Merges a neighbour's section of the round gathered at step `step` (its claims are
    /// ignored at step 0: those are the initial messages, sent before the first snapshot).
    pub fn merge(&mut self, step: u64, theirs: &[f64]) {
        let tasks = self.potentials.len();
        debug_assert_eq!(theirs.len(), words(self.packing.robots, tasks));
        if !self.lent {
            for (mine, &v) in self.potentials.iter_mut().zip(&theirs[..tasks]) {
                *mine = mine.min(v);
            }
        }
        if step == 0 {
            return;
        }
        let packing = self.packing;
        let flooding = &mut self.flooding;
        debug_assert!(
            (flooding
                .claims
                .chunks(packing.per_word)
                .map(|c| packing.pack(c)))
            .eq(flooding.packed.iter().map(|&word| word as f64)),
            "packed claims out of date"
        );
        let chunks = flooding.claims.chunks_mut(packing.per_word);
        for ((chunk, packed), &word) in chunks.zip(&mut flooding.packed).zip(&theirs[tasks..]) {
            let word = word as u64;
            // Most of a snapshot's flood is values equal to the robot's own.
            if word == *packed {
                continue;
            }
            // The smaller code of each, unclaimed (0) the largest: `code − 1`, wrapping.
            let mut merged = *packed;
            for j in 0..chunk.len() {
                let (claim, mine) = (packing.code(word, j), packing.code(merged, j));
                if claim.wrapping_sub(1) < mine.wrapping_sub(1) {
                    merged = packing.with_code(merged, j, claim);
                }
            }
            if merged != *packed {
                *packed = merged;
                for (j, mine) in chunk.iter_mut().enumerate() {
                    *mine = packing.code(merged, j);
                }
            }
        }
    }

    /// Starts the potentials from `prices` (Case 1, where any solution proves: the
    /// augmenting finish's labels, [`crate::methods::dual::finish`]), at a step every robot
    /// seeds the same vector.
    pub fn seed(&mut self, prices: &[f64]) {
        debug_assert!(self.reset.is_none(), "Case 2 potentials start at 0");
        self.potentials.copy_from_slice(prices);
    }

    /// Forgets everything of the last episode (its potentials were lowered for other
    /// costs, its claims are of other tasks): the state of a new snapshot.
    pub fn restart(&mut self) {
        self.potentials.fill(0.0);
        self.before.fill(0.0);
        self.stable = false;
        self.flooding = Claims::empty(self.potentials.len(), self.packing);
        self.settled = Claims::empty(self.potentials.len(), self.packing);
    }

    /// After merging step `step`'s messages and deciding the robot's `task` (`None`: it
    /// relays, with no constraint and no claim of its own): relaxes its own constraints
    /// (its `costs`, centred, and `allowed` tasks), notes whether the potentials stood
    /// still, settles the snapshot that has flooded for `P` rounds and starts the next one.
    /// Every robot does the same at the same steps.
    pub fn advance(&mut self, step: u64, task: Option<usize>, costs: &[f64], allowed: &[bool]) {
        let settles = step > 0 && step.is_multiple_of(self.period);
        let restart = self.reset.is_some_and(|every| {
            step > 0
                && (step.is_multiple_of(every)
                    || (settles && self.flooding.claims != self.settled.claims))
        });
        if restart {
            // The neighbours' values merged in this step are dropped: not stable.
            self.potentials.fill(0.0);
            self.stable = false;
        } else if self.lent {
            self.stable = false;
        } else {
            if let Some(task) = task {
                let best = (0..costs.len())
                    .filter(|&t| allowed[t] && t != task)
                    .map(|t| self.potentials[t] + costs[t] - costs[task])
                    .fold(f64::INFINITY, f64::min);
                if best < self.potentials[task] - self.epsilon {
                    self.potentials[task] = best;
                }
            }
            self.stable = self.potentials == self.before;
        }
        if !step.is_multiple_of(self.period) {
            return;
        }
        if settles {
            std::mem::swap(&mut self.settled, &mut self.flooding);
        }
        let code = self.own_code();
        self.flooding.start(task, code, self.packing);
    }

    /// The claims of the last settled snapshot (per task its smallest claimer's code,
    /// robot + 1, or 0) and the robot's own task when that snapshot started.
    pub fn settled(&self) -> (&[u64], Option<usize>) {
        (&self.settled.claims, self.settled.task)
    }

    /// A relay's slack: 0 when its potentials stood still and the settled snapshot claims
    /// every task (it has no constraint of its own to meet), ∞ otherwise.
    pub fn relay_slack(&self) -> f64 {
        if self.stable && !self.settled.claims.contains(&UNCLAIMED) {
            0.0
        } else {
            f64::INFINITY
        }
    }

    /// Writes the potentials and the snapshot being flooded into the message's section.
    pub fn write(&self, out: &mut [f64]) {
        let tasks = self.potentials.len();
        out[..tasks].copy_from_slice(&self.potentials);
        let chunks = self.flooding.claims.chunks(self.packing.per_word);
        for (word, chunk) in out[tasks..].iter_mut().zip(chunks) {
            *word = self.packing.pack(chunk);
        }
    }

    /// The robot's certificate slack (module docs) for its current `task`, with its own
    /// (centred) `costs` and `allowed` tasks; ∞ when it proves nothing.
    pub fn slack(&self, task: usize, costs: &[f64], allowed: &[bool], case: AssignmentCase) -> f64 {
        let part = &self.settled;
        if !self.stable || part.task != Some(task) || part.claims.contains(&UNCLAIMED) {
            return f64::INFINITY;
        }
        let extra = part.claims[task] != self.own_code();
        let coverage = case == AssignmentCase::Two;
        if extra && !coverage {
            return f64::INFINITY;
        }
        let reduced = |t: usize| costs[t] + self.potentials[t];
        let best = (0..costs.len())
            .filter(|&t| allowed[t])
            .map(reduced)
            .fold(f64::INFINITY, f64::min);
        let own = reduced(task) - best;
        if extra {
            // λ = −ȳ ≥ 0: the potentials start at 0 and only fall.
            own - self.potentials[task]
        } else {
            own
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chain of robots with their cost rows, stepping their certificates through written
    /// sections as the transports do; returns every robot's slack after each step.
    fn run_chain(
        costs: &[Vec<f64>],
        tasks_of: &[usize],
        case: AssignmentCase,
        steps: u64,
    ) -> Vec<Vec<f64>> {
        let n = costs.len();
        let m = costs[0].len();
        let allowed = vec![true; m];
        let mut robots: Vec<Snapshot> = (0..n)
            .map(|i| Snapshot::new(i, n, m, case, n - 1, 1e-12))
            .collect();
        let mut sections = vec![vec![0.0; words(n, m)]; n];
        for s in &mut sections {
            Snapshot::write_empty(s);
        }
        let mut slacks = Vec::new();
        for step in 0..steps {
            let gathered = sections.clone();
            let mut round = Vec::new();
            for (i, robot) in robots.iter_mut().enumerate() {
                robot.begin(false);
                for j in [i.wrapping_sub(1), i + 1] {
                    if j < n {
                        robot.merge(step, &gathered[j]);
                    }
                }
                robot.advance(step, Some(tasks_of[i]), &costs[i], &allowed);
                robot.write(&mut sections[i]);
                round.push(robot.slack(tasks_of[i], &costs[i], &allowed, case));
            }
            slacks.push(round);
        }
        slacks
    }

    /// The optimal assignment of a 3 × 3 chain is certified (every slack 0 at one round);
    /// a non-optimal one never is: its potentials keep falling.
    #[test]
    fn optimal_claims_are_priced_and_others_never() {
        let costs = vec![
            vec![0.0, 2.0, 4.0],
            vec![1.0, 0.0, 3.0],
            vec![5.0, 1.0, 0.0],
        ];
        let optimal = run_chain(&costs, &[0, 1, 2], AssignmentCase::One, 30);
        let first = optimal
            .iter()
            .position(|round| round.iter().all(|&s| s <= 1e-12));
        assert!(first.is_some(), "{optimal:?}");
        // A worse one: robot 1 and robot 2 swapped (cost 0 + 3 + 1 = 4 > 0).
        let worse = run_chain(&costs, &[0, 2, 1], AssignmentCase::One, 200);
        assert!(
            worse
                .iter()
                .all(|round| round.iter().any(|s| !s.is_finite() || *s > 1e-12)),
            "a non-optimal assignment was certified"
        );
    }

    /// Case 1: a shared task cannot certify; Case 2: the extra claimer pays its task's
    /// price, and an unclaimed task proves nothing.
    #[test]
    fn shared_and_unclaimed_tasks() {
        let costs = vec![vec![0.0, 1.0], vec![0.0, 1.0], vec![0.0, 1.0]];
        let shared = run_chain(&costs, &[0, 0, 1], AssignmentCase::Two, 40);
        let last = shared.last().unwrap();
        // Robots 0 and 1 share task 0 at price 0; robot 2 covers task 1 at a loss of 1,
        // which prices task 1 at λ = 1: slacks 0.
        assert!(last.iter().all(|&s| s.abs() <= 1e-12), "{last:?}");
        let unclaimed = run_chain(&costs, &[0, 0, 0], AssignmentCase::Two, 40);
        assert!(unclaimed.last().unwrap().iter().all(|s| s.is_infinite()));
        let square = vec![vec![0.0, 1.0], vec![0.0, 1.0]];
        let one = run_chain(&square, &[0, 0], AssignmentCase::One, 20);
        assert!(one.last().unwrap().iter().all(|s| s.is_infinite()));
    }

    /// Claims survive the packing for any team size: a robot that writes a claim table
    /// and one that merges it hold the same codes (and `words` counts the packed values).
    #[test]
    fn claims_round_trip_through_packed_values() {
        assert_eq!(claims_per_word(1), 53);
        assert_eq!(claims_per_word(100), 7);
        assert_eq!(words(100, 100), 100 + 15);
        assert_eq!(words(2, 10), 10 + 1);
        for (robots, tasks) in [
            (1, 1),
            (2, 5),
            (3, 3),
            (100, 100),
            (127, 40),
            (128, 40),
            (1 << 20, 9),
        ] {
            let mut writer = Snapshot::new(robots - 1, robots, tasks, AssignmentCase::Two, 1, 1e-9);
            // A claim table with every shape of code: none, the smallest and the largest robot.
            for (t, claim) in writer.flooding.claims.iter_mut().enumerate() {
                *claim = match t % 3 {
                    0 => UNCLAIMED,
                    1 => 1,
                    _ => robots as u64,
                };
            }
            let mut section = vec![0.0; words(robots, tasks)];
            writer.write(&mut section);
            assert!(section.iter().all(|v| v.is_finite() && v.fract() == 0.0));
            let mut reader = Snapshot::new(0, robots, tasks, AssignmentCase::Two, 1, 1e-9);
            reader.merge(1, &section);
            assert_eq!(
                reader.flooding.claims, writer.flooding.claims,
                "{robots} robots"
            );
            let packed = reader.flooding.packed.iter().map(|&word| word as f64);
            assert!(
                packed.eq(section[tasks..].iter().copied()),
                "{robots} robots"
            );
        }
    }

    /// A received section is accepted as written and refused, at the right value, when a
    /// potential is not finite or a packed value is not an integer of this team's codes.
    #[test]
    fn bad_sections_are_refused_at_their_value() {
        let (robots, tasks) = (5, 20);
        let mut writer = Snapshot::new(4, robots, tasks, AssignmentCase::Two, 1, 1e-9);
        writer.flooding.claims[19] = 5;
        let mut section = vec![0.0; words(robots, tasks)];
        writer.write(&mut section);
        assert_eq!(writer.check(&section), Ok(()));
        // 3-bit codes, 17 to a value: two values, the second holding 3 codes.
        assert_eq!(section.len(), tasks + 2);
        let bad = |k: usize, v: f64| {
            let mut s = section.clone();
            s[k] = v;
            writer.check(&s)
        };
        assert_eq!(bad(3, f64::NAN), Err(3));
        assert_eq!(bad(tasks, 0.5), Err(tasks));
        assert_eq!(bad(tasks, -8.0), Err(tasks));
        assert_eq!(bad(tasks, 6.0), Err(tasks)); // code 6 > 5 robots
        assert_eq!(bad(tasks + 1, (1u64 << 9) as f64), Err(tasks + 1)); // a 4th code
        assert_eq!(bad(tasks + 1, f64::INFINITY), Err(tasks + 1));
        assert_eq!(bad(tasks + 1, 2f64.powi(64)), Err(tasks + 1));
        assert_eq!(bad(tasks + 1, -1e300), Err(tasks + 1));
        assert_eq!(bad(tasks + 1, 5.0), Ok(()));
        // 7 robots fill their 3-bit codes: every code of a word in range is one of theirs.
        let seven = Packing::new(7);
        assert!(seven.holds(seven.pack(&[7, 0, 3]), 3));
        assert!(!seven.holds(seven.pack(&[7, 0, 3]), 2));
    }
}
