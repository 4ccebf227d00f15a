//! The `uds` transport as the process orchestration sees it: an agent's connection and
//! blame (a neighbour whose socket closed is the one that failed).

use crate::endpoint::{
    AgentEndpoint, ConnectError, ConnectRequest, ProcessTransport, board_culprit,
};
use crate::exchange::{Exchange, ExchangeError};
use crate::uds::exchange::UdsExchange;
use std::time::Instant;

/// The `uds` transport's processes: open files per agent `6 + degree` (counted in
/// `/proc/PID/fd`: the board, the listener and one socket per neighbour).
pub struct UdsProcesses;

impl ProcessTransport for UdsProcesses {
    fn files_per_agent(&self, degree: usize) -> u64 {
        6 + degree as u64
    }

    fn connect(
        &self,
        request: &ConnectRequest,
        deadline: Instant,
    ) -> Result<Box<dyn AgentEndpoint>, ConnectError> {
        Ok(Box::new(UdsExchange::connect(request, deadline)?))
    }
}

impl AgentEndpoint for UdsExchange {
    fn exchange(&mut self) -> &mut dyn Exchange {
        self
    }

    fn blame_for(&self, error: &ExchangeError) {
        let culprit = match error {
            // A neighbour that closed or reset its socket is gone.
            ExchangeError::PeerFailed { failed, .. } => Some(*failed),
            e => board_culprit(e, || self.laggard()),
        };
        if let Some(culprit) = culprit {
            self.blame(culprit);
        }
    }
}
