//! What Zenoh refused, with Zenoh's own words, and a Zenoh entry point in a build without
//! it.

/// A Zenoh entry point in a build without the `zenoh` feature.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error(
    "this admm-ta was built without Zenoh support: rebuild with `cargo build --release --features zenoh`"
)]
pub struct ZenohNotBuilt;

/// What Zenoh refused, with Zenoh's own words.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{what}: {detail}")]
pub struct ZenohError {
    /// What was tried.
    pub what: String,
    /// Zenoh's error, as its text (Zenoh's errors are neither `Clone` nor `PartialEq`).
    pub detail: String,
}

impl ZenohError {
    pub fn new(what: impl Into<String>, error: impl std::fmt::Display) -> Self {
        Self {
            what: what.into(),
            detail: error.to_string(),
        }
    }
}
