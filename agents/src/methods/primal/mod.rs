//! Primal consensus ADMM (Algorithm 1) in its two variants: the agent ([`agent`]), its
//! settings and variants ([`settings`]), and the fast variant's consensus step
//! ([`fast_consensus`]), readout ([`readout`]) and extrapolated readout
//! ([`readout_filter`]).

pub mod agent;
pub mod fast_consensus;
pub mod readout;
pub mod readout_filter;
pub mod settings;
