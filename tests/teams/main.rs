//! Independently started teams: team files and members on one machine, and teams across hosts (Zenoh, mixed) over loopback and on network namespaces.
//!
//! One test binary per area (as ripgrep does): each file here is a module.

#[path = "../common/mod.rs"]
mod common;

mod multihost;
mod netns;
mod private;
mod team;
