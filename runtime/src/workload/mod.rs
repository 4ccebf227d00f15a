//! What a team's agents are built from and what they compute.
//!
//! * [`plan`]: a solve's agents — ρ, γ, tolerance, perturbation and settings, computed once;
//! * [`episode`]: the surveillance robots' repeated assignments.

pub mod episode;
pub mod plan;
