//! The hosts of a team file: robots named in their `agents` lists become numbers, and a
//! zenoh or mixed team puts every robot on exactly one host with its own endpoint.

use crate::process::namespace::RunNamespace;
use crate::team::errors::{HostsError, TeamFileError};
use admm_ta_agents::problem::{cost_file, read_cost_text};
use admm_ta_topologies::RobotRef;
use admm_ta_transport::Transport;
use admm_ta_transport::zenoh_net::links::check_endpoint;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// How an independently started team is deployed: on one machine or across several, and
/// what carries its messages (a team file's `transport` key).
///
/// It is not a [`Transport`]: `mixed` is two transports at once (iceoryx2 among the agents of
/// a host, Zenoh between hosts through each host's bridge), and a deployment decides more
/// than an agent's exchange — whether the team has hosts, a shared board per host, bridges.
/// [`Deployment::agent_transport`] is the exchange each agent runs. On one machine a team
/// may also run the `shm` reference transport (one shared slot table, created by the first
/// member) or the copying `uds` baseline, as `solve --transport` does: without a launcher
/// to `waitpid` them, a dead agent is found by its neighbours' round deadline on `shm`
/// (its socket closes at once on `uds`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Deployment {
    /// Every agent on this machine, iceoryx2 zero-copy (`iceoryx2`, or `ipc` as on the
    /// command line).
    #[default]
    #[serde(alias = "ipc")]
    Iceoryx2,
    /// Every agent on this machine, one shared table of slots (futex wake-ups).
    Shm,
    /// Every agent on this machine, payloads copied through Unix-domain sockets.
    Uds,
    /// Every agent a Zenoh client of its host's router.
    Zenoh,
    /// iceoryx2 among the agents of a host; the host's bridge carries what crosses hosts.
    Mixed,
}

impl Deployment {
    /// The transport every agent's exchange runs.
    pub fn agent_transport(self) -> Transport {
        match self {
            Self::Iceoryx2 | Self::Mixed => Transport::Ipc,
            Self::Shm => Transport::Shm,
            Self::Uds => Transport::Uds,
            Self::Zenoh => Transport::Zenoh,
        }
    }

    /// The team spans machines, named by its `[[hosts]]`.
    pub fn across_hosts(self) -> bool {
        matches!(self, Self::Zenoh | Self::Mixed)
    }

    /// The agents of a host share a board in shared memory (iceoryx2 and mixed teams); a
    /// Zenoh team's presence, failures and cleanup travel on Zenoh instead.
    pub fn host_board(self) -> bool {
        self != Self::Zenoh
    }

    /// Each host runs a bridge between its agents' iceoryx2 services and the other hosts.
    pub fn bridged(self) -> bool {
        self == Self::Mixed
    }
}

/// One machine of a multi-host team.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HostEntry {
    /// Letters, digits and dashes (`admm-ta host --name NAME`).
    pub name: String,
    /// The robots that run on it.
    pub agents: Vec<usize>,
    /// Where its Zenoh router listens, `tcp/ADDRESS:PORT`, reachable from the other hosts.
    pub endpoint: String,
}

/// The robot names of the cost file `costs` (relative to `base`; `random` has none).
pub(crate) fn cost_robot_names(
    base: &Path,
    costs: &str,
) -> Result<Option<Vec<String>>, TeamFileError> {
    if costs == "random" || costs == "private" {
        return Ok(None);
    }
    let path = base.join(costs);
    let file = read_cost_text(&path)
        .and_then(|text| cost_file::parse(&text, None))
        .map_err(|source| TeamFileError::File {
            path: path.clone(),
            source,
        })?;
    Ok(file.costs.robot_names().map(<[String]>::to_vec))
}

/// Replaces robot names in the hosts' `agents` lists of the team file's `table` by their
/// numbers, looked up in the cost file's robot names; a file without names is left as it is.
pub(crate) fn number_host_agents(
    table: &mut toml::Table,
    base: &Path,
    path: &Path,
) -> Result<(), TeamFileError> {
    let named = |host: &toml::Value| {
        host.get("agents")
            .and_then(toml::Value::as_array)
            .is_some_and(|agents| agents.iter().any(toml::Value::is_str))
    };
    let Some(toml::Value::Array(hosts)) = table.get("hosts") else {
        return Ok(());
    };
    if !hosts.iter().any(named) {
        return Ok(());
    }
    let names = match table.get("costs") {
        Some(toml::Value::String(costs)) => cost_robot_names(base, costs)?,
        // The file's own check names what is missing.
        _ => return Ok(()),
    };
    let Some(toml::Value::Array(hosts)) = table.get_mut("hosts") else {
        return Ok(());
    };
    for host in hosts.iter_mut() {
        let name = host
            .get("name")
            .and_then(toml::Value::as_str)
            .unwrap_or("")
            .to_string();
        let Some(toml::Value::Array(agents)) = host.get_mut("agents") else {
            continue;
        };
        for agent in agents.iter_mut() {
            if let toml::Value::String(robot) = agent {
                let number = RobotRef::Name(std::mem::take(robot))
                    .resolve(names.as_deref())
                    .map_err(|source| TeamFileError::HostRobot {
                        path: path.to_path_buf(),
                        host: name.clone(),
                        source: Box::new(source),
                    })?;
                *agent = toml::Value::Integer(number as i64);
            }
        }
    }
    Ok(())
}

/// Checks the hosts of a team file: a zenoh or mixed team puts every robot on exactly one
/// named host with a distinct TCP endpoint; an iceoryx2 team has no hosts.
pub(crate) fn check_hosts(
    run: &str,
    robots: usize,
    transport: Deployment,
    hosts: &[HostEntry],
) -> Result<(), HostsError> {
    if !transport.across_hosts() {
        if !hosts.is_empty() {
            return Err(HostsError::NotAcrossHosts);
        }
        return Ok(());
    }
    if hosts.is_empty() {
        return Err(HostsError::None);
    }
    let mut host_of = vec![None; robots];
    for (h, host) in hosts.iter().enumerate() {
        if RunNamespace::check_team_name(&host.name).is_err() {
            return Err(HostsError::BadName(host.name.clone()));
        }
        check_endpoint(&host.endpoint).map_err(|source| HostsError::Endpoint {
            host: host.name.clone(),
            source,
        })?;
        if let Some(other) = hosts[..h].iter().find(|o| o.name == host.name) {
            return Err(HostsError::SameName(other.name.clone()));
        }
        if let Some(other) = hosts[..h].iter().find(|o| o.endpoint == host.endpoint) {
            return Err(HostsError::SameEndpoint {
                first: other.name.clone(),
                second: host.name.clone(),
                endpoint: host.endpoint.clone(),
            });
        }
        for &a in &host.agents {
            let slot = host_of.get_mut(a).ok_or_else(|| HostsError::NoSuchRobot {
                host: host.name.clone(),
                robot: a,
                robots,
            })?;
            if let Some(other) = slot.replace(h) {
                return Err(HostsError::TwoHosts {
                    robot: a,
                    first: hosts[other].name.clone(),
                    second: host.name.clone(),
                });
            }
        }
    }
    if transport.bridged()
        && let Some(host) = hosts.iter().find(|h| run.len() + 1 + h.name.len() > 40)
    {
        return Err(HostsError::NameTooLong {
            run: run.to_string(),
            host: host.name.clone(),
        });
    }
    let homeless: Vec<usize> = (0..robots).filter(|&a| host_of[a].is_none()).collect();
    if !homeless.is_empty() {
        return Err(HostsError::Homeless(homeless));
    }
    Ok(())
}
