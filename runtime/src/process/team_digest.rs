//! A team's identity: a SHA-256 over a canonical encoding of everything that defines the
//! team (costs, topology, method, every parameter, the payload length), not over the names
//! of one run (its id, shared-memory names, deadlines, wait strategy, which host).
//!
//! The launcher (or the first member of an independently started team) writes it on the
//! team's board; every agent compares its own with it before it opens a service, and one
//! that differs is refused by name before round 0, naming the first part that differs
//! (the board keeps a short digest of each part).

use crate::process::scenario::Scenario;
use admm_ta_transport::board::{Board, DIGEST_WORDS};
use sha2::{Digest, Sha256};

/// The parts of a team, in the order they are compared, and the scenario fields in each;
/// every other field not in [`RUN_ONLY`] belongs to the last part.
const PARTS: [(&str, &[&str]); 3] = [
    (
        "costs",
        &["robots", "tasks", "case", "cost_bits", "epsilon_bits"],
    ),
    ("topology", &["edges", "topology", "diameter"]),
    (
        "method",
        &["method", "settings", "workload", "adaptive_rho"],
    ),
];

/// Fields that name one run or one host, not the team.
const RUN_ONLY: [&str; 11] = [
    "run_id",
    "prefix",
    "transport_root",
    "board_shm",
    "transport_config",
    "local_agents",
    "roster",
    "round_timeout_ms",
    "startup_timeout_ms",
    "wait",
    "warmup_rounds",
];

/// Names of the parts, then "parameters" (seed, ρ, tolerance, stop rule, max rounds,
/// transport, global barrier, payload length).
const PART_NAMES: [&str; 4] = ["costs", "topology", "method", "parameters"];

/// A team's digest: 256 bits over all parts, and 64 bits per part.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TeamDigest {
    pub words: [u64; DIGEST_WORDS],
}

fn hash(bytes: &[u8]) -> [u8; 32] {
    Sha256::digest(bytes).into()
}

fn word(bytes: &[u8]) -> u64 {
    u64::from_le_bytes(bytes[..8].try_into().expect("8 bytes"))
}

impl TeamDigest {
    /// The digest of the team `scenario` describes.
    pub fn of(scenario: &Scenario) -> Self {
        let mut fields = match serde_json::to_value(scenario).expect("a scenario serialises") {
            serde_json::Value::Object(map) => map,
            _ => unreachable!("a scenario is a JSON object"),
        };
        for name in RUN_ONLY {
            fields.remove(name);
        }
        let mut parts = Vec::with_capacity(PART_NAMES.len());
        for (_, names) in PARTS {
            let part: serde_json::Map<String, serde_json::Value> = names
                .iter()
                .filter_map(|&n| fields.remove(n).map(|v| (n.to_string(), v)))
                .collect();
            parts.push(serde_json::to_vec(&part).expect("JSON"));
        }
        fields.insert("payload_len".into(), scenario.payload_len().into());
        // serde_json's maps are sorted by key: the encoding is canonical.
        parts.push(serde_json::to_vec(&fields).expect("JSON"));
        let digests: Vec<[u8; 32]> = parts.iter().map(|p| hash(p)).collect();
        let all = hash(&digests.concat());
        let mut words = [0u64; DIGEST_WORDS];
        for (k, chunk) in all.chunks(8).enumerate() {
            words[k] = word(chunk);
        }
        for (k, d) in digests.iter().enumerate() {
            words[4 + k] = word(d);
        }
        Self { words }
    }

    /// The first 4 hex digits of the whole digest (for messages).
    fn short(&self) -> String {
        format!("{:016x}", self.words[0].swap_bytes())[..4].to_string()
    }

    /// Writes this team's digest on `board` (its creator does, before any agent starts).
    pub fn publish(&self, board: &Board) {
        board.set_digest(&self.words);
    }

    /// The whole digest as hex (for a Zenoh key expression).
    pub fn to_hex(&self) -> String {
        self.words.iter().map(|w| format!("{w:016x}")).collect()
    }

    /// The digest written by [`Self::to_hex`].
    pub fn from_hex(hex: &str) -> Option<Self> {
        if hex.len() != 16 * DIGEST_WORDS || !hex.is_ascii() {
            return None;
        }
        let mut words = [0u64; DIGEST_WORDS];
        for (k, w) in words.iter_mut().enumerate() {
            *w = u64::from_str_radix(&hex[16 * k..16 * (k + 1)], 16).ok()?;
        }
        Some(Self { words })
    }

    /// Refuses `who` (e.g. "host b") if the running team's digest `running` is another:
    /// names the parts that differ.
    pub fn compare(&self, running: &Self, who: &str) -> Result<(), OtherTeam> {
        if running == self {
            return Ok(());
        }
        Err(OtherTeam {
            who: who.to_string(),
            ours: self.short(),
            running: running.short(),
            differs: PART_NAMES
                .iter()
                .enumerate()
                .filter(|(k, _)| self.words[4 + k] != running.words[4 + k])
                .map(|(_, name)| *name)
                .collect(),
        })
    }

    /// Refuses agent `agent` if `board`'s team is another: names the first part that
    /// differs. A board without a digest yet (a team being created) is no team to compare.
    pub fn check(&self, board: &Board, agent: usize) -> Result<(), OtherTeam> {
        let Some(running) = board.digest() else {
            return Ok(());
        };
        self.compare(&Self { words: running }, &format!("agent {agent}"))
    }
}

/// A member whose team file is not the running team's: who, both digests (short) and the
/// parts that differ.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "{who}'s team file differs from the running team's (digest {ours}… vs {running}…): {} differ{}",
    differs.join(" and "),
    if differs.len() == 1 && !differs[0].ends_with('s') { "s" } else { "" }
)]
pub struct OtherTeam {
    pub who: String,
    pub ours: String,
    pub running: String,
    /// Names of the parts that differ ("costs", "topology", "method", "parameters").
    pub differs: Vec<&'static str>,
}
