//! Pure algorithms of admm-ta: the task assignment model, one agent's consensus ADMM step
//! over preallocated buffers, the projections it needs, rounding, stopping rules and the
//! centralized oracle. No I/O, no threads, no transport: runners in `admm-ta-runtime`
//! drive the agents through [`agent::ConsensusAgent`]. The methods and what each needs and
//! supports are declared once, in the registry of [`method`]; [`method_agent::MethodAgent`]
//! runs any of them.

pub mod agent;
pub mod cbaa;
pub mod cost_model;
pub mod costs;
pub mod dist_hungarian;
pub mod dual;
pub mod fast_consensus;
pub mod feasibility;
pub mod forbidden;
pub mod general;
pub mod local_stop;
pub mod lsap;
pub mod lsap_workspace;
pub mod market;
pub mod method;
pub mod method_agent;
pub mod normalise;
pub mod oracle;
pub mod primal;
pub mod primal_settings;
pub mod probe;
pub mod problem;
pub mod projection;
pub mod readout;
pub mod readout_filter;
pub mod rho;
pub mod rounding;
pub mod stopping;
pub mod surveillance;
pub mod ties;
pub mod two_block;
mod value_enum;
