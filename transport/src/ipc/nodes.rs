//! The iceoryx2 nodes of a run: its configuration (own prefix and root), the agents' node
//! names, and the dead-node scans that find a crashed agent without a launcher.

use crate::board::Board;
use crate::ipc::services::Svc;
use iceoryx2::node::NodeView;
use iceoryx2::prelude::*;

/// See [`run_config`].
const CREATION_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(10);

/// The iceoryx2 configuration of a run: its own prefix and root directory, and no dead-node
/// scans (the launcher owns cleanup; the scans made start-up of a 50-agent complete graph
/// several times slower).
pub fn run_config(prefix: &str, root: &std::path::Path) -> Result<Config, RunNameError> {
    let mut config = Config::default();
    config.global.prefix = FileName::new(prefix.as_bytes()).map_err(|e| RunNameError::Prefix {
        prefix: prefix.to_string(),
        detail: format!("{e:?}"),
    })?;
    let root = format!("{}/", root.display());
    config
        .global
        .set_root_path(&Path::new(root.as_bytes()).map_err(|e| RunNameError::Root {
            detail: format!("{e:?}"),
            root: root.clone(),
        })?);
    // How long a process waits for another to finish creating a service or a connection:
    // iceoryx2's 1 s default was exceeded by teams starting at once on a loaded 2-core
    // machine, and a connection to a subscriber that times out is skipped for good (the
    // "round 0 reached 8 of 9 neighbours" false failure).
    config.global.creation_timeout = CREATION_TIMEOUT;
    config.global.node.cleanup_dead_nodes_on_creation = false;
    config.global.node.cleanup_dead_nodes_on_destruction = false;
    config.global.service.cleanup_dead_nodes_on_open = false;
    // Every subscriber allocates (and zeroes) room for this many expired connections (a
    // publisher gone while its samples are still borrowed): 128 by default, where a round
    // service has one publisher whose samples a subscriber borrows at most
    // `SUBSCRIBER_BORROWED` of. The default made the subscribers the largest cost of
    // start-up.
    config
        .defaults
        .publish_subscribe
        .subscriber_expired_connection_buffer = crate::ipc::services::SUBSCRIBER_BORROWED;
    Ok(config)
}

/// A run prefix or root that iceoryx2 cannot use as a file name or path.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RunNameError {
    #[error("bad iceoryx2 prefix {prefix:?}: {detail}")]
    Prefix { prefix: String, detail: String },
    #[error("bad iceoryx2 root {root:?}: {detail}")]
    Root { root: String, detail: String },
}

/// iceoryx2 node name of agent `i` (how others recognise it among dead nodes).
pub fn node_name(i: usize) -> String {
    format!("agent-{i}")
}

/// Agent index of an iceoryx2 node name made by [`node_name`].
pub fn agent_of_node(name: &str) -> Option<usize> {
    name.strip_prefix("agent-")?.parse().ok()
}

/// Looks for a dead agent among the run's iceoryx2 nodes; marks the first found on the board
/// and removes its stale resources. Returns its index.
pub fn scan_dead_agents(config: &Config, me: usize, board: &Board) -> Option<usize> {
    let mut dead = None;
    let _ = Node::<Svc>::list(config, |state| {
        if let NodeState::Dead(view) = state {
            let agent = view
                .details()
                .as_ref()
                .and_then(|d| agent_of_node(d.name().as_str()));
            if let Some(agent) = agent.filter(|&a| a != me) {
                // Whoever gets there first cleans up; the others find the node gone.
                let _ = view.try_remove_stale_resources();
                // An agent that finished its run is leaving, not dead (its node can look
                // dead while it goes away: a false failure at the end of a run otherwise).
                if board.finished(agent) {
                    return CallbackProgression::Continue;
                }
                dead = Some(agent);
                return CallbackProgression::Stop;
            }
        }
        CallbackProgression::Continue
    });
    let agent = dead?;
    Some(board.mark_failed(agent).unwrap_or(agent))
}

/// Removes the stale resources of every dead node of the run; returns how many it removed.
/// A node killed before it wrote its details is left to the namespace cleanup: iceoryx2
/// would clean it with its *global* configuration (another prefix and root, and a warning
/// on stderr that broke the launcher's one-line error once in the fault tests).
pub fn cleanup_dead_nodes(config: &Config) -> usize {
    let mut removed = 0;
    let _ = Node::<Svc>::list(config, |state| {
        if let NodeState::Dead(view) = state
            && view.details().is_some()
            && view.try_remove_stale_resources().is_ok()
        {
            removed += 1;
        }
        CallbackProgression::Continue
    });
    removed
}
