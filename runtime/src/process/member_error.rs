//! Why a process of a team — an agent, or a host of a team across machines — ended without
//! its result: refused before it ran (its input, or a team it does not belong to) or failed
//! while it ran. The command line maps the two to different exit codes (2 and 4), so
//! scripts can tell a wrong team file from a fault; the cause keeps its own type (a
//! [`crate::team::errors::TeamFileError`], an [`admm_ta_transport::exchange::ExchangeError`], a
//! [`crate::process::team_digest::OtherTeam`], …) for a library user to inspect with
//! [`MemberError::cause`] and `downcast_ref`.

use admm_ta_transport::error_text::one_line;

/// The typed cause of a [`MemberError`].
pub type Cause = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Why an agent or host process ended without its result.
#[derive(Debug, thiserror::Error)]
pub enum MemberError {
    /// Nothing ran: the team file or scenario is bad or unreadable, the id or host name is
    /// not in it, the system's limits do not fit the agent, or its team file differs from the
    /// running team's.
    #[error(transparent)]
    Refused(Cause),
    /// The run failed: this agent, a neighbour or the transport, or a deadline.
    #[error(transparent)]
    Failed(Cause),
}

impl MemberError {
    /// A refusal because of `cause`.
    pub fn refused(cause: impl Into<Cause>) -> Self {
        Self::Refused(cause.into())
    }

    /// A failure because of `cause`.
    pub fn failed(cause: impl Into<Cause>) -> Self {
        Self::Failed(cause.into())
    }

    /// Whether nothing ran.
    pub fn is_refusal(&self) -> bool {
        matches!(self, Self::Refused(_))
    }

    /// The typed cause.
    pub fn cause(&self) -> &(dyn std::error::Error + Send + Sync + 'static) {
        match self {
            Self::Refused(cause) | Self::Failed(cause) => cause.as_ref(),
        }
    }

    /// The same error with `prefix` before its text (the cause stays the source).
    pub fn prefixed(self, prefix: &str) -> Self {
        let wrap = |cause: Cause| -> Cause {
            Box::new(Prefixed {
                prefix: prefix.to_string(),
                cause,
            })
        };
        match self {
            Self::Refused(cause) => Self::Refused(wrap(cause)),
            Self::Failed(cause) => Self::Failed(wrap(cause)),
        }
    }

    /// The one-line text, causes included.
    pub fn text(&self) -> String {
        one_line(self)
    }
}

/// A cause with a prefix before its text (`agent 3: …`).
#[derive(Debug)]
struct Prefixed {
    prefix: String,
    cause: Cause,
}

impl std::fmt::Display for Prefixed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}{}", self.prefix, self.cause)
    }
}

impl std::error::Error for Prefixed {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.cause.source()
    }
}
