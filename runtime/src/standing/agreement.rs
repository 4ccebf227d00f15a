//! What a standing team with private costs floods between its robots around every episode,
//! and how a robot merges what its neighbours hold. Flooding for `D` rounds (the graph's
//! diameter) gives every robot the merge over the whole team, because each merge below is
//! commutative, associative and idempotent.
//!
//! * **Before** the episode ([`Opening`]): the scale of the stacked rows
//!   ([`TeamScale`]: lowest and highest allowed cost, their lattice), the shortest and the
//!   longest row (the episode's tasks), and who has no row (its program sent none in time),
//!   takes no task (unavailable: it relays), leaves the team (its program closed its input)
//!   or waits to join it (a robot next to it saw it ask): bits, 52 per word (integers below
//!   2⁵³ are exact in an `f64`).
//! * **After** the episode ([`Closing`]): every robot's cost of its own task (`+∞` when that
//!   pair is forbidden: the problem had no feasible assignment) and, when the message has
//!   room, its task: the team's total cost and assignment, which every robot then reports.
//! * **When the team's roster changed** ([`Sync`], first thing on the new roster): the
//!   episode each robot is at (the highest wins: a robot that lost an episode to a crash
//!   gives it up when another robot already answered it), who is new and who vanished.
//!
//! Nothing else of a robot's costs ever leaves it.

use admm_ta_agents::problem::private::TeamScale;

/// Bits per word (integers below 2⁵³ are exact in an `f64`).
const BITS_PER_WORD: usize = 52;

/// Bits an opening keeps per robot (missing, unavailable, leaving, joining).
const ROBOT_BITS: usize = 4;

/// Values the opening agreement of a team of `robots` and up to `tasks` tasks needs in a
/// message.
pub fn opening_words(robots: usize, tasks: usize) -> usize {
    TeamScale::WORDS + opening_bits(robots, tasks).div_ceil(BITS_PER_WORD)
}

/// Values of a private standing team's round message: its method's `payload` for the whole
/// team, and room for the opening agreement and for the closing's cost and task of every
/// robot.
pub fn message_len(payload: usize, robots: usize, tasks: usize) -> usize {
    payload.max(opening_words(robots, tasks)).max(2 * robots)
}

fn opening_bits(robots: usize, tasks: usize) -> usize {
    2 * tasks + ROBOT_BITS * robots + 1
}

/// Sets bit `bit` of `bits`.
fn set_bit(bits: &mut [u64], bit: usize) {
    bits[bit / BITS_PER_WORD] |= 1 << (bit % BITS_PER_WORD);
}

fn get_bit(bits: &[u64], bit: usize) -> bool {
    bits[bit / BITS_PER_WORD] >> (bit % BITS_PER_WORD) & 1 != 0
}

/// ORs the words a neighbour wrote (`f64` integers) into `bits`; a corrupt word cannot set
/// bits beyond a word's.
fn merge_bits(bits: &mut [u64], words: &[f64]) {
    let limit = (1u64 << BITS_PER_WORD) as f64;
    for (word, theirs) in bits.iter_mut().zip(words) {
        if theirs.is_finite() && *theirs >= 0.0 && *theirs < limit {
            *word |= *theirs as u64;
        }
    }
}

fn write_bits(bits: &[u64], out: &mut [f64]) {
    for (slot, word) in out.iter_mut().zip(bits) {
        *slot = *word as f64;
    }
}

/// What the robots flood: written into a message, merged from a neighbour's.
pub trait Flooded {
    /// Writes it into a message (the rest of the message is zero).
    fn write(&self, out: &mut [f64]);
    /// Merges a neighbour's message.
    fn merge(&mut self, words: &[f64]);
}

/// How a robot takes part in an episode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Participation {
    /// It gave a row of `len` costs.
    Row { len: usize },
    /// Its program gave no row in time.
    Missing,
    /// It takes no task this episode and relays for its neighbours.
    Unavailable,
    /// Its program closed its input: it leaves the team (it relays this episode).
    Leaving,
}

/// What a robot knows before an episode: the team's scale, the rows' lengths and who
/// takes no part. The bits: `[0, m)` "some row is longer than `j`" and `[m, 2m)` "some row
/// is shorter than `m − j`" (thermometer codes: their OR is the longest and the shortest
/// row), then four per robot (missing, unavailable, leaving, joining), then one: some
/// robot's costs moved far since the last episode (the team starts from zero rather than
/// from the last iterates).
#[derive(Debug, Clone, PartialEq)]
pub struct Opening {
    pub scale: TeamScale,
    tasks: usize,
    robots: usize,
    bits: Vec<u64>,
}

impl Opening {
    /// Robot `index`'s own opening: how it takes part, and its row's scale.
    pub fn own(
        robots: usize,
        tasks: usize,
        index: usize,
        part: Participation,
        scale: TeamScale,
    ) -> Self {
        let mut own = Self {
            scale,
            tasks,
            robots,
            bits: vec![0; opening_bits(robots, tasks).div_ceil(BITS_PER_WORD)],
        };
        let status = 2 * tasks + ROBOT_BITS * index;
        match part {
            Participation::Row { len } => {
                for j in 0..len.min(tasks) {
                    own.set(j);
                }
                for j in 0..tasks.saturating_sub(len) {
                    own.set(tasks + j);
                }
            }
            Participation::Missing => own.set(status),
            Participation::Unavailable => own.set(status + 1),
            Participation::Leaving => own.set(status + 2),
        }
        own
    }

    fn set(&mut self, bit: usize) {
        set_bit(&mut self.bits, bit);
    }

    fn get(&self, bit: usize) -> bool {
        get_bit(&self.bits, bit)
    }

    fn status(&self, offset: usize) -> Vec<usize> {
        (0..self.robots)
            .filter(|i| self.get(2 * self.tasks + ROBOT_BITS * i + offset))
            .collect()
    }

    /// Marks that robot `slot` (not in the team) asked to join it.
    pub fn set_joining(&mut self, slot: usize) {
        if slot < self.robots {
            self.set(2 * self.tasks + ROBOT_BITS * slot + 3);
        }
    }

    /// The robots that asked to join the team.
    pub fn joining(&self) -> Vec<usize> {
        self.status(3)
    }

    /// The robots with no row this episode.
    pub fn missing(&self) -> Vec<usize> {
        self.status(0)
    }

    /// The robots that take no task this episode and relay.
    pub fn unavailable(&self) -> Vec<usize> {
        self.status(1)
    }

    /// The robots leaving the team.
    pub fn leaving(&self) -> Vec<usize> {
        self.status(2)
    }

    /// Marks that this robot's costs moved far since the last episode.
    pub fn set_moved(&mut self) {
        self.set(2 * self.tasks + ROBOT_BITS * self.robots);
    }

    /// Some robot's costs moved far since the last episode.
    pub fn moved(&self) -> bool {
        self.get(2 * self.tasks + ROBOT_BITS * self.robots)
    }

    /// The shortest and the longest row, if any robot gave one.
    pub fn lengths(&self) -> Option<(usize, usize)> {
        let longest = (0..self.tasks).filter(|&j| self.get(j)).count();
        let shortfall = (0..self.tasks)
            .filter(|&j| self.get(self.tasks + j))
            .count();
        (longest > 0).then(|| (self.tasks - shortfall, longest))
    }
}

impl Flooded for Opening {
    fn write(&self, out: &mut [f64]) {
        self.scale.write(out);
        write_bits(&self.bits, &mut out[TeamScale::WORDS..]);
    }

    fn merge(&mut self, words: &[f64]) {
        self.scale.join(&TeamScale::read(words));
        merge_bits(&mut self.bits, &words[TeamScale::WORDS..]);
    }
}

/// What the robots report after an episode: every robot's cost of its own task and its
/// task (a round message has room for both: [`message_len`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Closing {
    /// Per robot its cost (user's numbers; `+∞`: a forbidden pair; 0 for a relay; NaN: not
    /// heard of yet).
    pub costs: Vec<f64>,
    /// Per robot its task (`−1`: a relay; NaN: not heard of yet).
    pub tasks: Vec<f64>,
}

impl Closing {
    /// Robot `index`'s own closing (`task` `None`: a relay), in a team whose robots outside
    /// `roster` take no part (known at once as relays: nobody waits to hear of them).
    pub fn own(
        robots: usize,
        roster: &[usize],
        index: usize,
        task: Option<usize>,
        cost: f64,
    ) -> Self {
        let unknown = |slot: usize, outside: f64| {
            if roster.binary_search(&slot).is_ok() {
                f64::NAN
            } else {
                outside
            }
        };
        let mut costs: Vec<f64> = (0..robots).map(|i| unknown(i, 0.0)).collect();
        costs[index] = cost;
        let mut tasks: Vec<f64> = (0..robots).map(|i| unknown(i, -1.0)).collect();
        tasks[index] = task.map_or(-1.0, |t| t as f64);
        Self { costs, tasks }
    }

    /// The team's total cost, once every robot is heard of (`+∞`: a forbidden pair).
    pub fn total(&self) -> Option<f64> {
        let complete = self.costs.iter().all(|c| !c.is_nan());
        complete.then(|| self.costs.iter().sum())
    }

    /// The team's assignment (`None` for a relay), once every robot is heard of.
    pub fn assignment(&self) -> Option<Vec<Option<usize>>> {
        let valid = |t: &f64| t.is_finite() && *t >= -1.0 && t.fract() == 0.0;
        self.tasks.iter().all(valid).then(|| {
            self.tasks
                .iter()
                .map(|&t| (t >= 0.0).then_some(t as usize))
                .collect()
        })
    }
}

impl Flooded for Closing {
    fn write(&self, out: &mut [f64]) {
        let n = self.costs.len();
        out[..n].copy_from_slice(&self.costs);
        out[n..n + self.tasks.len()].copy_from_slice(&self.tasks);
    }

    fn merge(&mut self, words: &[f64]) {
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
}

/// What robots flood first on a new roster: the episode each is at (the team takes the
/// highest), and which robots each finds new, vanished or cut off since its last roster
/// (bits, merged by OR: a robot that just joined knows of none).
#[derive(Debug, Clone, PartialEq)]
pub struct Sync {
    /// The highest episode any robot is at.
    pub episode: u64,
    robots: usize,
    bits: Vec<u64>,
}

/// Bits a sync keeps per robot (joined, vanished, cut off).
const SYNC_BITS: usize = 3;

/// What a robot knows changed in its team's roster.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RosterNews {
    /// Robots new in the roster.
    pub joined: Vec<usize>,
    /// Robots that vanished (their process died, or they left without a word).
    pub crashed: Vec<usize>,
    /// Robots cut off from the rest when others vanished.
    pub lost: Vec<usize>,
}

impl RosterNews {
    /// Adds `more`.
    pub fn merge(&mut self, more: &RosterNews) {
        for (into, from) in [
            (&mut self.joined, &more.joined),
            (&mut self.crashed, &more.crashed),
            (&mut self.lost, &more.lost),
        ] {
            into.extend_from_slice(from);
            into.sort_unstable();
            into.dedup();
        }
    }
}

impl Sync {
    /// Values a sync of a team of `robots` needs in a message.
    pub fn words(robots: usize) -> usize {
        1 + (SYNC_BITS * robots).div_ceil(BITS_PER_WORD)
    }

    /// A robot's own sync: the episode it is at, and the changes it knows of.
    pub fn own(robots: usize, episode: u64, news: &RosterNews) -> Self {
        let mut own = Self {
            episode,
            robots,
            bits: vec![0; (SYNC_BITS * robots).div_ceil(BITS_PER_WORD)],
        };
        for (offset, list) in [&news.joined, &news.crashed, &news.lost]
            .into_iter()
            .enumerate()
        {
            for &r in list.iter().filter(|&&r| r < robots) {
                set_bit(&mut own.bits, SYNC_BITS * r + offset);
            }
        }
        own
    }

    /// The changes some robot knew of.
    pub fn news(&self) -> RosterNews {
        let listed = |offset: usize| {
            (0..self.robots)
                .filter(|&i| get_bit(&self.bits, SYNC_BITS * i + offset))
                .collect()
        };
        RosterNews {
            joined: listed(0),
            crashed: listed(1),
            lost: listed(2),
        }
    }
}

impl Flooded for Sync {
    fn write(&self, out: &mut [f64]) {
        // Episode numbers below 2⁵³ are exact.
        out[0] = self.episode as f64;
        write_bits(&self.bits, &mut out[1..]);
    }

    fn merge(&mut self, words: &[f64]) {
        let theirs = words[0];
        if theirs.is_finite() && theirs >= 0.0 && theirs < (1u64 << 53) as f64 {
            self.episode = self.episode.max(theirs as u64);
        }
        merge_bits(&mut self.bits, &words[1..]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn openings_merge_to_the_whole_team() {
        let (n, m) = (60, 7);
        let own: Vec<Opening> = (0..n)
            .map(|i| {
                let part = match i {
                    41 => Participation::Leaving,
                    17 | 23 => Participation::Unavailable,
                    _ if i % 7 == 3 => Participation::Missing,
                    _ => Participation::Row {
                        len: if i == 5 { 4 } else { 6 },
                    },
                };
                let scale = match part {
                    Participation::Row { .. } => TeamScale::of_row(&[Some(i as f64)], false),
                    _ => TeamScale::EMPTY,
                };
                Opening::own(n, m, i, part, scale)
            })
            .collect();
        let mut words = vec![0.0; opening_words(n, m)];
        let mut merged = own[0].clone();
        for o in &own[1..] {
            o.write(&mut words);
            merged.merge(&words);
        }
        let missing: Vec<usize> = (0..n).filter(|i| i % 7 == 3 && *i != 17).collect();
        assert_eq!(merged.missing(), missing);
        assert_eq!(merged.unavailable(), vec![17, 23]);
        assert_eq!(merged.leaving(), vec![41]);
        assert!(merged.joining().is_empty());
        assert_eq!(merged.lengths(), Some((4, 6)));
        assert!(!merged.moved());
        let mut moved = Opening::own(n, m, 59, Participation::Row { len: 6 }, TeamScale::EMPTY);
        moved.set_moved();
        moved.write(&mut words);
        merged.merge(&words);
        assert!(merged.moved() && merged.missing().len() == 8);
        let mut joins = Opening::own(n, m, 2, Participation::Row { len: 6 }, TeamScale::EMPTY);
        joins.set_joining(59);
        joins.write(&mut words);
        merged.merge(&words);
        assert_eq!(merged.joining(), vec![59]);
        assert_eq!(merged.missing().len(), 8);
        assert_eq!((merged.scale.lo, merged.scale.hi), (0.0, 58.0));
        assert_eq!(merged.scale.step, 1.0);
        let alone = Opening::own(3, 2, 1, Participation::Missing, TeamScale::EMPTY);
        assert_eq!(alone.lengths(), None);
        assert_eq!(
            opening_words(2, 2),
            4,
            "a 2 × 2 team's agreement fits its message"
        );
    }

    #[test]
    fn closings_total_once_complete() {
        let all = [0, 1, 2];
        let mut a = Closing::own(3, &all, 0, Some(2), 1.5);
        assert_eq!(a.total(), None);
        let mut words = vec![0.0; 9];
        Closing::own(3, &all, 1, None, 0.0).write(&mut words);
        a.merge(&words);
        Closing::own(3, &all, 2, Some(1), -0.5).write(&mut words);
        a.merge(&words);
        assert_eq!(a.total(), Some(1.0));
        assert_eq!(a.assignment(), Some(vec![Some(2), None, Some(1)]));
        // Robots outside the roster are known at once, as relays.
        let mut part = Closing::own(4, &[0, 2], 0, Some(1), 2.0);
        Closing::own(4, &[0, 2], 2, Some(0), 1.0).write(&mut words);
        part.merge(&words);
        assert_eq!(part.total(), Some(3.0));
        assert_eq!(part.assignment(), Some(vec![Some(1), None, Some(0), None]));
    }

    #[test]
    fn syncs_take_the_highest_episode_and_every_change() {
        let news = |joined: &[usize], crashed: &[usize], lost: &[usize]| RosterNews {
            joined: joined.to_vec(),
            crashed: crashed.to_vec(),
            lost: lost.to_vec(),
        };
        let mut a = Sync::own(70, 12, &RosterNews::default());
        let mut words = vec![0.0; Sync::words(70)];
        Sync::own(70, 13, &news(&[65], &[3], &[])).write(&mut words);
        a.merge(&words);
        Sync::own(70, 11, &news(&[], &[3, 69], &[7])).write(&mut words);
        a.merge(&words);
        assert_eq!(a.episode, 13);
        assert_eq!(a.news(), news(&[65], &[3, 69], &[7]));
        words[0] = f64::NAN;
        a.merge(&words);
        assert_eq!(a.episode, 13);
    }
}
