//! Standing teams whose robots keep their own costs (`costs = "private"` in the team file).
//!
//! Every robot joins once and then solves episode after episode with the cost row its own
//! program gives it; no process ever reads, receives or stores another robot's costs. What
//! robots share besides the method's iterates is in [`agreement`]: the team's scale (lowest
//! and highest allowed cost, the lattice they lie on), who has no row or leaves, and after
//! each episode every robot's cost of its own task and its task.
//!
//! * [`member`]: [`TeamMember`], one robot (join, then [`TeamMember::assign`] per episode);
//! * `episode`: one episode as one robot runs it (agreement, the method on the part of the
//!   team that takes part, closing);
//! * [`serve`]: `admm-ta agent --team FILE --id I --serve`, the same over JSON lines on
//!   standard input and output, for robot programs in any language;
//! * [`answer`]: what a robot gets back per episode, and the rows it cannot give;
//! * [`threads`]: a standing team in one process, a thread per robot (benchmarks,
//!   simulations);
//! * [`agreement`]: what the team floods around an episode and how it merges.

pub mod agreement;
pub mod answer;
mod episode;
mod epoch;
pub mod member;
mod outcome;
pub(crate) mod plane;
pub mod roster;
pub mod serve;
pub mod threads;

pub use answer::{Answer, LeaveRefused, RowError};
pub use member::TeamMember;
