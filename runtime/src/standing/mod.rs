//! Standing teams whose robots keep their own costs (`costs = "private"` in the team file).
//!
//! Every robot joins once and then solves episode after episode with the cost row its own
//! program gives it; no process ever reads, receives or stores another robot's costs. What
//! robots share besides the method's iterates is in [`agreement`]: the team's scale (lowest
//! and highest allowed cost, the lattice they lie on), who has no row, leaves or asks to
//! join, and after each episode every robot's cost of its own task and its task.
//!
//! Robots come and go while the team goes on: the team file lists the slots, the *roster*
//! is who takes part ([`roster`]). A roster changes at an episode boundary, as the robots
//! agreed in the episode's opening (leaves, joins), or after a robot vanished, as each of
//! the others sees it on the team's *plane* (`plane`); every roster is a fresh run of the
//! team's transport in a namespace of its own, on the graph it induces (`epoch`).
//!
//! * [`member`]: [`TeamMember`], one robot (join, then [`TeamMember::assign`] per episode,
//!   [`TeamMember::leave`]), and how it gets to a roster (joining, moving on, recovering);
//! * `episode` and `outcome`: one episode as one robot runs it (agreement, the method on
//!   the part of the roster that takes part, closing) and the answer it makes of it;
//! * `epoch`: one roster as one robot holds it (its namespace, its run of the transport);
//! * [`roster`]: who takes part, and the rules every robot applies alike to change it;
//! * `plane`: where the robots see each other across rosters (the team's board on one
//!   machine; `zenoh_plane`: Zenoh tokens across machines);
//! * [`serve`]: `admm-ta agent --team FILE --robot I --serve`, the same over JSON lines on
//!   standard input and output, for robot programs in any language;
//! * `ros2` (feature `ros2`): `--ros2`, the same over ROS 2 topics, for robot programs that
//!   are ROS 2 nodes;
//! * [`answer`]: what a robot gets back per episode, and the rows it cannot give;
//! * [`one_process`]: a standing team in one process, a thread per robot (benchmarks,
//!   simulations; its robots do not come and go);
//! * [`agreement`]: what the team floods around an episode and how it merges.

pub mod agreement;
pub mod answer;
mod episode;
mod epoch;
pub mod member;
pub mod one_process;
mod outcome;
pub(crate) mod plane;
#[cfg(feature = "ros2")]
pub mod ros2;
pub mod roster;
pub mod serve;
pub(crate) mod zenoh_plane;

pub use answer::{Answer, LeaveRefused, RowError};
pub use member::TeamMember;
