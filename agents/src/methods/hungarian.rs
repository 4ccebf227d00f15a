//! The centralized optimum as a method (`--method hungarian`): the exact rectangular linear
//! sum assignment of [`crate::certify::oracle`] on the user's own numbers, in the caller's
//! process, one "round", no agents — the reference row of every comparison.

use crate::method::info::{
    Certification, Memory, MethodInfo, Numbers, OWN_STATE_STOPS, ReportText, Role,
    case_two_expansion,
};

/// The centralized optimum's registration.
pub const INFO: MethodInfo = MethodInfo {
    name: "hungarian",
    summary: "the centralized optimum, one round, sim only",
    role: Role::Centralized,
    team: None,
    variants: None,
    stops: OWN_STATE_STOPS,
    // The solver's copy of the costs (Case 2: its n×n expansion) and its O(n + m) arrays.
    memory: Memory {
        bytes: |n, m| 8.0 * ((n * m) as f64 + case_two_expansion(n, m) + 8.0 * (n + m) as f64),
        of: "working memory",
        because: "the centralized solver holds the n×m costs, n×n in Case 2",
    },
    certification: Certification::Always,
    numbers: Numbers::Exact,
    report: ReportText { inner_steps: None },
    paper: None,
};
