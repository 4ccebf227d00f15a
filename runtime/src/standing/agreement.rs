//! What a standing team with private costs floods between its robots around every episode,
//! and how a robot merges what its neighbours hold. Flooding for `D` rounds (the graph's
//! diameter) gives every robot the merge over the whole team, because each merge below is
//! commutative, associative and idempotent.
//!
//! * **Before** the episode ([`Opening`]): the scale of the stacked rows
//!   ([`TeamScale`]: lowest and highest allowed cost, their lattice) and who has no row this
//!   episode (its program sent none in time) or is leaving the team (its program closed its
//!   input): two bits per robot, 26 robots per word (integers below 2⁵³ are exact in an
//!   `f64`).
//! * **After** the episode ([`Closing`]): every robot's cost of its own task (`+∞` when that
//!   pair is forbidden: the problem had no feasible assignment) and, when the message has
//!   room, its task: the team's total cost and assignment, which every robot then reports.
//!
//! Nothing else of a robot's costs ever leaves it.

use admm_ta_agents::problem::private::TeamScale;

/// Robots per status word (two bits each, below 2⁵³).
const ROBOTS_PER_WORD: usize = 26;

/// Values the opening agreement of a team of `robots` needs in a message.
pub fn opening_words(robots: usize) -> usize {
    TeamScale::WORDS + robots.div_ceil(ROBOTS_PER_WORD)
}

/// What the robots flood: written into a message, merged from a neighbour's.
pub trait Flooded {
    /// Writes it into a message (the rest of the message is zero).
    fn write(&self, out: &mut [f64]);
    /// Merges a neighbour's message.
    fn merge(&mut self, words: &[f64]);
}

/// What a robot knows before an episode: the team's scale and who takes no part.
#[derive(Debug, Clone, PartialEq)]
pub struct Opening {
    pub scale: TeamScale,
    /// Per word, two bits per robot: `01` no row this episode, `10` leaving the team.
    status: Vec<u64>,
}

impl Opening {
    /// Robot `index`'s own opening: its row's scale (`None`: it has no row this episode),
    /// and whether it leaves.
    pub fn own(robots: usize, index: usize, scale: Option<TeamScale>, leaving: bool) -> Self {
        let mut status = vec![0u64; robots.div_ceil(ROBOTS_PER_WORD)];
        let bits = u64::from(scale.is_none() && !leaving) | (u64::from(leaving) << 1);
        status[index / ROBOTS_PER_WORD] |= bits << (2 * (index % ROBOTS_PER_WORD));
        Self {
            scale: scale.unwrap_or(TeamScale::EMPTY),
            status,
        }
    }

    fn write_words(&self, out: &mut [f64]) {
        self.scale.write(out);
        for (slot, word) in out[TeamScale::WORDS..].iter_mut().zip(&self.status) {
            *slot = *word as f64;
        }
    }

    fn merge_words(&mut self, words: &[f64]) {
        self.scale.join(&TeamScale::read(words));
        for (word, theirs) in self.status.iter_mut().zip(&words[TeamScale::WORDS..]) {
            // A corrupt word cannot set bits beyond the team's robots.
            if theirs.is_finite() && *theirs >= 0.0 && *theirs < (1u64 << 52) as f64 {
                *word |= *theirs as u64;
            }
        }
    }

    fn with_bit(&self, bit: u64) -> Vec<usize> {
        let mut robots = Vec::new();
        for (w, word) in self.status.iter().enumerate() {
            for k in 0..ROBOTS_PER_WORD {
                if word >> (2 * k) & bit != 0 {
                    robots.push(w * ROBOTS_PER_WORD + k);
                }
            }
        }
        robots
    }

    /// The robots with no row this episode.
    pub fn missing(&self) -> Vec<usize> {
        self.with_bit(1)
    }

    /// The robots leaving the team.
    pub fn leaving(&self) -> Vec<usize> {
        self.with_bit(2)
    }
}

impl Flooded for Opening {
    fn write(&self, out: &mut [f64]) {
        self.write_words(out)
    }
    fn merge(&mut self, words: &[f64]) {
        self.merge_words(words)
    }
}

impl Flooded for Closing {
    fn write(&self, out: &mut [f64]) {
        self.write_words(out)
    }
    fn merge(&mut self, words: &[f64]) {
        self.merge_words(words)
    }
}

/// What the robots report after an episode: every robot's cost of its own task and, when
/// the message has room, its task.
#[derive(Debug, Clone, PartialEq)]
pub struct Closing {
    /// Per robot its cost (user's numbers; `+∞`: a forbidden pair; NaN: not heard of yet).
    pub costs: Vec<f64>,
    /// Per robot its task (NaN: not heard of yet); empty when the message has no room.
    pub tasks: Vec<f64>,
}

impl Closing {
    /// Robot `index`'s own closing, in a message of `payload_len` values.
    pub fn own(robots: usize, payload_len: usize, index: usize, task: usize, cost: f64) -> Self {
        let mut costs = vec![f64::NAN; robots];
        costs[index] = cost;
        let mut tasks = Vec::new();
        if payload_len >= 2 * robots {
            tasks = vec![f64::NAN; robots];
            tasks[index] = task as f64;
        }
        Self { costs, tasks }
    }

    fn write_words(&self, out: &mut [f64]) {
        let n = self.costs.len();
        out[..n].copy_from_slice(&self.costs);
        out[n..n + self.tasks.len()].copy_from_slice(&self.tasks);
    }

    fn merge_words(&mut self, words: &[f64]) {
        let n = self.costs.len();
        for (mine, theirs) in self.costs.iter_mut().zip(&words[..n]) {
            if mine.is_nan() {
                *mine = *theirs;
            }
        }
        for (mine, theirs) in self.tasks.iter_mut().zip(&words[n..]) {
            if mine.is_nan() {
                *mine = *theirs;
            }
        }
    }

    /// The team's total cost, once every robot is heard of (`+∞`: a forbidden pair).
    pub fn total(&self) -> Option<f64> {
        let complete = self.costs.iter().all(|c| !c.is_nan());
        complete.then(|| self.costs.iter().sum())
    }

    /// The team's assignment, once every robot is heard of (when the message had room).
    pub fn assignment(&self) -> Option<Vec<usize>> {
        let valid = |t: &f64| t.is_finite() && *t >= 0.0 && t.fract() == 0.0;
        (!self.tasks.is_empty() && self.tasks.iter().all(valid))
            .then(|| self.tasks.iter().map(|&t| t as usize).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn openings_merge_to_the_whole_team() {
        let n = 60;
        let scales: Vec<Option<TeamScale>> = (0..n)
            .map(|i| (i % 7 != 3).then(|| TeamScale::of_row(&[Some(i as f64)], false)))
            .collect();
        let own: Vec<Opening> = (0..n)
            .map(|i| Opening::own(n, i, scales[i], i == 41))
            .collect();
        let mut words = vec![0.0; opening_words(n)];
        let mut merged = own[0].clone();
        for o in &own[1..] {
            o.write(&mut words);
            merged.merge(&words);
        }
        let expected: Vec<usize> = (0..n).filter(|i| i % 7 == 3).collect();
        assert_eq!(merged.missing(), expected);
        assert_eq!(merged.leaving(), vec![41]);
        assert_eq!((merged.scale.lo, merged.scale.hi), (0.0, 59.0));
        assert_eq!(merged.scale.step, 1.0);
    }

    #[test]
    fn closings_total_once_complete() {
        let mut a = Closing::own(3, 9, 0, 2, 1.5);
        assert_eq!(a.total(), None);
        let mut words = vec![0.0; 9];
        Closing::own(3, 9, 1, 0, 2.0).write(&mut words);
        a.merge(&words);
        Closing::own(3, 9, 2, 1, -0.5).write(&mut words);
        a.merge(&words);
        assert_eq!(a.total(), Some(3.0));
        assert_eq!(a.assignment(), Some(vec![2, 0, 1]));
        let narrow = Closing::own(3, 4, 0, 0, 1.0);
        assert!(narrow.tasks.is_empty() && narrow.assignment().is_none());
    }
}
