//! Where one agent's Zenoh session connects and listens, and the key expressions of a run.

use serde::{Deserialize, Serialize};

/// The Zenoh side of a scenario.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct ZenohLinks {
    /// Key-expression prefix of the run, e.g. `admm-ta/team/demo`: every key of the run
    /// lives below it, so runs sharing a Zenoh network never see each other's messages.
    pub key_prefix: String,
    /// Endpoints the session connects to: its host's router.
    pub connect: Vec<String>,
    /// The team's hosts (multi-host teams): an agent joins once all of them are up, so that
    /// every host sees the whole run.
    #[serde(default)]
    pub hosts: Vec<String>,
    /// One roster of a standing team (its name): the run's round messages, presence and
    /// failures live below `<key_prefix>/<epoch>`; hosts, digests and stop requests stay
    /// the team's.
    #[serde(default)]
    pub epoch: Option<String>,
}

impl ZenohLinks {
    /// Where the run's own keys live (the team's prefix, or its roster's below it).
    fn run_prefix(&self) -> std::borrow::Cow<'_, str> {
        match &self.epoch {
            Some(epoch) => format!("{}/{epoch}", self.key_prefix).into(),
            None => self.key_prefix.as_str().into(),
        }
    }

    /// Key agent `i` publishes its round messages on.
    pub fn round_key(&self, i: usize) -> String {
        format!("{}/round/{i}", self.run_prefix())
    }

    /// Key of agent `i`'s liveliness token (present while it runs).
    pub fn alive_key(&self, i: usize) -> String {
        format!("{}/alive/{i}", self.run_prefix())
    }

    /// Every agent's liveliness token.
    pub fn alive_all(&self) -> String {
        format!("{}/alive/*", self.run_prefix())
    }

    /// The agent whose liveliness token `key` is.
    pub fn agent_of_alive_key(&self, key: &str) -> Option<usize> {
        key.strip_prefix(self.run_prefix().as_ref())?
            .strip_prefix("/alive/")?
            .parse()
            .ok()
    }

    /// Key on which the index of the agent that failed is announced (the first one wins).
    pub fn failure_key(&self) -> String {
        format!("{}/failed", self.run_prefix())
    }

    /// Key on which stop requests (termination signals) are announced: the team's.
    pub fn stop_key(&self) -> String {
        format!("{}/failed", self.key_prefix)
    }

    /// Key of host `name`'s bridge for this run (a mixed team's: declared once it is
    /// subscribed to the other hosts' agents, so theirs may start).
    pub fn bridge_key(&self, name: &str) -> String {
        format!("{}/bridge/{name}", self.run_prefix())
    }

    /// Key of a standing team's robot `i` asking to join (present while it waits).
    pub fn joining_key(&self, i: usize) -> String {
        format!("{}/joining/{i}", self.key_prefix)
    }

    /// Every joining robot's key.
    pub fn joining_all(&self) -> String {
        format!("{}/joining/*", self.key_prefix)
    }

    /// The robot of joining key `key`.
    pub fn robot_of_joining_key(&self, key: &str) -> Option<usize> {
        key.strip_prefix(&self.key_prefix)?
            .strip_prefix("/joining/")?
            .parse()
            .ok()
    }

    /// Key of robot `i` being in roster `epoch` (named `name`, its robots as the bitmap
    /// `roster`) of a standing team, or (`formed`) of the roster having formed.
    pub fn epoch_key(&self, formed: bool, name: &str, roster: &str, i: usize) -> String {
        let what = if formed { "formed" } else { "in" };
        format!("{}/rosters/{what}/{name}/{roster}/{i}", self.key_prefix)
    }

    /// Every roster key ([`ZenohLinks::epoch_key`]).
    pub fn epoch_all(&self) -> String {
        format!("{}/rosters/**", self.key_prefix)
    }

    /// What roster key `key` says: formed (or in), the roster's name and bitmap, the robot.
    pub fn of_epoch_key<'k>(&self, key: &'k str) -> Option<(bool, &'k str, &'k str, usize)> {
        let rest = key
            .strip_prefix(&self.key_prefix)?
            .strip_prefix("/rosters/")?;
        let mut parts = rest.split('/');
        let formed = match parts.next()? {
            "formed" => true,
            "in" => false,
            _ => return None,
        };
        let (name, roster, robot) = (parts.next()?, parts.next()?, parts.next()?);
        if parts.next().is_some() {
            return None;
        }
        Some((formed, name, roster, robot.parse().ok()?))
    }

    /// Every host's liveliness token.
    pub fn host_all(&self) -> String {
        format!("{}/host/*", self.key_prefix)
    }

    /// Key of host `name`'s team-digest token: the hex digest of its team file and when it
    /// started (milliseconds since the epoch), so that the later of two differing hosts is
    /// the one refused.
    pub fn digest_key(&self, digest: &str, started_ms: u64, name: &str) -> String {
        format!("{}/digest/{digest}/{started_ms}/{name}", self.key_prefix)
    }

    /// Every host's team-digest token.
    pub fn digest_all(&self) -> String {
        format!("{}/digest/*/*/*", self.key_prefix)
    }

    /// The digest, start time and host of team-digest token `key`.
    pub fn of_digest_key(&self, key: &str) -> Option<(String, u64, String)> {
        let rest = key
            .strip_prefix(&self.key_prefix)?
            .strip_prefix("/digest/")?;
        let mut parts = rest.splitn(3, '/');
        let digest = parts.next()?.to_string();
        let started = parts.next()?.parse().ok()?;
        Some((digest, started, parts.next()?.to_string()))
    }

    /// Key of host `name`'s liveliness token (its router or bridge is up).
    pub fn host_key(&self, name: &str) -> String {
        format!("{}/host/{name}", self.key_prefix)
    }

    /// The host of host token `key`.
    pub fn host_of_key<'k>(&self, key: &'k str) -> Option<&'k str> {
        key.strip_prefix(&self.key_prefix)?.strip_prefix("/host/")
    }

    /// Key on which host `name` says goodbye before its token goes: a token that vanishes
    /// without it is a host lost (killed, crashed, cut off).
    pub fn goodbye_key(&self, name: &str) -> String {
        format!("{}/goodbye/{name}", self.key_prefix)
    }

    /// Every host's goodbye key.
    pub fn goodbye_all(&self) -> String {
        format!("{}/goodbye/*", self.key_prefix)
    }

    /// The host of goodbye key `key`.
    pub fn host_of_goodbye<'k>(&self, key: &'k str) -> Option<&'k str> {
        key.strip_prefix(&self.key_prefix)?
            .strip_prefix("/goodbye/")
    }
}

/// Checks that `endpoint` is a Zenoh TCP endpoint `tcp/ADDRESS:PORT` (the only link this
/// build carries).
pub fn check_endpoint(endpoint: &str) -> Result<(), NotAnEndpoint> {
    endpoint
        .strip_prefix("tcp/")
        .and_then(|address| address.rsplit_once(':'))
        .filter(|(host, port)| !host.is_empty() && port.parse::<u16>().is_ok())
        .map(|_| ())
        .ok_or_else(|| NotAnEndpoint {
            endpoint: endpoint.to_string(),
        })
}

/// A text that is no Zenoh TCP endpoint.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("'{endpoint}' is not a Zenoh TCP endpoint like tcp/192.168.1.10:7447")]
pub struct NotAnEndpoint {
    pub endpoint: String,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_of_a_run() {
        let links = ZenohLinks {
            key_prefix: "admm-ta/team/demo".into(),
            ..ZenohLinks::default()
        };
        assert_eq!(links.round_key(3), "admm-ta/team/demo/round/3");
        assert_eq!(links.agent_of_alive_key(&links.alive_key(12)), Some(12));
        assert_eq!(links.agent_of_alive_key("admm-ta/team/other/alive/1"), None);
        assert_eq!(links.agent_of_alive_key("admm-ta/team/demo/alive/x"), None);
        assert_eq!(
            links.of_digest_key(&links.digest_key("ab12", 7, "b")),
            Some(("ab12".into(), 7, "b".into()))
        );
        let roster = ZenohLinks {
            epoch: Some("e3xab".into()),
            ..links.clone()
        };
        assert_eq!(roster.round_key(3), "admm-ta/team/demo/e3xab/round/3");
        assert_eq!(roster.agent_of_alive_key(&roster.alive_key(4)), Some(4));
        assert_eq!(roster.agent_of_alive_key(&links.alive_key(4)), None);
        assert_eq!(roster.stop_key(), links.failure_key());
        assert_eq!(
            links.of_epoch_key(&links.epoch_key(true, "e3xab", "f1", 9)),
            Some((true, "e3xab", "f1", 9))
        );
        assert_eq!(links.robot_of_joining_key(&links.joining_key(2)), Some(2));
    }

    #[test]
    fn endpoints() {
        assert!(check_endpoint("tcp/10.0.0.2:7447").is_ok());
        assert!(check_endpoint("tcp/[::1]:7447").is_ok());
        for bad in [
            "udp/10.0.0.2:7447",
            "tcp/10.0.0.2",
            "tcp/10.0.0.2:99999",
            "tcp/:7447",
        ] {
            assert!(check_endpoint(bad).is_err(), "{bad}");
        }
    }
}
