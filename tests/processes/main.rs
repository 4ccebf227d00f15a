//! Agent processes as a Unix tool runs them: every transport, blame of the failed agent, injected faults, signals, system limits, private directories, stress.
//!
//! One test binary per area (as ripgrep does): each file here is a module.

#[path = "../common/mod.rs"]
mod common;

mod blame;
mod faults;
mod limits;
mod logs;
mod private_dirs;
mod signals;
mod stress;
mod timeline;
mod top;
mod transports;
