//! Why a process of a team — an agent, or a host of a team across machines — ended without
//! its result: refused before it ran (its input, or a team it does not belong to) or failed
//! while it ran. The command line maps the two to different exit codes (2 and 4), so
//! scripts can tell a wrong team file from a fault.

/// Why an agent or host process ended without its result; the text is one line.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MemberError {
    /// Nothing ran: the team file or scenario is bad or unreadable, the id or host name is
    /// not in it, the system's limits do not fit the agent, or its team file differs from the
    /// running team's.
    #[error("{0}")]
    Refused(String),
    /// The run failed: this agent, a neighbour or the transport, or a deadline.
    #[error("{0}")]
    Failed(String),
}

impl MemberError {
    /// The same error with `prefix` before its text.
    pub fn prefixed(self, prefix: &str) -> Self {
        match self {
            Self::Refused(text) => Self::Refused(format!("{prefix}{text}")),
            Self::Failed(text) => Self::Failed(format!("{prefix}{text}")),
        }
    }

    /// The one-line text.
    pub fn text(&self) -> &str {
        match self {
            Self::Refused(text) | Self::Failed(text) => text,
        }
    }
}

/// Errors of the run itself are one-line texts: a failure.
impl From<String> for MemberError {
    fn from(text: String) -> Self {
        Self::Failed(text)
    }
}

impl From<&str> for MemberError {
    fn from(text: &str) -> Self {
        Self::Failed(text.to_string())
    }
}
