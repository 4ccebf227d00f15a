//! What a Zenoh router carries: every round message of a run passes through one (the
//! launcher's on loopback, or each host's), so its rate bounds a team's round. The launcher
//! refuses a team whose round it cannot carry within half the round deadline
//! ([`crate::endpoint::ProcessTransport::relay_bytes_per_second`]), and an agent waits for
//! about that long before it sends its first messages again.

/// Bytes a second a team's routers relay, at least: one loopback router on 2 cores relayed
/// a round of 200 agents on `random:0.1` (4 000 messages of 320 kB, 1.28 GB) in 1.2–1.7 s
/// (issue 49).
pub const RELAY_BYTES_PER_SECOND: f64 = 1e9;
