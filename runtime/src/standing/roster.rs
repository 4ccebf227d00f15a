//! Who takes part in a standing team: the **roster** (the robots of the team file's slots
//! that are in the team now) and how it changes at an episode boundary.
//!
//! The team file lists the slots and the full topology; the robots in the roster run on the
//! graph the roster induces, whose diameter every robot computes alone. Every rule here is a
//! pure function of what the whole team agreed on (the opening flood of an episode) or of
//! the same view of who is gone, so every robot derives the same next roster:
//!
//! * **leave** ([`LeaveRule::Refuse`], the default): the leavers go unless the rest would
//!   fall apart; then the fewest leavers (the lowest first) stay and relay, and their leave is
//!   refused ([`Change::refused`]). With [`LeaveRule::Force`] every leaver goes and the team
//!   goes on in the largest connected part (ties: the part with the lowest robot), the others
//!   are lost ([`Change::lost`]);
//! * **join**: a slot that asked to join is admitted when one of its neighbours is in the
//!   next roster (joiners next to each other come in together);
//! * **crash** ([`after_loss`]): the robots gone leave the roster; the largest connected part
//!   goes on. Where a robot's disappearance may be a network cut rather than a death, the
//!   part that goes on must hold more than half of the last roster (half, with its lowest
//!   robot): the other side of a cut stops rather than solving the same tasks again.

use admm_ta_agents::certify::local_stop::MAX_DIAMETER;
use admm_ta_topologies::Graph;
use std::collections::BTreeSet;

/// The robots that take part, sorted.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct Roster(Vec<usize>);

impl Roster {
    /// The roster of `robots` (any order, duplicates dropped).
    pub fn new(robots: impl IntoIterator<Item = usize>) -> Self {
        let set: BTreeSet<usize> = robots.into_iter().collect();
        Self(set.into_iter().collect())
    }

    /// Every slot of a team of `n`.
    pub fn all(n: usize) -> Self {
        Self((0..n).collect())
    }

    pub fn robots(&self) -> &[usize] {
        &self.0
    }

    pub fn len(&self) -> usize {
        self.0.len()
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    pub fn contains(&self, robot: usize) -> bool {
        self.0.binary_search(&robot).is_ok()
    }

    /// The robots of this roster not in `other`.
    pub fn without(&self, other: &Roster) -> Vec<usize> {
        self.0
            .iter()
            .copied()
            .filter(|&r| !other.contains(r))
            .collect()
    }

    /// A short stable name of the roster: FNV-1a over its robots (epoch namespaces).
    pub fn hash(&self) -> u32 {
        let h = self.0.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &r| {
            (h ^ (r as u64 + 1)).wrapping_mul(0x0100_0000_01b3)
        });
        (h ^ (h >> 32)) as u32
    }

    /// The roster as a bitmap in hexadecimal, slot 0 in the lowest bit of the last digit
    /// (for names that carry it: Zenoh keys).
    pub fn to_hex(&self, slots: usize) -> String {
        let digits = slots.div_ceil(4).max(1);
        (0..digits)
            .rev()
            .map(|d| {
                let nibble = (0..4)
                    .filter(|b| self.contains(4 * d + b))
                    .fold(0u32, |v, b| v | 1 << b);
                char::from_digit(nibble, 16).expect("a nibble")
            })
            .collect()
    }

    /// The roster of a bitmap written by [`Roster::to_hex`] for a team of `slots`.
    pub fn from_hex(hex: &str, slots: usize) -> Option<Self> {
        let mut robots = Vec::new();
        for (d, c) in hex.chars().rev().enumerate() {
            let nibble = c.to_digit(16)?;
            for b in 0..4 {
                if nibble >> b & 1 == 1 {
                    let r = 4 * d + b;
                    if r >= slots {
                        return None;
                    }
                    robots.push(r);
                }
            }
        }
        Some(Self::new(robots))
    }
}

/// Whether `robots` induce a graph a team can run on: connected, its diameter at most
/// [`MAX_DIAMETER`] (the stop protocol's window; none is fine).
fn fits(graph: &Graph, robots: &[usize]) -> bool {
    robots.is_empty()
        || graph
            .diameter_among(robots)
            .is_some_and(|d| d <= MAX_DIAMETER)
}

/// One roster of a standing team's life: its number (it grows with every change) and its
/// robots. Its name names everything the robots of that roster share (their transport's
/// namespace): two robots meet only when they hold the same roster.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct EpochId {
    pub number: u64,
    pub roster: Roster,
}

/// Rosters in the order robots prefer them when two form at once: the later number, then
/// the more robots, then the robots themselves (a total order every robot applies alike).
impl Ord for EpochId {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        (self.number, self.roster.len(), self.roster.robots()).cmp(&(
            other.number,
            other.roster.len(),
            other.roster.robots(),
        ))
    }
}

impl PartialOrd for EpochId {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl EpochId {
    /// `e<number>x<roster hash>` (letters and digits).
    pub fn name(&self) -> String {
        format!("e{}x{:08x}", self.number, self.roster.hash())
    }

    /// The number of an epoch named `name` ([`EpochId::name`]), if it is one.
    pub fn number_of(name: &str) -> Option<u64> {
        let (number, hash) = name.strip_prefix('e')?.split_once('x')?;
        (hash.len() == 8 && hash.chars().all(|c| c.is_ascii_hexdigit()))
            .then(|| number.parse().ok())
            .flatten()
    }
}

/// What a leave does when the rest of the team would fall apart (the team file's `leave`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LeaveRule {
    /// The leave is refused: the robot stays and relays until its leave splits nobody.
    #[default]
    Refuse,
    /// The robot goes: the team goes on in its largest connected part, the others are lost.
    Force,
}

/// How an episode's agreement changes the roster.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Change {
    /// Robots that leave (they relay this episode and are out from the next).
    pub left: Vec<usize>,
    /// Robots whose leave is refused: they stay (and relay this episode).
    pub refused: Vec<usize>,
    /// Robots cut off by a forced leave: out from the next episode.
    pub lost: Vec<usize>,
    /// Robots admitted: in from the next episode.
    pub joined: Vec<usize>,
    /// The roster of the next episode.
    pub next: Roster,
}

/// The largest connected part of `robots` in `graph` (ties: the part with the lowest robot).
fn largest_part(graph: &Graph, robots: &[usize]) -> Vec<usize> {
    graph
        .components_among(robots)
        .into_iter()
        .fold(Vec::new(), |best, part| {
            if part.len() > best.len() { part } else { best }
        })
}

/// Leavers that stay so that the rest stays connected: the lowest first until it is, then
/// any of those that can go after all (the highest first).
fn refused_leaves(graph: &Graph, roster: &Roster, leaving: &[usize]) -> Vec<usize> {
    let mut kept: BTreeSet<usize> = roster.robots().iter().copied().collect();
    for l in leaving {
        kept.remove(l);
    }
    let connected = |kept: &BTreeSet<usize>| fits(graph, &kept.iter().copied().collect::<Vec<_>>());
    let mut refused = Vec::new();
    for &l in leaving {
        if connected(&kept) {
            break;
        }
        kept.insert(l);
        refused.push(l);
    }
    for at in (0..refused.len()).rev() {
        kept.remove(&refused[at]);
        if connected(&kept) {
            refused.remove(at);
        } else {
            kept.insert(refused[at]);
        }
    }
    refused
}

/// The next roster after an episode whose agreement says `leaving` want to leave and
/// `joining` want to join (both sorted; leavers and joiners outside their side of the roster
/// are ignored).
pub fn change(
    graph: &Graph,
    roster: &Roster,
    leaving: &[usize],
    joining: &[usize],
    rule: LeaveRule,
) -> Change {
    let leaving: Vec<usize> = leaving
        .iter()
        .copied()
        .filter(|&l| roster.contains(l))
        .collect();
    let (refused, lost, mut next) = match rule {
        LeaveRule::Refuse => {
            let refused = refused_leaves(graph, roster, &leaving);
            let next: BTreeSet<usize> = roster
                .robots()
                .iter()
                .copied()
                .filter(|r| !leaving.contains(r) || refused.contains(r))
                .collect();
            (refused, Vec::new(), next)
        }
        LeaveRule::Force => {
            let rest: Vec<usize> = roster
                .robots()
                .iter()
                .copied()
                .filter(|r| !leaving.contains(r))
                .collect();
            let part = largest_part(graph, &rest);
            let lost = rest.iter().copied().filter(|r| !part.contains(r)).collect();
            (Vec::new(), lost, part.into_iter().collect())
        }
    };
    let left = leaving
        .iter()
        .copied()
        .filter(|l| !refused.contains(l))
        .collect();
    // Joiners come in next to a robot of the next roster (or next to another joiner that
    // does): a team that everybody leaves admits nobody.
    let mut joined = Vec::new();
    let mut waiting: Vec<usize> = joining
        .iter()
        .copied()
        .filter(|&j| j < graph.robots() && !roster.contains(j))
        .collect();
    while !next.is_empty() {
        let before = joined.len();
        waiting.retain(|&j| {
            let adjacent = graph.neighbours(j).iter().any(|n| next.contains(n));
            let with: Vec<usize> = next.iter().copied().chain([j]).collect();
            let admitted = adjacent && fits(graph, &with);
            if admitted {
                next.insert(j);
                joined.push(j);
            }
            !admitted
        });
        if joined.len() == before {
            break;
        }
    }
    joined.sort_unstable();
    Change {
        left,
        refused,
        lost,
        joined,
        next: Roster::new(next),
    }
}

/// Why the robots left after a loss cannot go on.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CutOff {
    /// This robot is not in the part of the team that goes on.
    #[error(
        "robot {robot} is cut off from the team: after losing robot(s) {gone:?}, the team goes on with robot(s) {part:?}"
    )]
    Outside {
        robot: usize,
        gone: Vec<usize>,
        part: Vec<usize>,
    },
    /// The part that goes on is too long a graph for the stop protocol.
    #[error(
        "the team cannot go on after losing robot(s) {gone:?}: the graph of the robots left has a diameter above {MAX_DIAMETER}"
    )]
    TooLong { gone: Vec<usize> },
    /// The part this robot is in holds no majority of the last roster: the robots it lost
    /// may have gone on without it (a network cut).
    #[error(
        "robot {robot} is cut off from the team: it reaches {reached} of the {of} robots of the last roster (robot(s) {gone:?} vanished), too few to go on without them"
    )]
    Minority {
        robot: usize,
        reached: usize,
        of: usize,
        gone: Vec<usize>,
    },
}

/// The roster after the robots `gone` vanished from `roster`, as robot `me` goes on with it:
/// the largest connected part of the rest (see the module), and the robots left behind.
/// `majority`: a vanished robot may be cut off rather than dead, so the part must hold more
/// than half of `roster` (exactly half with its lowest robot).
pub fn after_loss(
    graph: &Graph,
    roster: &Roster,
    gone: &[usize],
    me: usize,
    majority: bool,
) -> Result<(Roster, Vec<usize>), CutOff> {
    let rest: Vec<usize> = roster
        .robots()
        .iter()
        .copied()
        .filter(|r| !gone.contains(r))
        .collect();
    let part = largest_part(graph, &rest);
    if !part.contains(&me) {
        return Err(CutOff::Outside {
            robot: me,
            gone: gone.to_vec(),
            part,
        });
    }
    let half = 2 * part.len() == roster.len() && part.first() == roster.robots().first();
    if majority && 2 * part.len() <= roster.len() && !half {
        return Err(CutOff::Minority {
            robot: me,
            reached: part.len(),
            of: roster.len(),
            gone: gone.to_vec(),
        });
    }
    if !fits(graph, &part) {
        return Err(CutOff::TooLong {
            gone: gone.to_vec(),
        });
    }
    let lost = rest.iter().copied().filter(|r| !part.contains(r)).collect();
    Ok((Roster::new(part), lost))
}

#[cfg(test)]
mod tests {
    use super::*;
    use admm_ta_topologies::generate;

    #[test]
    fn a_ring_that_loses_a_robot_becomes_a_chain_and_takes_it_back() {
        let ring = generate::ring(8).unwrap();
        let all = Roster::all(8);
        let c = change(&ring, &all, &[5], &[], LeaveRule::Refuse);
        assert_eq!((c.left.clone(), c.refused.clone()), (vec![5], vec![]));
        assert_eq!(c.next, Roster::new([0, 1, 2, 3, 4, 6, 7]));
        assert_eq!(ring.diameter_among(c.next.robots()), Some(6));
        let back = change(&ring, &c.next, &[], &[5], LeaveRule::Refuse);
        assert_eq!(back.joined, vec![5]);
        assert_eq!(back.next, all);
        // On the chain 6-7-0-1-2-3-4, robot 4 (an end) may go, robot 1 may not; robots 1
        // and 3 together may not either (4 and 2 would be cut off).
        let split = change(&ring, &c.next, &[1, 4], &[], LeaveRule::Refuse);
        assert_eq!((split.left, split.refused), (vec![4], vec![1]));
        let both = change(&ring, &c.next, &[1, 3], &[], LeaveRule::Refuse);
        assert_eq!((both.left, both.refused), (vec![], vec![1, 3]));
    }

    #[test]
    fn a_star_refuses_its_hub_unless_everybody_goes_or_the_leave_is_forced() {
        let star = generate::star(5).unwrap();
        let all = Roster::all(5);
        let hub = change(&star, &all, &[0], &[], LeaveRule::Refuse);
        assert_eq!((hub.left, hub.refused), (vec![], vec![0]));
        assert_eq!(hub.next, all);
        let everybody = change(&star, &all, &[0, 1, 2, 3, 4], &[], LeaveRule::Refuse);
        assert_eq!(everybody.left, vec![0, 1, 2, 3, 4]);
        assert!(everybody.next.is_empty() && everybody.refused.is_empty());
        let forced = change(&star, &all, &[0], &[], LeaveRule::Force);
        assert_eq!(forced.left, vec![0]);
        assert_eq!(forced.next, Roster::new([1]));
        assert_eq!(forced.lost, vec![2, 3, 4]);
        // A joiner next to nobody of the next roster waits; chains of joiners come in.
        let chain = generate::chain(6).unwrap();
        let c = change(
            &chain,
            &Roster::new([0, 1]),
            &[],
            &[2, 3, 5],
            LeaveRule::Refuse,
        );
        assert_eq!(c.joined, vec![2, 3]);
        assert_eq!(c.next, Roster::new([0, 1, 2, 3]));
    }

    #[test]
    fn losses_keep_the_largest_part_and_a_majority() {
        let ring = generate::ring(8).unwrap();
        let all = Roster::all(8);
        let (next, lost) = after_loss(&ring, &all, &[2], 0, true).unwrap();
        assert_eq!((next.len(), lost), (7, vec![]));
        // Losing 2 and 6 splits the ring into {3, 4, 5} and {7, 0, 1}: equal halves of 6,
        // neither a majority of 8.
        assert!(matches!(
            after_loss(&ring, &all, &[2, 6], 0, true),
            Err(CutOff::Minority { .. })
        ));
        let (next, lost) = after_loss(&ring, &all, &[2, 6], 0, false).unwrap();
        assert_eq!((next, lost), (Roster::new([0, 1, 7]), vec![3, 4, 5]));
        assert!(matches!(
            after_loss(&ring, &all, &[2, 6], 4, false),
            Err(CutOff::Outside { .. })
        ));
        // Exactly half, with the lowest robot, goes on.
        let (next, _) = after_loss(&ring, &all, &[4, 5, 6, 7], 0, true).unwrap();
        assert_eq!(next, Roster::new([0, 1, 2, 3]));
        assert!(after_loss(&ring, &all, &[0, 1, 2, 3], 5, true).is_err());
    }

    #[test]
    fn a_roster_too_long_for_the_stop_protocol_is_refused() {
        let n = 2 * MAX_DIAMETER + 10;
        let ring = generate::ring(n).unwrap();
        let all = Roster::all(n);
        let c = change(&ring, &all, &[3], &[], LeaveRule::Refuse);
        assert_eq!(
            (c.left, c.refused),
            (vec![], vec![3]),
            "a chain of {} robots",
            n - 1
        );
        assert!(matches!(
            after_loss(&ring, &all, &[3], 0, false),
            Err(CutOff::TooLong { .. })
        ));
    }

    #[test]
    fn rosters_name_themselves() {
        for n in [4, 5, 63, 200] {
            let r = Roster::new((0..n).filter(|i| i % 3 != 1));
            assert_eq!(Roster::from_hex(&r.to_hex(n), n), Some(r.clone()));
            assert_ne!(r.hash(), Roster::all(n).hash());
        }
        assert_eq!(Roster::new([0, 5]).to_hex(8), "21");
        assert_eq!(Roster::from_hex("100", 8), None);
        assert_eq!(Roster::from_hex("xz", 8), None);
        let id = EpochId {
            number: 12,
            roster: Roster::new([1, 2]),
        };
        assert_eq!(EpochId::number_of(&id.name()), Some(12));
        assert_eq!(EpochId::number_of("e12"), None);
        assert_eq!(EpochId::number_of("parts"), None);
    }
}
