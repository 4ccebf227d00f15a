//! The `shm` transport as the process orchestration sees it: the run's slot table, created
//! before the agents start and removed after them, and an agent's connection and blame.

use crate::endpoint::{
    AgentEndpoint, ConnectError, ConnectRequest, ProcessTransport, Resource, RunRequest,
    SupportError, board_culprit,
};
use crate::exchange::{Exchange, ExchangeError};
use crate::shm::exchange::ShmExchange;
use crate::shm::table::{SlotTable, table_name};
use std::time::Instant;

/// The `shm` transport's processes.
pub struct ShmProcesses;

impl ProcessTransport for ShmProcesses {
    /// The board and the table, whatever the degree.
    fn files_per_agent(&self, _degree: usize) -> u64 {
        6
    }

    fn create_resources(
        &self,
        run: &RunRequest,
    ) -> Result<Option<Box<dyn Resource>>, SupportError> {
        let table = SlotTable::create(
            &table_name(&run.run.prefix),
            run.degrees.len(),
            run.payload_len,
        )
        .map_err(|e| SupportError::new(CannotCreate(e)))?;
        Ok(Some(Box::new(table)))
    }

    fn connect(
        &self,
        request: &ConnectRequest,
        deadline: Instant,
    ) -> Result<Box<dyn AgentEndpoint>, ConnectError> {
        Ok(Box::new(ShmExchange::connect(request, deadline)?))
    }
}

/// The slot table could not be created.
#[derive(Debug, thiserror::Error)]
#[error("cannot create the run's slot table")]
struct CannotCreate(#[source] crate::shm::table::TableError);

impl AgentEndpoint for ShmExchange {
    fn exchange(&mut self) -> &mut dyn Exchange {
        self
    }

    fn blame_for(&self, error: &ExchangeError) {
        if let Some(culprit) = board_culprit(error, || self.laggard()) {
            self.blame(culprit);
        }
    }
}
