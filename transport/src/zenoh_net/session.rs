//! Zenoh session configurations: agents are **clients** of their host's router, and routers
//! link the hosts and carry the traffic between them. Multicast scouting is off everywhere: a
//! team names its endpoints (robot networks often drop multicast, and a test must not find
//! another test's sessions).
//!
//! Why clients and not peers (as `rmw_zenoh` deploys them): peers of one host link to each
//! other directly once the router's gossip introduces them — one hop instead of two, but
//! `k(k − 1)/2` links for `k` agents, all opened at start-up, each tried **once** (a failed
//! gossip connection is logged and never retried), and a Zenoh router does not relay between
//! two peers of its own region. At 100 agents (4 950 links, each process accepting at most
//! `accept_pending` = 100 handshakes at once) some pair always stayed unlinked, for the whole
//! run: its round messages had no route, and resending could not help (issue 36). A client
//! has one link, to its router, which relays between its clients; the router accepts as many
//! handshakes as a fleet opens at once (`ROUTER_ACCEPT_PENDING`).
use crate::zenoh_net::error::ZenohError;
use std::time::Duration;
use zenoh::{Config, Session, Wait};

/// What a session is for.
pub enum Role {
    /// An agent: a client that must reach its router within `within`, or fail.
    Agent { within: Duration },
    /// A host's router: keeps trying the other hosts' routers in the background.
    Router,
}

/// Batches (64 kB each) of a link's data queue (Zenoh allows 1…16, default 2).
const TX_QUEUE_BATCHES: usize = 16;

/// How long a push with blocking congestion control may wait for room in a link's queue
/// before Zenoh closes the link (Zenoh's default: 5 s), in microseconds: a round's default
/// deadline. A closed link is not a slow one: its client reconnects with a new session
/// whose key-expression ids the router no longer maps to the old ones ("Received Data for
/// unknown expr_id"), and round messages were routed to other agents' subscriptions (issue
/// 49: 200 agents with 320 kB messages through one router on 2 cores — the router could not
/// push a round's burst into a starved agent's link within 5 s, closed it, and agents saw
/// "the message on neighbour 95's service claims to come from agent 54", a payload of 0
/// values, or a neighbour's token vanish). A congested link now only slows the round; the
/// round's deadline, not Zenoh, decides when a team is too slow.
const BLOCK_BEFORE_CLOSE_US: u64 = 30_000_000;

/// Handshakes a router accepts at once: more than a team has agents.
const ROUTER_ACCEPT_PENDING: usize = 4096;

/// Sessions a router holds: its clients and the other hosts' routers.
const ROUTER_MAX_SESSIONS: usize = 8192;

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
pub fn config(role: &Role, listen: &[String], connect: &[String]) -> Result<Config, ZenohError> {
    let mut config = Config::default();
    let mode = match role {
        Role::Agent { .. } => "\"client\"",
        Role::Router => "\"router\"",
    };
    set(&mut config, "mode", mode)?;
    set(&mut config, "scouting/multicast/enabled", "false")?;
    set(&mut config, "listen/endpoints", &list(listen))?;
    set(&mut config, "connect/endpoints", &list(connect))?;
    // A round message of a large team is bigger than a batch (100 × 100 f64: 80 kB, two
    // 64 kB batches): with Zenoh's two batches per priority queue one message fills a link's
    // queue and the router relays one message at a time; sixteen (1 MB per link) let it
    // relay a round's burst.
    set(
        &mut config,
        "transport/link/tx/queue/size/data",
        &TX_QUEUE_BATCHES.to_string(),
    )?;
    set(
        &mut config,
        "transport/link/tx/queue/congestion_control/block/wait_before_close",
        &BLOCK_BEFORE_CLOSE_US.to_string(),
    )?;
    match role {
        Role::Agent { within } => {
            let ms = within.as_millis().clamp(1, i64::MAX as u128);
            set(&mut config, "connect/timeout_ms", &ms.to_string())?;
            set(&mut config, "connect/exit_on_failure", "true")?;
        }
        Role::Router => {
            set(&mut config, "connect/timeout_ms", "-1")?;
            set(&mut config, "connect/exit_on_failure", "false")?;
            // A fleet's agents connect at once: every handshake is accepted (Zenoh's
            // default, 100 pending, closes the rest silently).
            set(
                &mut config,
                "transport/unicast/accept_pending",
                &ROUTER_ACCEPT_PENDING.to_string(),
            )?;
            set(
                &mut config,
                "transport/unicast/max_sessions",
                &ROUTER_MAX_SESSIONS.to_string(),
            )?;
        }
    }
    Ok(config)
}

/// Worker threads of Zenoh's receive runtime in a process whose router holds `links` links:
/// one per link, and two to spare.
///
/// Why (issue 36): a Zenoh router forwards a received message on the receiving link's task,
/// and a push with blocking congestion control into a full link queue blocks the worker
/// *thread* that task runs on (it waits on a condition variable inside the task). Zenoh's
/// receive runtime has two worker threads by default. At 100 agents on four hosts, both
/// workers of every router ended up blocked pushing round messages towards another router
/// whose two workers were blocked the same way: no router read any link any more, until
/// Zenoh closed a link after `wait_before_close` (5 s; set to 60 s, the routers stayed stuck
/// for 60 s — seen in thread dumps of the four routers, both `rx` threads of each waiting in
/// `push_network_message` from `route_data`), and the round messages on it were lost. With a
/// worker per link, a blocked push holds only its own link's reader: every router keeps
/// reading the other routers, and every queue drains. (One router alone, as a launcher's on
/// loopback, cannot wait in a circle: its clients always read.)
fn router_rx_workers(links: usize) -> usize {
    links + 2
}

/// Sizes Zenoh's receive runtime for a router holding `links` links (see
/// `router_rx_workers`), unless the user configured Zenoh's runtimes (`ZENOH_RUNTIME`).
/// Zenoh reads that variable when it starts its first runtime; later calls change nothing.
///
/// # Safety
/// Changes the process's environment: nothing else may read or write it at the same time —
/// call it before the process starts any other thread.
pub unsafe fn size_router_runtime(links: usize) {
    const VARIABLE: &str = RUNTIME_VARIABLE;
    match std::env::var_os(VARIABLE) {
        None => {
            let setting = format!("(rx: (worker_threads: {}))", router_rx_workers(links));
            // SAFETY: the caller runs no other thread (this function's contract).
            unsafe { std::env::set_var(VARIABLE, setting) };
        }
        Some(given) if !given.to_string_lossy().contains("rx") => tracing::warn!(
            given = %given.to_string_lossy(),
            wanted = router_rx_workers(links),
            "ZENOH_RUNTIME is set without `rx`: the router keeps Zenoh's two receive workers, and a fleet's routers can block each other"
        ),
        Some(_) => {}
    }
}

/// Whether this process runs a single thread (Linux's `/proc/self/status`): the only time
/// changing its environment is sound.
pub fn single_threaded() -> bool {
    std::fs::read_to_string("/proc/self/status").is_ok_and(|status| {
        status
            .lines()
            .find_map(|l| l.strip_prefix("Threads:"))
            .is_some_and(|n| n.trim() == "1")
    })
}

/// Sizes Zenoh's receive runtime for a router holding `links` links
/// ([`size_router_runtime`]) if this process still runs a single thread and Zenoh's
/// runtimes were not configured by the user; returns whether this process set the variable,
/// now or for an earlier router (then it is this process's own, not its children's: see
/// [`RUNTIME_VARIABLE`]). A process that already
/// runs other threads (a program embedding the library) keeps Zenoh's two workers.
pub fn size_router_runtime_if_alone(links: usize) -> bool {
    use std::sync::atomic::{AtomicBool, Ordering};
    /// This process set the variable (for its first router; Zenoh reads it once).
    static SET_HERE: AtomicBool = AtomicBool::new(false);
    if SET_HERE.load(Ordering::Acquire) {
        return true;
    }
    if std::env::var_os(RUNTIME_VARIABLE).is_some() || !single_threaded() {
        return false;
    }
    // SAFETY: this process runs one thread (checked above), so nothing else reads or writes
    // the environment meanwhile.
    unsafe { size_router_runtime(links) };
    SET_HERE.store(true, Ordering::Release);
    true
}

/// Zenoh's runtime configuration variable: a process that set it for its own router removes
/// it from the agents it starts (each agent is one client with one link; sized for a router,
/// every agent would start a receive worker per link of the team).
pub const RUNTIME_VARIABLE: &str = "ZENOH_RUNTIME";

/// How long closing a session is waited for: what is queued is flushed and the others are
/// told within it; a link to a host that was cut off is not waited for (Zenoh's own close
/// can take 10 s and more then, and a host must not outlive its team by that much).
pub const CLOSE_WITHIN: Duration = Duration::from_secs(2);

/// Closes `session`, waiting at most [`CLOSE_WITHIN`] (the rest of the close goes on in the
/// background until the process exits).
pub fn close(session: &Session) {
    let session = session.clone();
    let (done, closed) = std::sync::mpsc::channel();
    let closing = std::thread::Builder::new()
        .name("zenoh-close".into())
        .spawn(move || {
            let _ = session.close().wait();
            let _ = done.send(());
        });
    if closing.is_ok() {
        let _ = closed.recv_timeout(CLOSE_WITHIN);
    }
}

/// Opens a session of `role`.
pub fn open(role: &Role, listen: &[String], connect: &[String]) -> Result<Session, ZenohError> {
    let config = config(role, listen, connect)?;
    zenoh::open(config).wait().map_err(|e| {
        ZenohError::new(
            format!("cannot open a Zenoh session (listen {listen:?}, connect {connect:?})"),
            e,
        )
    })
}

/// The keys below `key` with a liveliness token on the network now.
///
/// The replies go to an unbounded channel: Zenoh answers the tokens it knows inside the
/// query's `wait`, on the asking thread, and its default handler (a channel of 256) blocked
/// that thread for good once a standing team of 200 robots held more tokens than that.
pub fn alive_keys(session: &Session, key: String) -> Result<Vec<String>, ZenohError> {
    let (sender, replies) = std::sync::mpsc::channel();
    let deliver = move |reply: zenoh::query::Reply| {
        // The receiver outlives the query; a send can only fail once it is gone.
        let _ = sender.send(reply);
    };
    session
        .liveliness()
        .get(&key)
        .timeout(Duration::from_secs(1))
        .with((deliver, ()))
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
pub fn missing_hosts(
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
pub fn alive_agents(
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
pub fn announce_failure(
    session: &Session,
    links: &crate::zenoh_net::links::ZenohLinks,
    failed: usize,
) {
    put_failure(
        session,
        links,
        failed.to_string(),
        zenoh::qos::CongestionControl::Block,
    );
}

/// Announces agent `failed` as failed because its host `lost` left the team without a
/// goodbye (as `N lost HOST`: agents read the agent, hosts also the host; `None`: as a
/// plain `N`). Never blocks: dropped where a link's queue is full (the announcement is
/// repeated many times, and a blocking put to a link that was just cut can hold the caller
/// for Zenoh's `wait_before_close`).
pub fn announce_lost_host(
    session: &Session,
    links: &crate::zenoh_net::links::ZenohLinks,
    failed: usize,
    lost: Option<&str>,
) {
    let text = match lost {
        Some(host) => format!("{failed} lost {host}"),
        None => failed.to_string(),
    };
    put_failure(session, links, text, zenoh::qos::CongestionControl::Drop);
}

fn put_failure(
    session: &Session,
    links: &crate::zenoh_net::links::ZenohLinks,
    text: String,
    congestion: zenoh::qos::CongestionControl,
) {
    let _ = session
        .put(links.failure_key(), text)
        .congestion_control(congestion)
        .wait();
}

/// What a failure announcement says: the agent, and the lost host it belonged to if the
/// announcement is a host's for a lost host (`None` for a stop request or a malformed text).
fn parse_failure(text: &str) -> Option<(usize, Option<&str>)> {
    let mut words = text.split_whitespace();
    let failed = words.next()?.parse().ok()?;
    match (words.next(), words.next(), words.next()) {
        (None, _, _) => Some((failed, None)),
        (Some("lost"), Some(host), None) => Some((failed, Some(host))),
        _ => None,
    }
}

/// Asks every agent and host of the run of `links` to stop: termination signal `signal`
/// (on the failure key, as `stop N`: [`watch_failures`] ignores it, [`watch_stops`] sees it).
pub fn announce_stop(session: &Session, links: &crate::zenoh_net::links::ZenohLinks, signal: i32) {
    let _ = session
        .put(links.stop_key(), format!("stop {signal}"))
        .congestion_control(zenoh::qos::CongestionControl::Block)
        .wait();
}

/// Calls `on_stop` with the signal of every stop request announced on the run of `links`.
pub fn watch_stops(
    session: &Session,
    links: &crate::zenoh_net::links::ZenohLinks,
    on_stop: impl Fn(i32) + Send + Sync + 'static,
) -> Result<zenoh::pubsub::Subscriber<()>, ZenohError> {
    session
        .declare_subscriber(links.stop_key())
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

/// Calls `on_failure` with every agent announced as failed on the run of `links`, and the
/// host it belonged to when a host announced it for a host lost.
pub fn watch_failures(
    session: &Session,
    links: &crate::zenoh_net::links::ZenohLinks,
    on_failure: impl Fn(usize, Option<&str>) + Send + Sync + 'static,
) -> Result<zenoh::pubsub::Subscriber<()>, ZenohError> {
    session
        .declare_subscriber(links.failure_key())
        .callback(move |sample| {
            let text = String::from_utf8_lossy(&sample.payload().to_bytes()).into_owned();
            if let Some((failed, lost)) = parse_failure(&text) {
                on_failure(failed, lost);
            }
        })
        .wait()
        .map_err(|e| ZenohError::new("cannot watch the run's failure announcements", e))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// More tokens than Zenoh's default reply channel holds (256): the query answers every
    /// one, where it used to block its own thread for good (a standing team of 200 robots).
    #[test]
    fn a_liveliness_query_answers_more_tokens_than_a_default_channel_holds() {
        let session = open(&Role::Router, &[], &[]).unwrap();
        let prefix = format!("admm-ta-test/{}/alive", std::process::id());
        let _tokens: Vec<_> = (0..300)
            .map(|k| {
                session
                    .liveliness()
                    .declare_token(format!("{prefix}/{k}"))
                    .wait()
                    .unwrap()
            })
            .collect();
        let (done, keys) = std::sync::mpsc::channel();
        let asking = session.clone();
        std::thread::spawn(move || {
            let _ = done.send(alive_keys(&asking, format!("{prefix}/*")));
        });
        match keys.recv_timeout(Duration::from_secs(30)) {
            Ok(keys) => assert_eq!(keys.unwrap().len(), 300),
            Err(_) => {
                // Dropping them would wait for the blocked query's lock.
                std::mem::forget((_tokens, session));
                panic!("the liveliness query blocked its thread");
            }
        }
    }

    #[test]
    fn failure_announcements() {
        assert_eq!(parse_failure("12"), Some((12, None)));
        assert_eq!(parse_failure(" 12\n"), Some((12, None)));
        assert_eq!(parse_failure("12 lost h3"), Some((12, Some("h3"))));
        for other in [
            "stop 15",
            "",
            "x",
            "12 lost",
            "12 gone h3",
            "12 lost h3 extra",
        ] {
            assert_eq!(parse_failure(other), None, "{other:?}");
        }
    }
}
