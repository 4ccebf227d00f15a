//! Pure algorithms of admm-ta: the task assignment model, one agent's consensus ADMM step
//! over preallocated buffers, the projections it needs, rounding, stopping rules and the
//! centralized oracle. No I/O, no threads, no transport: runners in `admm-ta-runtime`
//! drive the agents.

pub mod general;
pub mod lsap;
pub mod oracle;
pub mod problem;
pub mod projection;
