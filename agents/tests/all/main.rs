//! The agents' integration tests: parsers, normalisation, projections, allocation-free steps, the two-block ADMM.
//!
//! One test binary per area (as ripgrep does): each file here is a module.

mod fuzz_parsers;
mod normalise;
mod projection_paths_agree;
mod step_does_not_allocate;
mod two_block_lasso;
