//! The fast dual's augmenting finish (Case 1, `n = m`): when the claims leave tasks
//! claimed twice and tasks claimed by nobody, the robots freeze the claims and move whole
//! chains of robots at once along augmenting paths of successive shortest paths, found by
//! a distributed Bellman–Ford in which every robot relaxes only its own cost row and every
//! robot computes the labels from the moves the owners chose; owners on a negative cycle
//! of the frozen claims move round it ("Negative cycles"), also in claims of every task
//! that the certificate does not prove.
//!
//! # Why
//! At 1000 robots the ADMM's last hundreds of rounds (bench/README, "Where the dual's rounds
//! go at 1000 robots") are spent on *chains*: robots each one task along from their optimal
//! one, ending at a task two robots claim, with a task claimed by nobody. The prices move
//! such a chain one robot every ~20 rounds; an augmenting path moves all of it at once.
//!
//! # The labels
//! The claims of a settled snapshot are frozen (every robot holds them, at the same step):
//! each task's smallest claimer *owns* it, the other claimers are *excess*. `L_s` is the
//! least change of cost that frees task `s` by moving owners, each to another task, along a
//! path that ends at an unclaimed task:
//!
//! ```text
//! L_f = 0  (f unclaimed),     L_s = min over t ≠ s allowed to s's owner j:  α_{j,t} − α_{j,s} + L_t
//! ```
//!
//! An owner relaxes its own task's label by more than `ε` (the certificate's) and notes
//! the move that set it: the *tag* `t` (its owner `j` is known) and the *move* `α_{j,t} −
//! α_{j,s}`, a change of its own costs. The robots flood the moves and tags, not the
//! labels: every robot holds one (move, tag) per task and computes every label from them,
//! `L_s = move_s + L_{tag_s}` along the tags to an unclaimed task. It takes a neighbour's
//! (move, tag) for task `s` where that gives `s` a lower label as its own labels have it
//! (ties to the smaller tag). So a label that falls falls at once, at every robot that
//! hears of it, with every label whose path leads through it; a Bellman–Ford that floods
//! the labels passes the fall on one owner at a time, one flood a hop (1000 robots: labels
//! 40–80 tags deep, 2.7 rounds a hop, 90–150 rounds a batch; with the moves 30–50).
//! Labels only fall (but by the bound's rounding, "The bound"), each at least the cost of
//! a path there is, its move plus its successor's label; the owners' claims are the cheapest
//! for the tasks they cover when there is no negative cycle, and then the labels stop,
//! the same moves and tags at every robot, so the same labels (the potentials of
//! successive shortest paths).
//!
//! # Agreement, entries, the move
//! As in [`crate::certify::local_stop`], a window of bits (one packed value) tells every
//! robot, at the same step `r`, that every robot's labels, moves and tags stood still at
//! step `r − D`: then all held the same moves and tags (the graph is connected: a
//! neighbour's that differed would have lowered a label or lost to this robot's), so the
//! same labels, and it is a fixed point,
//! so every robot holds it still (with a bound, the labels up to it: "The bound" below). Each
//! excess robot `e` then names its *entry*
//! `t_e = argmin_t α_{e,t} + L_t` (the tag `(e, t_e)` at its task), and the entries flood
//! for `D` steps (a min-flood of fixed values; of several excess claimers of one task the
//! smallest code enters). At `r + D` every robot traces the same paths: from each entry,
//! in the order of the tasks, tag by tag to an unclaimed task, keeping a path only when it
//! enters no task a path kept before entered. The entry's robot moves to the task it
//! enters, each owner on the path to the task its tag names.
//!
//! Every robot's new claim is then its cheapest under the prices `L` (within `ε`): an owner
//! that stays meets its relaxation, a moved owner moves along a tight tag, an excess robot
//! to its entry. So when the kept paths fill every unclaimed task the assignment is optimal
//! and `L` proves it: the certificate starts from `L` ([`Finish::prices`]) and holds within
//! a few rounds. When tasks are left unclaimed the moved claims are frozen at once (every
//! robot traced the paths, so it knows the new owners and unclaimed tasks) and the labels
//! start again: the owners' claims are still the cheapest under `L`, so no negative cycle
//! appears (successive shortest paths), and the robots keep claiming their rounded
//! columns meanwhile. A label whose tags lead to a task still unclaimed over tasks no path
//! touched is kept (the cost of a path that is still there: an upper bound, from which the
//! relaxations fall as from unreached), the others start unreached.
//!
//! # The bound
//! After a move the labels moved along are potentials (every owner's claim is its cheapest
//! under them within `ε`), the *base*, and the new labels only rise above it (successive
//! shortest paths' distances only grow): an excess robot's entry rises too. Every excess
//! robot floods how far its entry rose (a min-flood, the *bound*), and a label more than
//! the bound above its base serves no entry that rose the least: its changes no longer
//! hold the agreement back, and once the labels settled it is *capped* at its base plus
//! the bound (and `ε`), without a tag (the Hungarian method's Dijkstra cap, so the capped
//! labels are potentials again, within `ε`, and the next base). A relaxation from a label
//! above the bound (as the bound stands then) sets a label above it, so once the bound
//! stands the labels below it come from labels below it (within `ε` the base's reduced
//! costs are not negative): a quiet step tells that they are the fixed point. The robots
//! compute only the labels up to the bound, as deep as
//! the shortest path is long rather than as the deepest chain of tags (1000 robots: a last
//! path of 7 tasks took 115 rounds among tags 42 deep). An excess robot enters at its
//! cheapest task preferring a computed label, and names no entry whose tags reach a
//! capped one (it leads nowhere, and would hide another excess claimer's path). A
//! capped batch moves the paths whose entries rose the least, often one, where a whole
//! batch moves every disjoint shortest path: the bound is used only when a move left at
//! most two tasks unclaimed (with more, costs of many ties took up to 2.2 times the
//! rounds: integer costs moved one path a batch instead of many). Claims
//! frozen anew, from the rounded columns, have no base.
//!
//! # Never wrong, never stuck
//! The finish only chooses claims: the certificate ([`crate::methods::dual::snapshot`])
//! still proves them optimal or not, and the ADMM iterates go on underneath. While the
//! labels are computed the robots claim their rounded columns, and when a settling
//! snapshot of those claims leaves fewer tasks unclaimed than the frozen ones the finish
//! freezes them instead, keeping each label whose tags lead over tasks of the same owner
//! in both to a task unclaimed in both (an upper bound, as after a move): the ADMM
//! resolves many short chains at once, the finish a few long ones. Neither the first
//! freeze nor a re-freeze waits for the claims to stand still: the finish freezes the
//! first settled snapshot whose unclaimed tasks are no fewer than the last one's (the
//! ADMM stalls on them: at 1000 robots within about 30 rounds, hundreds unclaimed; a small
//! team whose ADMM fills tasks period by period is left to it), the frozen claims follow
//! the ADMM's as long as their unclaimed tasks fall, and the batches run from where they
//! stop falling (200 robots: 23 % fewer rounds, bench/README). Labels that do not settle
//! are given up after a budget of `64 P` steps from the last freeze, move or cancel (at
//! most `m` cancels a freeze, "Negative cycles"); so is a full assignment the certificate
//! does not prove within `16 P` steps ([`CLAIM_PERIODS`]). The robots claim their rounded
//! columns again, and the finish waits `64 P` steps before it freezes again. Every
//! transition happens at a step every robot knows, from what every robot holds.
//!
//! # Negative cycles
//! The frozen claims need not be the cheapest for the tasks they cover: the ADMM's may
//! not be, and a standing team's warm episode starts from the last episode's optimum, a
//! full assignment that the new costs may make dearer than another. Then owners round a
//! *negative cycle* could swap tasks for less, and the labels round it fall forever. A
//! robot whose tags lead round a cycle says so in an OR-flooded *alarm* window, which
//! tells every robot at one step `r`. Each robot then offers every cycle of its tags
//! whose moves cost less than `−ε` in all (its tags name one task each, so its cycles are
//! disjoint): per task on one the code `i·(m + 1) + tag` of finder `i`, min-flooded for
//! `D` steps. At `r + D` every robot holds per task the smallest code offered, so the same
//! cycles whole (those no smaller finder touched), and the owners on each move round it
//! at once, each to the task its tag names. The claims' cost falls by more than `ε` a
//! cycle, so cycles are cancelled finitely often; the labels start again (those whose
//! tags lead off the cycles to an end are kept: upper bounds, as after a move). At most
//! `m` cancels follow one freeze (a cancel by a little more than `ε` where costs tie
//! makes little progress, and a faulty neighbour could offer cycles for ever: the
//! potentials stay lent meanwhile). Without a whole cycle, or past the `m` cancels, the
//! finish gives up: with tasks unclaimed it may freeze again after `P` steps (the
//! certificate lost nothing while it rested), else after `64 P`.
//!
//! Claims of every task are frozen too, once [`FULL_PERIODS`] settled snapshots in a
//! row claimed every task (the certificate proves an optimal one, mostly within that
//! time and sooner than labels found anew; a negative cycle keeps its potentials falling
//! for ever). No task is unclaimed, so the labels are *rooted*: every label starts at 0
//! (a path from a virtual task one move of cost 0 from every task) and only falls.
//! Negative cycles are cancelled as above, and labels that settle price the claims:
//! every owner's claim is its cheapest under them within `ε`, so the robots claim their
//! frozen tasks and the certificate starts from the labels ([`Finish::prices`]). A
//! standing team's warm episodes run the finish so (50 robots, `random:0.1`, drifting
//! distances: median 341 → 66 rounds; a cold episode 226 → 136, bench/README.md).
//!
//! # Layout of the payload
//! The moves of the tasks `0 … m−1` (0: none) travel in the certificate's potentials'
//! place: while the finish computes the labels the potentials stand (every robot at the
//! same steps) and prove nothing, so the ADMM's own claims cannot be certified meanwhile;
//! an unreached label (a claimed task without a tag) is `f64::MAX`, held by each robot,
//! never sent. Once the labels settled every robot holds them, and the entries
//! `e·m + t + 1` (0: none) travel in their place; for `D` steps after an alarm, the
//! offered cycles' codes (the section then zeros). The finish's own section is
//! `[packed tags, window, alarm, bound]` (the bound `f64::MAX`: none): a tag is `t + 1`
//! (0: none; the mover is the task's owner), packed as the claims are. Case 1 only (`robots =
//! tasks`, at least 2, diameter at most 53):
//! other teams carry no section, or zeros.
//!
//! Size: one protocol — its phases share one robot's state (labels, tags, entries, the
//! window and the frozen claims) and every transition reads the others; about 150 lines
//! are these docs (its unit tests are in `tests.rs`).

use crate::methods::dual::snapshot::{Packing, Snapshot};
use crate::problem::AssignmentCase;

/// A label no path reaches yet.
const UNREACHED: f64 = f64::MAX;
/// Bits of the agreement window (one packed value).
const WINDOW_BITS: usize = f64::MANTISSA_DIGITS as usize;
/// Snapshot periods the labels may take to settle before the finish gives up.
pub const LABEL_PERIODS: u64 = 64;
/// Snapshot periods a full assignment of the finish is claimed for the certificate.
pub const CLAIM_PERIODS: u64 = 16;
/// Settled snapshots in a row that claim every task before the finish freezes them: the
/// certificate proves an optimal full assignment sooner than labels found anew (10-robot
/// rings: warm episodes 13 rounds, with the labels from the first full snapshot 25).
pub const FULL_PERIODS: u64 = 3;
/// The most tasks a move may leave unclaimed for the next labels to stop at the bound
/// (module docs, "The bound").
const BOUNDED_UNCLAIMED: usize = 2;

/// Values of the finish's own payload section for `robots` robots and `tasks` tasks: its
/// moves travel in the certificate's potentials' place. A team of more robots than tasks
/// carries it too (zeros): a standing team's episode where some robots take no part may be
/// a Case 1 problem inside the team's messages.
pub const fn words(robots: usize, tasks: usize) -> usize {
    if robots < tasks || tasks < 2 {
        return 0;
    }
    match robots.checked_mul(tasks) {
        Some(max) if Packing::fits(max) => Packing::words(tasks, tasks) + 3,
        _ => 0,
    }
}

/// The largest entry code (`robots · tasks`, exact in an `f64`), where the finish can run.
const fn entry_max(robots: usize, tasks: usize) -> Option<usize> {
    if robots != tasks || words(robots, tasks) == 0 {
        return None;
    }
    // An offered cycle's codes (module docs, "Negative cycles") reach `robots · (tasks + 1)`.
    match robots.checked_mul(tasks + 1) {
        Some(max) if Packing::fits(max) => {}
        _ => return None,
    }
    Some(robots * tasks)
}

/// Where a robot is in the finish.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// It claims its rounded column.
    Idle,
    /// The claims were frozen at step `since`, in which it claims `task` (none: a relay);
    /// the labels settled at step `settled`.
    Labelling {
        since: u64,
        task: Option<usize>,
        settled: Option<u64>,
    },
    /// It moved (or stayed) at step `at` and claims `task`.
    Claiming { at: u64, task: Option<usize> },
    /// At step `at` every robot heard of a negative cycle among the frozen claims, in which
    /// it claims `task`: the cycles found flood for `D` steps, then the owners on each
    /// whole one move round it.
    Cancelling { at: u64, task: Option<usize> },
}

/// One robot's side of the augmenting finish.
#[derive(Debug, Clone)]
pub struct Finish {
    index: usize,
    tasks: usize,
    /// The largest entry code.
    entry_max: u64,
    /// The diameter `D`, where the finish runs.
    diameter: Option<u64>,
    period: u64,
    epsilon: f64,
    packing: Packing,
    phase: Phase,
    /// It owns its frozen task (else it is an excess claimer, or a relay).
    owner: bool,
    /// The frozen claims are a full assignment: every label starts at 0, a path from a
    /// virtual task that every task is one move of cost 0 from.
    rooted: bool,
    /// No freezing from the rounded claims before this step (after a finish given up).
    quiet_until: u64,
    /// Tasks the last settled snapshot left unclaimed (`usize::MAX` before the first).
    last_unclaimed: usize,
    /// Settled snapshots in a row that claimed every task.
    full: u64,
    labels: Vec<f64>,
    /// Per task its owner's change of cost `α_{j,t} − α_{j,s}` for the move its tag names
    /// (0 without a tag): the labels follow from these and the tags.
    moves: Vec<f64>,
    /// After a move that left at most [`BOUNDED_UNCLAIMED`] tasks unclaimed, the labels
    /// moved along (capped at the bound): potentials under which every owner's claim is
    /// its cheapest within `ε`; infinite otherwise.
    base: Vec<f64>,
    /// The least rise of an excess robot's entry over its entry under `base` that this robot
    /// heard of (`f64::MAX`: none): a label further above its `base` serves no entry.
    bound: f64,
    /// This excess robot's entry under `base`.
    entry_base: Option<f64>,
    tags: Vec<u64>,
    /// The tags packed as they are sent (merging skips a neighbour's equal tags).
    packed: Vec<u64>,
    entries: Vec<u64>,
    /// The window sent last step, and the AND of the neighbours' this step.
    window: u64,
    heard: u64,
    /// It found a negative cycle among the frozen claims; the alarm window it sent last
    /// step (bit `k`: a robot within `k` hops had found one `k + 1` steps before), and the
    /// OR of the neighbours' this step.
    cycle: bool,
    alarm: u64,
    alarmed: u64,
    changed: bool,
    /// A move, a tag or the bound changed since the labels were last computed from them.
    dirty: bool,
    /// It moved along settled labels this step to a full assignment, or its rooted labels
    /// settled this step.
    moved: bool,
    /// The robot is on one of the last paths traced.
    entered: bool,
    /// The last paths traced left no task unclaimed.
    complete: bool,
    /// The frozen claims as the moves left them (per task its owner's code, 0: none, an
    /// unclaimed task).
    frozen: Vec<u64>,
    /// Paths moved since the costs were set.
    paths: u64,
    /// Negative cycles cancelled since the costs were set.
    cycles: u64,
    /// Cancels since the claims were frozen: at most `m` (a cancel by more than `ε` that
    /// makes no real progress, or a faulty neighbour's offers, would lend the potentials
    /// for ever).
    cancels: usize,
    // Scratch of the tracing.
    used: Vec<bool>,
    /// Per task whether its label is kept after a move, and the tasks of one walk.
    keep: Vec<u8>,
    walk: Vec<usize>,
    /// `(from, whether this robot moves, to)` of each hop of a path.
    path: Vec<(usize, bool, usize)>,
}

impl Finish {
    /// Robot `index` of `robots`' side for `tasks` tasks on a graph of diameter `diameter`,
    /// relaxing by more than `epsilon`. It runs in Case 1 on graphs of diameter 1 to 53.
    pub fn new(
        index: usize,
        robots: usize,
        tasks: usize,
        case: AssignmentCase,
        diameter: usize,
        epsilon: f64,
    ) -> Self {
        let runs = case == AssignmentCase::One && (1..=WINDOW_BITS).contains(&diameter);
        let max = entry_max(robots, tasks).filter(|_| runs);
        let len = if max.is_some() { tasks } else { 0 };
        let packing = Packing::new(tasks.max(1));
        Self {
            index,
            tasks,
            entry_max: max.unwrap_or(0) as u64,
            diameter: max.map(|_| diameter as u64),
            period: diameter.max(1) as u64,
            epsilon,
            packing,
            phase: Phase::Idle,
            owner: false,
            rooted: false,
            quiet_until: 0,
            last_unclaimed: usize::MAX,
            full: 0,
            labels: vec![0.0; len],
            moves: vec![0.0; len],
            base: vec![f64::INFINITY; len],
            bound: UNREACHED,
            entry_base: None,
            tags: vec![0; len],
            packed: vec![0; len.div_ceil(packing.per_word())],
            entries: vec![0; len],
            window: 0,
            heard: 0,
            cycle: false,
            alarm: 0,
            alarmed: 0,
            changed: false,
            dirty: true,
            moved: false,
            entered: false,
            complete: false,
            frozen: vec![0; len],
            paths: 0,
            cycles: 0,
            cancels: 0,
            used: vec![false; len],
            keep: vec![0; len],
            walk: Vec::with_capacity(len + 1),
            path: Vec::with_capacity(len),
        }
    }

    /// Whether the finish runs for this team (Case 1 on a diameter of 1 to 53).
    pub fn runs(&self) -> bool {
        self.diameter.is_some()
    }

    /// Paths moved since the costs were last set.
    pub fn paths(&self) -> u64 {
        self.paths
    }

    /// Negative cycles among frozen claims cancelled since the costs were last set.
    pub fn cycles(&self) -> u64 {
        self.cycles
    }

    /// Whether it is computing labels (the claims frozen).
    pub fn labelling(&self) -> bool {
        matches!(
            self.phase,
            Phase::Labelling { .. } | Phase::Cancelling { .. }
        )
    }

    /// Forgets the last episode: the state of new costs. A standing team's warm episode
    /// starts from the last optimum, a full assignment that need not be the cheapest for
    /// the new costs: the finish cancels its negative cycles (50 robots, `random:0.1`,
    /// drifting distances: warm episodes 341 → 66 rounds, bench/README.md).
    pub fn restart(&mut self) {
        self.phase = Phase::Idle;
        self.quiet_until = 0;
        self.last_unclaimed = usize::MAX;
        self.full = 0;
        self.paths = 0;
        self.cycles = 0;
        self.clear();
    }

    fn clear(&mut self) {
        self.labels.fill(0.0);
        self.moves.fill(0.0);
        self.forget_base();
        self.tags.fill(0);
        self.packed.fill(0);
        self.clear_agreement();
    }

    /// Forgets the entries and the windows (kept labels start a new agreement).
    fn clear_agreement(&mut self) {
        self.entries.fill(0);
        self.bound = UNREACHED;
        self.dirty = true;
        self.window = 0;
        self.cycle = false;
        self.alarm = 0;
    }

    /// Checks a neighbour's section: tags of `tasks` tasks, windows of 53 bits and a bound
    /// of at least 0 (a finish that does not run reads nothing of it). Returns the offending
    /// value's index
    /// within the section.
    pub fn check(&self, theirs: &[f64]) -> Result<(), usize> {
        let m = self.tasks;
        if theirs.is_empty() {
            return Ok(());
        }
        let per = self.packing.per_word();
        let words = m.div_ceil(per);
        for (k, &word) in theirs[..words].iter().enumerate() {
            let codes = (m - k * per).min(per);
            if !self.packing.holds(word, codes) {
                return Err(k);
            }
        }
        for k in [words, words + 1] {
            if !Packing::new(1).holds(theirs[k], WINDOW_BITS) {
                return Err(k);
            }
        }
        // A bound is a rise (at least 0) or none (`f64::MAX`).
        let bound = theirs[words + 2];
        if !(bound.is_finite() && bound >= 0.0) {
            return Err(words + 2);
        }
        Ok(())
    }

    /// Starts a step: nothing heard yet.
    pub fn begin(&mut self) {
        self.changed = false;
        self.heard = u64::MAX;
        self.alarmed = 0;
    }

    /// Merges a neighbour's `place` (the potentials' place of its message) and section,
    /// only while labelling: its moves (sent in the labels' place) and tags, each taken
    /// where it lowers the label as this robot's labels have it, or once the labels settled
    /// the entries sent in the labels' place; while cancelling, the cycles it offered.
    pub fn merge(&mut self, place: &[f64], theirs: &[f64]) {
        let settled = match self.phase {
            Phase::Labelling { settled, .. } => settled,
            Phase::Cancelling { .. } => return self.merge_cycles(place),
            _ => return,
        };
        let m = self.tasks;
        if settled.is_some() {
            for (mine, &value) in self.entries.iter_mut().zip(place) {
                // Codes outside 1..=robots·tasks (only a faulty sender writes them) name
                // nobody.
                let code = value as u64;
                let valid = value.fract() == 0.0 && (1..=self.entry_max).contains(&code);
                if valid && (*mine == 0 || code < *mine) {
                    *mine = code;
                }
            }
            return;
        }
        let (packing, moves) = (self.packing, place);
        let words = &theirs[..m.div_ceil(packing.per_word())];
        self.heard &= theirs[words.len()] as u64;
        self.alarmed |= theirs[words.len() + 1] as u64;
        if theirs[words.len() + 2] < self.bound {
            self.bound = theirs[words.len() + 2];
            (self.changed, self.dirty) = (true, true);
        }
        // Most neighbours hold the robot's own tags and moves: one pass over the whole
        // vectors tells.
        let same = words.iter().zip(&self.packed).all(|(&w, &p)| w as u64 == p);
        if same && equal(moves, &self.moves) {
            return;
        }
        let per = packing.per_word();
        for (k, &word) in words.iter().enumerate() {
            let span = k * per..(k * per + per).min(m);
            if word as u64 == self.packed[k]
                && equal(&moves[span.clone()], &self.moves[span.clone()])
            {
                continue;
            }
            for s in span {
                let tag = packing.code(word as u64, s - k * per);
                // An unclaimed task takes no move (only a faulty sender tags it).
                let same = tag == self.tags[s] && moves[s] == self.moves[s];
                if tag == 0 || same || self.frozen[s] == 0 {
                    continue;
                }
                let value = self.through(s, tag as usize - 1, moves[s]);
                if value < self.labels[s] || (value == self.labels[s] && tag < self.tags[s]) {
                    self.adopt(s, tag as usize - 1, moves[s], value);
                }
            }
        }
    }

    /// The task the robot claims this step: its `rounded` one (none: a relay) unless the
    /// finish moved its claim. While labelling an owner relaxes its frozen task's label
    /// with its (centred) `costs` on its `allowed` tasks; once the labels settled an excess
    /// claimer names its entry, and `D` steps later the robots move (rooted labels: the
    /// robots claim their frozen tasks at once). At an alarm the robots offer their
    /// negative cycles, and `D` steps later the owners on them move round them.
    pub fn claim(
        &mut self,
        step: u64,
        rounded: Option<usize>,
        costs: &[f64],
        allowed: &[bool],
    ) -> Option<usize> {
        self.moved = false;
        let (since, task, settled) = match self.phase {
            Phase::Idle => return rounded,
            Phase::Claiming { task, .. } => return task,
            Phase::Cancelling { at, task } => {
                let diameter = self
                    .diameter
                    .expect("cancelling only where the finish runs");
                if step >= at + diameter {
                    self.cancel(step, task);
                }
                return rounded;
            }
            Phase::Labelling {
                since,
                task,
                settled,
            } => (since, task, settled),
        };
        let diameter = self.diameter.expect("labelling only where the finish runs");
        match settled {
            None => {
                self.derive();
                if let Some(s) = task.filter(|_| self.owner) {
                    self.relax(s, costs, allowed);
                }
                if let Some(rise) = self.rise(task, costs, allowed)
                    && rise < self.bound
                {
                    self.bound = rise;
                    (self.changed, self.dirty) = (true, true);
                }
                let (heard, alarmed) = (self.window & self.heard, self.alarm | self.alarmed);
                let bits = (1 << WINDOW_BITS) - 1;
                self.window = u64::from(!self.changed) | ((heard << 1) & bits);
                self.alarm = u64::from(self.cycle) | ((alarmed << 1) & bits);
                if step > since && alarmed >> (diameter - 1) & 1 == 1 {
                    // Some robot found a negative cycle: the labels would fall forever.
                    // The robots that hold one offer it, and the owners move round it.
                    if self.cancels < self.tasks {
                        self.offer_cycles(step, task);
                    } else {
                        self.give_up(step, LABEL_PERIODS);
                    }
                    return rounded;
                }
                if step > since && heard >> (diameter - 1) & 1 == 1 {
                    if self.rooted {
                        // No negative cycle is left: the labels price the frozen claims.
                        self.phase = Phase::Claiming { at: step, task };
                        self.moved = true;
                        return task;
                    }
                    self.cap();
                    if let Some(s) = task.filter(|_| !self.owner) {
                        self.enter(s, costs, allowed);
                    }
                    self.phase = Phase::Labelling {
                        since,
                        task,
                        settled: Some(step),
                    };
                }
                rounded
            }
            Some(at) if step >= at + diameter => self.traced(step, task, rounded, costs, allowed),
            Some(_) => rounded,
        }
    }

    /// Offers, once every robot heard of a negative cycle at `step`, every cycle of its own
    /// tags whose moves cost less than `−ε` in all (a robot's tags name one task each, so
    /// its cycles are disjoint): per task on one the code `i·(m + 1) + tag` of finder `i`
    /// (0 elsewhere), min-flooded for `D` steps. Then every robot holds, per task, the
    /// smallest code offered for it, so the same cycles whole: those of which no task was
    /// offered by a smaller finder (a smaller finder's codes are smaller on every task).
    fn offer_cycles(&mut self, step: u64, task: Option<usize>) {
        const UNKNOWN: u8 = 0;
        const WALKING: u8 = 1;
        const KNOWN: u8 = 2;
        let first = (self.index * (self.tasks + 1)) as u64;
        self.entries.fill(0);
        self.keep.fill(UNKNOWN);
        for s in 0..self.tasks {
            let mut at = s;
            while self.keep[at] == UNKNOWN && self.frozen[at] != 0 && self.tags[at] != 0 {
                self.keep[at] = WALKING;
                at = self.tags[at] as usize - 1;
            }
            if self.keep[at] == WALKING && self.cycle_cost(at) < -self.epsilon {
                let start = at;
                loop {
                    let tag = self.tags[at];
                    self.entries[at] = first + tag;
                    at = tag as usize - 1;
                    if at == start {
                        break;
                    }
                }
            }
            let mut x = s;
            while self.keep[x] == WALKING {
                self.keep[x] = KNOWN;
                x = self.tags[x] as usize - 1;
            }
        }
        self.phase = Phase::Cancelling { at: step, task };
    }

    /// The moves round the cycle of tags through task `start`.
    fn cycle_cost(&self, start: usize) -> f64 {
        let (mut cost, mut at) = (0.0, start);
        loop {
            cost += self.moves[at];
            at = self.tags[at] as usize - 1;
            if at == start {
                return cost;
            }
        }
    }

    /// Takes a neighbour's offered cycles (the potentials' place), each task's smallest
    /// code. Codes that name no finder's tag (only a faulty sender writes them) are skipped.
    fn merge_cycles(&mut self, place: &[f64]) {
        let (span, max) = (self.tasks as u64 + 1, self.entry_max + self.tasks as u64);
        for (mine, &value) in self.entries.iter_mut().zip(place) {
            let code = value as u64;
            let valid =
                value.fract() == 0.0 && (1..max).contains(&code) && !code.is_multiple_of(span);
            if valid && (*mine == 0 || code < *mine) {
                *mine = code;
            }
        }
    }

    /// `D` steps after the alarm every robot holds the same offered cycles: the owners on
    /// each whole one (disjoint: each task holds one code) move round it, each to the task
    /// its tag names (the frozen claims' cost falls by more than `ε` a cycle), and the
    /// labels start again, keeping those whose tags lead to an unclaimed task (a rooted
    /// one: to a task without a tag) over tasks no cycle touched (their owners and costs
    /// are the same: upper bounds). Without a whole cycle (the tags may have left the cycles
    /// found by the step of the offers) the finish gives up: with tasks unclaimed for `P` steps (the
    /// certificate loses nothing while it rests), rooted for `64 P`.
    fn cancel(&mut self, step: u64, task: Option<usize>) {
        let span = self.tasks as u64 + 1;
        let mut claim = task;
        let mut cancelled = 0;
        self.used.fill(false);
        self.keep.fill(0);
        for start in 0..self.tasks {
            let code = self.entries[start];
            if code == 0 || self.keep[start] != 0 {
                continue;
            }
            // The task its finder's tag names, while the code is that finder's.
            let finder = code / span;
            let entries = &self.entries;
            let next = |s: usize| {
                let code = entries[s];
                (code != 0 && code / span == finder).then(|| (code % span - 1) as usize)
            };
            // Marks the finder's tasks walked (another finder's task ends the walk).
            let (mut at, mut hops, mut whole) = (start, 0, true);
            while let Some(t) = next(at).filter(|_| hops < self.tasks) {
                self.keep[at] = 1;
                whole &= self.frozen[at] != 0;
                (at, hops) = (t, hops + 1);
                if at == start || self.keep[at] != 0 {
                    break;
                }
            }
            if !whole || at != start {
                continue;
            }
            let mut carried = self.frozen[start];
            loop {
                let t = next(at).expect("on a whole cycle");
                std::mem::swap(&mut self.frozen[t], &mut carried);
                self.used[t] = true;
                if self.owner && task == Some(at) {
                    claim = Some(t);
                }
                at = t;
                if at == start {
                    break;
                }
            }
            cancelled += 1;
        }
        if cancelled == 0 {
            // A full assignment's labels lend the certificate's potentials: they rest long.
            return self.give_up(step, if self.rooted { LABEL_PERIODS } else { 1 });
        }
        self.cycles += cancelled;
        self.cancels += 1;
        self.forget_base();
        self.keep_untouched_labels();
        self.phase = Phase::Labelling {
            since: step,
            task: claim,
            settled: None,
        };
    }

    /// Lowers the label of the robot's own task `s` to its best move by more than `ε`.
    fn relax(&mut self, s: usize, costs: &[f64], allowed: &[bool]) {
        // The best move as the label it gives (a label above the bound gives one above it).
        let label = |t: usize, _| self.through(s, t, costs[t] - costs[s]);
        if let Some((value, t)) = self.best(costs, allowed, Some(s), label)
            && value < self.labels[s] - self.epsilon
        {
            self.adopt(s, t, costs[t] - costs[s], value);
            self.note_cycle(s);
        }
    }

    /// The label of task `s` when its owner moves to `t` at a change of cost `change`: a
    /// label above the bound gives one above the bound too (module docs, "The bound":
    /// labels below it then come only from labels below it, above it after the addition's
    /// rounding too). Every robot computes it alike from the same values.
    /// A sum beyond an `f64` (only a faulty sender's moves make one) reaches nothing.
    fn through(&self, s: usize, t: usize, change: f64) -> f64 {
        let from = self.labels[t];
        let value = change + from;
        if from == UNREACHED || !value.is_finite() {
            return UNREACHED;
        }
        let threshold = self.threshold(s);
        if from > self.threshold(t) && threshold < UNREACHED {
            value.max(threshold.next_up())
        } else {
            value
        }
    }

    /// Task `s`'s owner moves to `t` at a change of cost `change` for a label `value`.
    fn adopt(&mut self, s: usize, t: usize, change: f64, value: f64) {
        self.labels[s] = value;
        self.moves[s] = change;
        self.dirty = true;
        self.tags[s] = t as u64 + 1;
        self.packing.set(&mut self.packed, s, t as u64 + 1);
        self.changed |= value <= self.threshold(s);
    }

    /// Notes a negative cycle when the tags lead from task `s`'s back to `s`: each label on
    /// the way is at least its move plus its successor's label now, so the moves around
    /// the cycle cost nothing or less in all (as in Bellman–Ford's predecessor graph). The
    /// owner notes its own at once; moves taken from neighbours are walked by `derive`.
    fn note_cycle(&mut self, s: usize) {
        let mut at = self.tags[s] as usize - 1;
        for _ in 0..self.tasks {
            if at == s {
                self.cycle |= self.cycle_cost(s) < -self.epsilon;
                break;
            }
            if self.frozen[at] == 0 || self.tags[at] == 0 {
                break;
            }
            at = self.tags[at] as usize - 1;
        }
    }

    /// Computes every label from the moves and tags (the labels of a path: an unclaimed
    /// task 0, a claimed one without a tag unreached, or rooted 0): a label that falls
    /// falls at every robot at once with the labels along its path, where a Bellman–Ford
    /// passes it on one owner a flood. Labels on a cycle of tags stay (one that costs less
    /// than `−ε` raises the alarm).
    fn derive(&mut self) {
        if !std::mem::take(&mut self.dirty) {
            return;
        }
        const UNKNOWN: u8 = 0;
        const WALKING: u8 = 1;
        const KNOWN: u8 = 2;
        let m = self.tasks;
        self.keep.fill(UNKNOWN);
        for s in 0..m {
            self.walk.clear();
            let mut at = s;
            while self.keep[at] == UNKNOWN {
                if self.frozen[at] == 0 || self.tags[at] == 0 {
                    self.keep[at] = KNOWN;
                    break;
                }
                self.keep[at] = WALKING;
                self.walk.push(at);
                at = self.tags[at] as usize - 1;
            }
            let cycle = self.keep[at] == WALKING;
            self.cycle |= cycle && self.cycle_cost(at) < -self.epsilon;
            for k in (0..self.walk.len()).rev() {
                let x = self.walk[k];
                self.keep[x] = KNOWN;
                if cycle {
                    continue;
                }
                let value = self.through(x, self.tags[x] as usize - 1, self.moves[x]);
                if value != self.labels[x] {
                    self.changed |= value <= self.threshold(x);
                    self.labels[x] = value;
                }
            }
        }
    }

    /// How far an excess robot's entry rose over its entry under `base` (none: no base, or
    /// not an excess robot with a reached task). With `base` a move's labels no label
    /// falls below it (successive shortest paths' distances only grow), so a label more
    /// than the least rise of any excess robot above its base serves no entry that rose
    /// the least (module docs, "The bound").
    /// At least 0 (a negative one would cap labels at their base).
    fn rise(&self, task: Option<usize>, costs: &[f64], allowed: &[bool]) -> Option<f64> {
        let base = self.entry_base.filter(|_| task.is_some() && !self.owner)?;
        let (value, _) = self.best(costs, allowed, None, |_, v| v)?;
        Some((value - base).max(0.0))
    }

    /// The highest value of task `t`'s label that holds the agreement back: its base plus
    /// the bound, within the bound's tolerance (infinite without a base, about `f64::MAX`
    /// without a bound).
    fn threshold(&self, t: usize) -> f64 {
        self.base[t] + self.bound + self.slack()
    }

    /// The tolerance of the bound: relaxations by `ε` or less are not made.
    fn slack(&self) -> f64 {
        self.epsilon
    }

    /// Once the labels settled: a label above its threshold is not computed (it may still
    /// fall) and is set to the threshold, without a tag (potentials still: every owner's
    /// claim stays its cheapest within `ε`); the labels below are exact. Every robot holds
    /// the same labels below the threshold and the same bound, so the same capped labels.
    fn cap(&mut self) {
        let (bound, slack) = (self.bound, self.slack());
        let mut capped = false;
        let tasks = self
            .labels
            .iter_mut()
            .zip(&mut self.tags)
            .zip(&mut self.moves);
        for (((label, tag), change), &base) in tasks.zip(&self.base) {
            if *label > base + bound + slack {
                *label = if base == UNREACHED {
                    UNREACHED
                } else {
                    base + bound + slack
                };
                (*tag, *change) = (0, 0.0);
                capped = true;
            }
        }
        if capped {
            self.repack();
        }
    }

    /// Packs the tags again after tags changed outside the merge and the relaxation.
    fn repack(&mut self) {
        let per = self.packing.per_word();
        for (word, chunk) in self.packed.iter_mut().zip(self.tags.chunks(per)) {
            *word = self.packing.pack(chunk) as u64;
        }
    }

    /// No base: every label is computed.
    fn forget_base(&mut self) {
        self.base.fill(f64::INFINITY);
        self.entry_base = None;
    }

    /// An excess claimer of task `s` names its entry (its cheapest task under the labels).
    /// An entry whose tags lead to a capped label leads nowhere: the robot names none (its
    /// smaller code would hide another excess claimer's path).
    fn enter(&mut self, s: usize, costs: &[f64], allowed: &[bool]) {
        let slack = self.slack();
        let computed = |t: usize, v: f64| if self.capped(t) { v + slack } else { v };
        if let Some((_, t)) = self.best(costs, allowed, None, computed)
            && self.leads_to_unclaimed(t)
        {
            let entry = (self.index * self.tasks + t + 1) as u64;
            if self.entries[s] == 0 || entry < self.entries[s] {
                self.entries[s] = entry;
            }
        }
    }

    /// Whether task `t`'s tags lead to an unclaimed task (not to a capped label, nor round a
    /// cycle). Every robot holds the same labels and tags up to the bound, so all agree.
    fn leads_to_unclaimed(&self, t: usize) -> bool {
        let mut at = t;
        for _ in 0..=self.tasks {
            if self.frozen[at] == 0 {
                return true;
            }
            if self.tags[at] == 0 {
                return false;
            }
            at = self.tags[at] as usize - 1;
        }
        false
    }

    /// Whether task `t`'s label was capped (claimed, with a label and no tag).
    fn capped(&self, t: usize) -> bool {
        self.frozen[t] != 0 && self.tags[t] == 0 && self.labels[t] != UNREACHED
    }

    /// The reached allowed task `t` (other than `except`) of least `costs[t] + L_t`, as
    /// `adjust(t, value)` has it: an excess robot's entry prefers a computed label to a
    /// capped one within the bound's tolerance (where its entry rose by the bound, the
    /// computed label it rose to costs the same as the capped ones), an owner's relaxation
    /// ranks its moves by the labels they give.
    fn best(
        &self,
        costs: &[f64],
        allowed: &[bool],
        except: Option<usize>,
        adjust: impl Fn(usize, f64) -> f64,
    ) -> Option<(f64, usize)> {
        let mut best: Option<(f64, usize)> = None;
        for t in 0..self.tasks {
            if Some(t) != except && allowed[t] && self.labels[t] != UNREACHED {
                let value = adjust(t, self.labels[t] + costs[t]);
                if best.is_none_or(|(b, _)| value < b) {
                    best = Some((value, t));
                }
            }
        }
        best
    }

    /// Moves along the traced paths: to a full assignment, claimed for the certificate;
    /// else the moved claims are frozen at once and the labels the move changed start again
    /// (every robot knows the paths, so the new owners and unclaimed tasks). Gives up
    /// without a path.
    fn traced(
        &mut self,
        step: u64,
        task: Option<usize>,
        rounded: Option<usize>,
        costs: &[f64],
        allowed: &[bool],
    ) -> Option<usize> {
        let Some(claim) = self.trace(task) else {
            self.give_up(step, LABEL_PERIODS);
            return rounded;
        };
        if self.complete {
            self.phase = Phase::Claiming {
                at: step,
                task: claim,
            };
            self.moved = true;
            return claim;
        }
        // A robot on a kept path owns the task it entered (its owner moved on; an excess
        // robot may enter its own task).
        self.owner |= self.entered;
        // The labels moved along are the next labels' base, and a robot still excess
        // notes its entry under them when few tasks are left unclaimed (no bound else).
        let left = self.frozen.iter().filter(|&&c| c == 0).count();
        if left > BOUNDED_UNCLAIMED {
            self.forget_base();
        } else {
            self.base.copy_from_slice(&self.labels);
        }
        self.entry_base = task
            .filter(|_| !self.owner && left <= BOUNDED_UNCLAIMED)
            .and_then(|_| self.best(costs, allowed, None, |_, v| v))
            .map(|(value, _)| value);
        self.keep_untouched_labels();
        self.phase = Phase::Labelling {
            since: step,
            task: claim,
            settled: None,
        };
        rounded
    }

    /// After a move that left tasks unclaimed (or claims frozen anew, [`Finish::freeze`], or
    /// cycles cancelled): keeps every label whose path (its tags) still leads to an
    /// unclaimed task (rooted: to a task without a tag) over tasks no kept path or cycle
    /// touched, marked `used` (its owners and their costs are the same, so it
    /// is at least the cost of a path there is: an upper bound, from which the relaxations
    /// fall to the new labels as from unreached), and makes the others unreached (rooted:
    /// 0, a root again). After a
    /// move every robot held the same settled tags and traced the same paths, so all keep
    /// the same labels; the labels computed anew are those the move changed. A `used`
    /// task is never an end: claims frozen anew may claim a task `frozen` has unclaimed.
    fn keep_untouched_labels(&mut self) {
        const UNKNOWN: u8 = 0;
        const KEPT: u8 = 1;
        const DROPPED: u8 = 2;
        let m = self.tasks;
        self.keep.fill(UNKNOWN);
        for s in 0..m {
            // Walk the tags from `s` to a task whose fate is known; all on the way share it.
            self.walk.clear();
            let mut at = s;
            let fate = loop {
                if self.keep[at] != UNKNOWN {
                    break self.keep[at];
                }
                if self.used[at] {
                    break DROPPED;
                }
                if self.frozen[at] == 0 || (self.rooted && self.tags[at] == 0) {
                    break KEPT;
                }
                if self.tags[at] == 0 || self.walk.len() > m {
                    break DROPPED;
                }
                self.walk.push(at);
                at = self.tags[at] as usize - 1;
            };
            if self.keep[at] == UNKNOWN {
                self.keep[at] = fate;
            }
            for &t in &self.walk {
                self.keep[t] = fate;
            }
        }
        for t in 0..m {
            if self.frozen[t] == 0 && !self.used[t] {
                (self.labels[t], self.tags[t], self.moves[t]) = (0.0, 0, 0.0);
            } else if self.keep[t] == DROPPED {
                // A rooted label starts again at its root.
                let start = if self.rooted { 0.0 } else { UNREACHED };
                (self.labels[t], self.tags[t], self.moves[t]) = (start, 0, 0.0);
            }
        }
        self.repack();
        self.clear_agreement();
    }

    /// Traces the paths of the settled labels from the entries (module docs) and returns
    /// the robot's claim after moving along them (its `task` if it is on none), or `None`
    /// when no path leads to an unclaimed task. Every robot traces the same paths.
    fn trace(&mut self, task: Option<usize>) -> Option<Option<usize>> {
        let m = self.tasks;
        self.used.fill(false);
        self.entered = false;
        let (mut claim, mut found) = (task, 0);
        for d in (0..m).filter(|&d| self.entries[d] != 0) {
            self.path.clear();
            // The entry's robot enters a task; from there each task's owner moves on.
            let entry = self.entries[d] as usize - 1;
            let (mut from, mut me, mut to) = (d, entry / m == self.index, entry % m);
            let mut ends = false;
            for _ in 0..=m {
                if self.used[to] || self.path.iter().any(|&(_, _, t)| t == to) {
                    break;
                }
                self.path.push((from, me, to));
                if self.frozen[to] == 0 || self.tags[to] == 0 {
                    ends = self.frozen[to] == 0;
                    break;
                }
                (from, me) = (to, self.owner && task == Some(to));
                to = self.tags[to] as usize - 1;
            }
            if !ends {
                continue;
            }
            found += 1;
            // Each task on the path passes to its predecessor's owner (the first to the
            // entry's robot): from the end, so that every owner is read before it moves.
            for k in (0..self.path.len()).rev() {
                let (from, _, to) = self.path[k];
                self.frozen[to] = if k == 0 {
                    (entry / m + 1) as u64
                } else {
                    self.frozen[from]
                };
            }
            for &(from, me, to) in &self.path {
                self.used[to] = true;
                if me && task == Some(from) {
                    claim = Some(to);
                    self.entered = true;
                }
            }
        }
        self.paths += found;
        self.complete = !self.frozen.contains(&0);
        (found > 0).then_some(claim)
    }

    /// The settled labels when the robots moved along them this step to a full assignment
    /// (every task reached), or rooted labels settled this step on claims of every task:
    /// prices under which every robot's new claim is its cheapest
    /// task within `ε` (module docs), so the certificate starts from them instead of
    /// finding its potentials again.
    pub fn prices(&self) -> Option<&[f64]> {
        let full = self.moved && !self.labels.contains(&UNREACHED);
        full.then_some(&self.labels[..])
    }

    /// The robots claim their rounded columns again, and wait `periods` snapshot periods
    /// before freezing again.
    fn give_up(&mut self, step: u64, periods: u64) {
        self.phase = Phase::Idle;
        self.quiet_until = step + periods * self.period;
        self.clear();
    }

    /// After the snapshot advanced at `step`: gives up what ran out of its budget, and
    /// freezes the claims of a settling snapshot that has unclaimed tasks (idle: no fewer
    /// than the last snapshot's; while labelling: fewer than the frozen claims; after a
    /// move to a full assignment: a snapshot started after it), or, idle, the claims of
    /// every task that [`FULL_PERIODS`] settling snapshots in a row held. Every robot does
    /// the same at the same step.
    pub fn observe(&mut self, step: u64, snapshot: &Snapshot) {
        if self.diameter.is_none() {
            return;
        }
        let period = self.period;
        match self.phase {
            Phase::Labelling { since, .. } if step >= since + LABEL_PERIODS * period => {
                self.give_up(step, LABEL_PERIODS);
            }
            Phase::Claiming { at, .. } if step >= at + CLAIM_PERIODS * period => {
                self.give_up(step, LABEL_PERIODS);
            }
            _ => {}
        }
        if step == 0 || !step.is_multiple_of(period) {
            return;
        }
        let (claims, task) = snapshot.settled();
        let unclaimed = claims.iter().filter(|&&c| c == 0).count();
        self.full = if unclaimed == 0 { self.full + 1 } else { 0 };
        let freeze = match self.phase {
            Phase::Idle => {
                step >= self.quiet_until
                    && (self.full >= FULL_PERIODS
                        || (unclaimed > 0 && unclaimed >= self.last_unclaimed))
            }
            // The settling snapshot started after the move.
            Phase::Claiming { at, .. } => unclaimed > 0 && step >= at + period,
            // The rounded claims left fewer tasks unclaimed than the frozen ones.
            Phase::Labelling { settled: None, .. } => {
                let frozen = self.frozen.iter().filter(|&&c| c == 0).count();
                unclaimed > 0 && unclaimed < frozen
            }
            Phase::Labelling { .. } | Phase::Cancelling { .. } => false,
        };
        self.last_unclaimed = unclaimed;
        if freeze {
            self.freeze(step, claims, task);
        }
    }

    /// Freezes `claims` (per task its smallest claimer's code, 0: none) at `step`, the
    /// robot claiming `task` in them: labels 0 at unclaimed tasks, unreached elsewhere (claims
    /// of every task: rooted, every label 0).
    /// Claims frozen in place of claims still labelling keep every label whose tags lead,
    /// over tasks whose owner is the same in both, to a task unclaimed in both: each hop
    /// costs what it cost, so the label is at least the cost of a path there is (an upper
    /// bound, as [`Finish::keep_untouched_labels`] keeps after a move).
    fn freeze(&mut self, step: u64, claims: &[u64], task: Option<usize>) {
        if matches!(self.phase, Phase::Labelling { settled: None, .. }) {
            for (t, &claim) in claims.iter().enumerate() {
                self.used[t] = self.frozen[t] != claim;
            }
            self.keep_untouched_labels();
            // Other owners: the base's claims are not theirs.
            self.forget_base();
        } else {
            self.clear();
            self.rooted = !claims.contains(&0);
            self.labels.fill(if self.rooted { 0.0 } else { UNREACHED });
        }
        for (t, &claim) in claims.iter().enumerate() {
            if claim == 0 {
                // Its tag is none already: kept at a task unclaimed in both, or dropped.
                debug_assert_eq!(self.tags[t], 0);
                self.labels[t] = 0.0;
            }
        }
        self.frozen.copy_from_slice(claims);
        self.cancels = 0;
        self.owner = task.is_some_and(|s| claims[s] == self.index as u64 + 1);
        self.phase = Phase::Labelling {
            since: step,
            task,
            settled: None,
        };
    }

    /// Writes its section of the message (zeros unless labelling) and, while labelling, the
    /// potentials' place (`labels`): the moves, or once the labels settled the entries
    /// (codes `e·m + t + 1`, 0: none); while cancelling, the offered cycles' codes.
    pub fn write(&self, labels: &mut [f64], out: &mut [f64]) {
        let settled = match self.phase {
            Phase::Labelling { settled, .. } => settled,
            Phase::Cancelling { .. } => {
                for (o, &code) in labels.iter_mut().zip(&self.entries) {
                    *o = code as f64;
                }
                out.fill(0.0);
                return;
            }
            Phase::Idle | Phase::Claiming { .. } => {
                out.fill(0.0);
                return;
            }
        };
        if settled.is_some() {
            for (o, &entry) in labels.iter_mut().zip(&self.entries) {
                *o = entry as f64;
            }
        } else {
            labels.copy_from_slice(&self.moves);
        }
        let chunks = self.tags.chunks(self.packing.per_word());
        for ((o, &word), chunk) in out.iter_mut().zip(&self.packed).zip(chunks) {
            debug_assert_eq!(
                word as f64,
                self.packing.pack(chunk),
                "packed tags out of date"
            );
            *o = word as f64;
        }
        out[out.len() - 3] = self.window as f64;
        out[out.len() - 2] = self.alarm as f64;
        out[out.len() - 1] = self.bound;
    }
}

/// Whether `a` and `b` hold the same values.
fn equal(a: &[f64], b: &[f64]) -> bool {
    a.iter().zip(b).all(|(a, b)| a.to_bits() == b.to_bits())
}

#[cfg(test)]
mod tests;
