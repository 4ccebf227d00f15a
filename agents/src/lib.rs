//! Pure algorithms of admm-ta: the task assignment model, one agent's consensus ADMM step
//! over preallocated buffers, the projections it needs, rounding, stopping rules and the
//! centralized oracle. No I/O, no threads, no transport: runners in `admm-ta-runtime`
//! drive the agents through [`agent::ConsensusAgent`].
//!
//! * [`problem`]: the user's problem and the normalised one the agents solve (costs,
//!   cases, forbidden pairs, feasibility, normalisation, ties, random cost models);
//! * [`methods`]: one module per method, each registered once in the method registry
//!   ([`methods::Method`]), and the latency probe;
//! * [`method`]: what every method declares (its information, its settings, how its team
//!   is built) and [`method::agent::MethodAgent`], which runs any of them;
//! * [`numerics`]: exact linear sum assignment, the projections of the x-update, the
//!   two-block ADMM of the tutorial;
//! * [`certify`]: stop rules, the decentralized certified stop, rounding and repair, the
//!   centralized oracle.

pub mod agent;
pub mod certify;
pub mod method;
pub mod methods;
pub mod numerics;
pub mod problem;
mod value_enum;
