//! The `ipc` transport as the process orchestration sees it: every iceoryx2 service of the
//! run, created before the agents start (agents only open them), an agent's connection and
//! blame, and the dead agents' nodes cleaned up after a failure.
//!
//! Open files per agent process, counted in `/proc/PID/fd` on real runs and fitted (degree
//! `d`): `19 + 11·d` (degree 1, 2, 9, 49: 30, 41, 118, 558 — each neighbour costs a
//! subscriber, a notifier and their shared-memory connections and segments).

use crate::endpoint::{
    AgentEndpoint, ConnectError, ConnectRequest, ProcessTransport, Resource, RunPlace, RunRequest,
    SupportError, board_culprit,
};
use crate::exchange::{Exchange, ExchangeError};
use crate::ipc::exchange::IpcExchange;
use crate::ipc::nodes::{cleanup_dead_nodes, run_config};
use crate::ipc::services::RunServices;
use std::time::Instant;

/// The `ipc` transport's processes.
pub struct IpcProcesses;

impl ProcessTransport for IpcProcesses {
    fn files_per_agent(&self, degree: usize) -> u64 {
        19 + 11 * degree as u64
    }

    fn create_resources(
        &self,
        run: &RunRequest,
    ) -> Result<Option<Box<dyn Resource>>, SupportError> {
        let config = run_config(&run.run.prefix, &run.run.root).map_err(SupportError::new)?;
        let services =
            RunServices::create(&config, &run.degrees, run.bridged).map_err(SupportError::new)?;
        Ok(Some(Box::new(services)))
    }

    fn connect(
        &self,
        request: &ConnectRequest,
        deadline: Instant,
    ) -> Result<Box<dyn AgentEndpoint>, ConnectError> {
        let config =
            run_config(&request.run.prefix, &request.run.root).map_err(ConnectError::setup)?;
        Ok(Box::new(IpcExchange::connect(request, &config, deadline)?))
    }

    fn cleanup_dead(&self, run: &RunPlace) -> Option<usize> {
        Some(
            run_config(&run.prefix, &run.root)
                .map(|config| cleanup_dead_nodes(&config))
                .unwrap_or(0),
        )
    }
}

impl AgentEndpoint for IpcExchange {
    fn exchange(&mut self) -> &mut dyn Exchange {
        self
    }

    fn blame_for(&self, error: &ExchangeError) {
        if let Some(culprit) = board_culprit(error, || self.laggard()) {
            self.blame(culprit);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ipc::services::{Svc, open_round_service};
    use iceoryx2::prelude::*;

    #[test]
    fn agents_only_open_the_services_their_creator_made() {
        let unique = format!(
            "admmtest{}x{}",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .unwrap()
                .as_nanos()
        );
        let prefix = format!("{unique}_");
        let root = std::env::temp_dir().join(&unique);
        std::fs::create_dir_all(&root).unwrap();
        let config = run_config(&prefix, &root).unwrap();
        let node = NodeBuilder::new()
            .config(&config)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<Svc>()
            .unwrap();
        // Before the creator: nothing to open (an agent never creates a service).
        assert!(open_round_service(&node, 0, 2).is_err());
        let degrees = [2, 2, 2];
        let services = RunServices::create(&config, &degrees, false).unwrap();
        for (j, &degree) in degrees.iter().enumerate() {
            let service = open_round_service(&node, j, degree).unwrap();
            assert_eq!(service.static_config().max_subscribers(), 2);
        }
        // One creator per run.
        assert!(RunServices::create(&config, &degrees, false).is_err());
        drop(services);
        drop(node);
        // What a run's namespace cleanup removes (the launcher's tests check that it does).
        for entry in std::fs::read_dir("/dev/shm")
            .into_iter()
            .flatten()
            .flatten()
        {
            if entry.file_name().to_string_lossy().starts_with(&prefix) {
                let _ = std::fs::remove_file(entry.path());
            }
        }
        let _ = std::fs::remove_dir_all(&root);
    }
}
