//! Shared numerics: exact rectangular linear sum assignment ([`lsap`], and its
//! allocation-free workspace [`lsap_workspace`]), the x-update's projections onto the
//! assignment polytope ([`projection`]) and the generic two-block ADMM of the tutorial
//! ([`two_block`]).

pub mod lsap;
pub mod lsap_workspace;
pub mod projection;
pub mod two_block;
