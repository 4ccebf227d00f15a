//! Zenoh session configurations, as `rmw_zenoh` deploys them: agents are peers that connect
//! to their host's router and listen on loopback, so that agents of one host link to each
//! other directly once the router's gossip introduces them (one hop instead of two through
//! the router: 1.7 vs 2.3 ms per round for 10 agents on a complete graph here, 0.45 vs 0.73
//! on a ring); routers link the hosts and carry the traffic between them. Multicast scouting is off everywhere: a team names its endpoints (robot networks
//! often drop multicast, and a test must not find another test's sessions).

use crate::zenoh_net::ZenohError;
use std::time::Duration;
use zenoh::{Config, Session, Wait};

/// What a session is for.
pub(crate) enum Role {
    /// An agent: a peer that must reach its router within `within`, or fail.
    Agent { within: Duration },
    /// A host's router: keeps trying the other hosts' routers in the background.
    Router,
}

fn set(config: &mut Config, key: &str, value: &str) -> Result<(), ZenohError> {
    config
        .insert_json5(key, value)
        .map_err(|e| ZenohError::new(format!("Zenoh configuration {key} = {value}"), e))
}

fn list(items: &[String]) -> String {
    serde_json::to_string(items).expect("strings serialise")
}

/// The configuration of a session of `role` listening on `listen` and connecting to
/// `connect`.
pub(crate) fn config(
    role: &Role,
    listen: &[String],
    connect: &[String],
) -> Result<Config, ZenohError> {
    let mut config = Config::default();
    let mode = match role {
        Role::Agent { .. } => "\"peer\"",
        Role::Router => "\"router\"",
    };
    set(&mut config, "mode", mode)?;
    set(&mut config, "scouting/multicast/enabled", "false")?;
    set(&mut config, "listen/endpoints", &list(listen))?;
    set(&mut config, "connect/endpoints", &list(connect))?;
    match role {
        Role::Agent { within } => {
            let ms = within.as_millis().clamp(1, i64::MAX as u128);
            set(&mut config, "connect/timeout_ms", &ms.to_string())?;
            set(&mut config, "connect/exit_on_failure", "true")?;
        }
        Role::Router => {
            set(&mut config, "connect/timeout_ms", "-1")?;
            set(&mut config, "connect/exit_on_failure", "false")?;
        }
    }
    Ok(config)
}

/// Opens a session of `role`.
pub(crate) fn open(
    role: &Role,
    listen: &[String],
    connect: &[String],
) -> Result<Session, ZenohError> {
    let config = config(role, listen, connect)?;
    zenoh::open(config).wait().map_err(|e| {
        ZenohError::new(
            format!("cannot open a Zenoh session (listen {listen:?}, connect {connect:?})"),
            e,
        )
    })
}

/// The keys below `key` with a liveliness token on the network now.
pub(crate) fn alive_keys(session: &Session, key: String) -> Result<Vec<String>, ZenohError> {
    let replies = session
        .liveliness()
        .get(&key)
        .timeout(Duration::from_secs(1))
        .wait()
        .map_err(|e| ZenohError::new(format!("cannot ask for the liveliness tokens {key}"), e))?;
    let mut keys = Vec::new();
    while let Ok(reply) = replies.recv() {
        if let Ok(sample) = reply.result() {
            keys.push(sample.key_expr().as_str().to_string());
        }
    }
    Ok(keys)
}

/// The hosts of `links` whose tokens are not on the network now.
pub(crate) fn missing_hosts(
    session: &Session,
    links: &crate::zenoh_net::links::ZenohLinks,
) -> Result<Vec<String>, ZenohError> {
    let up = alive_keys(session, links.host_all())?;
    Ok(links
        .hosts
        .iter()
        .filter(|h| !up.contains(&links.host_key(h)))
        .cloned()
        .collect())
}

/// The agents whose liveliness tokens are on the network now, asked with a liveliness query.
/// A liveliness subscriber with history can miss tokens declared while the subscriber's own
/// declaration propagates (seen with a router's local subscriber and clients that connected
/// during its start-up), so presence checks that must not miss anybody ask.
pub(crate) fn alive_agents(
    session: &Session,
    links: &crate::zenoh_net::links::ZenohLinks,
) -> Result<Vec<usize>, ZenohError> {
    Ok(alive_keys(session, links.alive_all())?
        .iter()
        .filter_map(|k| links.agent_of_alive_key(k))
        .collect())
}

/// Announces agent `failed` as the one that failed on the run of `links`: every agent and
/// host of the run stops (the first announcement is the one they report).
pub(crate) fn announce_failure(
    session: &Session,
    links: &crate::zenoh_net::links::ZenohLinks,
    failed: usize,
) {
    let _ = session
        .put(links.failure_key(), failed.to_string())
        .congestion_control(zenoh::qos::CongestionControl::Block)
        .wait();
}

/// Asks every agent and host of the run of `links` to stop: termination signal `signal`
/// (on the failure key, as `stop N`: [`watch_failures`] ignores it, [`watch_stops`] sees it).
pub(crate) fn announce_stop(
    session: &Session,
    links: &crate::zenoh_net::links::ZenohLinks,
    signal: i32,
) {
    let _ = session
        .put(links.failure_key(), format!("stop {signal}"))
        .congestion_control(zenoh::qos::CongestionControl::Block)
        .wait();
}

/// Calls `on_stop` with the signal of every stop request announced on the run of `links`.
pub(crate) fn watch_stops(
    session: &Session,
    links: &crate::zenoh_net::links::ZenohLinks,
    on_stop: impl Fn(i32) + Send + Sync + 'static,
) -> Result<zenoh::pubsub::Subscriber<()>, ZenohError> {
    session
        .declare_subscriber(links.failure_key())
        .callback(move |sample| {
            let text = String::from_utf8_lossy(&sample.payload().to_bytes()).into_owned();
            if let Some(signal) = text
                .trim()
                .strip_prefix("stop ")
                .and_then(|s| s.parse::<i32>().ok())
            {
                on_stop(signal);
            }
        })
        .wait()
        .map_err(|e| ZenohError::new("cannot watch the run's stop requests", e))
}

/// Calls `on_failure` with every agent announced as failed on the run of `links`.
pub(crate) fn watch_failures(
    session: &Session,
    links: &crate::zenoh_net::links::ZenohLinks,
    on_failure: impl Fn(usize) + Send + Sync + 'static,
) -> Result<zenoh::pubsub::Subscriber<()>, ZenohError> {
    session
        .declare_subscriber(links.failure_key())
        .callback(move |sample| {
            let announced = String::from_utf8_lossy(&sample.payload().to_bytes())
                .trim()
                .parse::<usize>();
            if let Ok(failed) = announced {
                on_failure(failed);
            }
        })
        .wait()
        .map_err(|e| ZenohError::new("cannot watch the run's failure announcements", e))
}
