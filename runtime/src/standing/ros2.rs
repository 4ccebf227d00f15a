//! `admm-ta agent --team FILE --robot I --ros2` (feature `ros2`): the sidecar protocol
//! ([`crate::standing::serve`]) over ROS 2 topics, for robots whose programs are ROS 2 nodes.
//!
//! The member is a ROS 2 node named `admm_ta` in the robot's namespace (`/robotI`, or
//! `/<name>` when the team's cost file names its robots, or the one given), with two private
//! topics of type `std_msgs/String`, each message one JSON line of the sidecar protocol:
//!
//! * `~/costs` (`/robot3/admm_ta/costs`), in: the rows (`{"costs": [...]}`,
//!   `{"available": false}`, `{"leave": true}`); QoS reliable, volatile, so any default
//!   rclpy or rclcpp publisher matches;
//! * `~/assignment` (`/robot3/admm_ta/assignment`), out: the answers and errors; QoS
//!   reliable, transient local, keep last 1, so a subscriber that comes late still gets the
//!   latest answer, and a default subscriber matches too.
//!
//! The node's read-only parameters say who it is: `robot` (its number), `robots` and `tasks`
//! (the team file's), `team_file`.
//!
//! The ROS 2 side is `ros2-client` over RustDDS (pure Rust; no ROS installation to build or
//! run). As ROS 2 does, it reads `ROS_DOMAIN_ID` (0 by default) and keeps discovery on this
//! machine with `ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST` (or `ROS_LOCALHOST_ONLY=1`).
//!
//! A robot program publishes its first row once the member's subscription matched its
//! publisher (`publisher.get_subscription_count() > 0` in rclpy): a volatile row published
//! before is lost, as on any ROS 2 topic.

use crate::process::member_error::MemberError;
use crate::standing::member::TeamMember;
use crate::standing::serve::{Input, Lines, ServeEnd, serve_from, tell_failure};
use crate::team::team_file::Team;
use ros2_client::dds::rustdds::DomainParticipantBuilder;
use ros2_client::dds::rustdds::mio1::{Events, Interest, Poll, Token};
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{
    Context, MessageTypeName, Name, Node, NodeName, NodeOptions, ParameterValue, Publisher,
    QosProfile, Subscription,
};
use std::collections::VecDeque;
use std::io::Write;
use std::path::Path;
use std::sync::mpsc::RecvTimeoutError;
use std::time::{Duration, Instant};

/// The node's name, in the robot's namespace.
pub const NODE_NAME: &str = "admm_ta";

/// Rows a robot program may publish ahead of the team (the rows' history).
const ROWS_DEPTH: usize = 64;

/// How long a publish may wait for room in the history.
const DELIVERY: Duration = Duration::from_secs(1);

/// How long the process stays for its last answer to be taken.
const LINGER: Duration = Duration::from_millis(250);

/// How far apart the members of a team launched together start their DDS participants.
///
/// Measured here (8 members started within a few milliseconds of each other while rclpy's
/// Fast DDS participant was up): Fast DDS never matched the endpoints of 1 to 5 of the 8
/// (it took their participants, but not the announcements of their topics, and RustDDS did
/// not send them again) in about half the launches with SUBNET discovery and one in eight
/// with LOCALHOST. Started 80 ms apart and without same-host loopback (see
/// [`participant`]), all were matched in 20 launches of 20 (SUBNET) and 12 of 12
/// (LOCALHOST); 30 ms apart still missed one member in 10 SUBNET launches.
const DDS_STAGGER: Duration = Duration::from_millis(80);

/// Robots `0..STAGGER_SLOTS` start `DDS_STAGGER` apart; robot `i` takes slot `i % STAGGER_SLOTS`,
/// so none waits more than about 5 s whatever the team's size.
const STAGGER_SLOTS: usize = 64;

/// What keeps a ROS 2 member from starting.
#[derive(Debug, thiserror::Error)]
pub enum Ros2Error {
    #[error(
        "--ros2-namespace {0:?}: a ROS 2 namespace is `/` and names of letters, digits and \
         underscores (not starting with a digit), separated by single slashes"
    )]
    Namespace(String),
    #[error(
        "robot {id} is named {name:?} in the team's cost file, which is no ROS 2 name: \
         give a namespace with --ros2-namespace"
    )]
    RobotName { id: usize, name: String },
    #[error("ROS_DOMAIN_ID={0:?}: a domain id is a number from 0 to 232")]
    DomainId(String),
    #[error(
        "ROS_AUTOMATIC_DISCOVERY_RANGE={0:?}: expected SUBNET, LOCALHOST, OFF or SYSTEM_DEFAULT"
    )]
    DiscoveryRange(String),
    #[error("the ROS 2 node {what}: {why}")]
    Node { what: &'static str, why: String },
}

impl Ros2Error {
    fn node(what: &'static str, why: impl std::fmt::Debug) -> Self {
        Self::Node {
            what,
            why: format!("{why:?}"),
        }
    }
}

/// Whether `name` is a ROS 2 name token: letters, digits, underscores, no leading digit.
fn is_token(name: &str) -> bool {
    let mut chars = name.chars();
    chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// The namespace given (made absolute), or the robot's: `/robotI`, or `/<name>` when the
/// team's cost file names its robots.
pub fn namespace(team: &Team, id: usize, given: Option<&str>) -> Result<String, Ros2Error> {
    if let Some(given) = given {
        let absolute = format!("/{}", given.trim_start_matches('/'));
        let tokens = absolute.trim_start_matches('/');
        return if absolute == "/" || tokens.split('/').all(is_token) {
            Ok(absolute)
        } else {
            Err(Ros2Error::Namespace(given.to_string()))
        };
    }
    let named = team.robot_names().ok().flatten();
    match named.as_ref().and_then(|names| names.get(id)) {
        Some(name) if is_token(name) => Ok(format!("/{name}")),
        Some(name) => Err(Ros2Error::RobotName {
            id,
            name: name.clone(),
        }),
        None => Ok(format!("/robot{id}")),
    }
}

/// The DDS domain and the networks discovery may use, from ROS 2's environment variables.
fn participant() -> Result<DomainParticipantBuilder, Ros2Error> {
    let domain = match std::env::var("ROS_DOMAIN_ID") {
        Ok(text) if text.trim().is_empty() => 0,
        Ok(text) => text
            .trim()
            .parse::<u16>()
            .ok()
            .filter(|&d| d <= 232)
            .ok_or(Ros2Error::DomainId(text))?,
        Err(_) => 0,
    };
    let range = std::env::var("ROS_AUTOMATIC_DISCOVERY_RANGE").unwrap_or_default();
    let legacy_localhost = std::env::var("ROS_LOCALHOST_ONLY").is_ok_and(|v| v.trim() == "1");
    let localhost = match range.trim() {
        "LOCALHOST" | "OFF" => true,
        "" | "SYSTEM_DEFAULT" => legacy_localhost,
        "SUBNET" => false,
        _ => return Err(Ros2Error::DiscoveryRange(range)),
    };
    // RustDDS's same-host loopback (announcing to 127.0.0.1's well-known ports, preferring
    // loopback routes) lets the members of a team find each other, which they do not need,
    // and with it Fast DDS missed some members launched together (see [`DDS_STAGGER`]).
    // Without it a member still answers the robots' nodes that announce themselves to it
    // (with LOCALHOST, Fast DDS announces to the first 32 ports on 127.0.0.1), and with
    // SUBNET it announces itself by multicast. It stays on where no interface but loopback
    // can carry multicast, or the interfaces cannot be listed.
    let builder = DomainParticipantBuilder::new(domain).same_host_loopback(!has_network());
    Ok(if localhost {
        builder.with_only_networks([std::net::Ipv4Addr::LOCALHOST])
    } else {
        builder
    })
}

/// Whether an interface other than loopback is up, running, takes multicast and has an
/// IPv4 address.
fn has_network() -> bool {
    let mut list: *mut libc::ifaddrs = std::ptr::null_mut();
    // SAFETY: getifaddrs fills `list` with a list this function frees below.
    if unsafe { libc::getifaddrs(&mut list) } != 0 || list.is_null() {
        return false;
    }
    let mut found = false;
    let mut entry = list;
    while !entry.is_null() && !found {
        // SAFETY: `entry` is a node of the list getifaddrs returned, not yet freed.
        let ifa = unsafe { &*entry };
        let flags = ifa.ifa_flags;
        let has = |flag: libc::c_int| flags & flag as libc::c_uint != 0;
        let up = has(libc::IFF_UP) && has(libc::IFF_RUNNING) && has(libc::IFF_MULTICAST);
        let loopback = has(libc::IFF_LOOPBACK);
        // SAFETY: a non-null ifa_addr points to a sockaddr whose family field is readable.
        let ipv4 = !ifa.ifa_addr.is_null()
            && i32::from(unsafe { (*ifa.ifa_addr).sa_family }) == libc::AF_INET;
        found = up && !loopback && ipv4;
        entry = ifa.ifa_next;
    }
    // SAFETY: `list` came from getifaddrs and is freed once.
    unsafe { libc::freeifaddrs(list) };
    found
}

/// Runs `build` with the termination signals blocked in this thread, so that the threads it
/// starts (DDS's event loops) never take one: a signal that interrupts their `poll` would
/// end them. This thread's mask comes back afterwards.
fn with_signals_blocked<T>(build: impl FnOnce() -> T) -> T {
    struct Restore(libc::sigset_t);
    impl Drop for Restore {
        fn drop(&mut self) {
            // SAFETY: the mask saved below; only this thread's mask changes.
            unsafe { libc::pthread_sigmask(libc::SIG_SETMASK, &self.0, std::ptr::null_mut()) };
        }
    }
    // SAFETY: the sets are initialised by sigemptyset before use; pthread_sigmask only
    // changes this thread's mask, and the guard restores the old one (on a panic too).
    let _restore = unsafe {
        let mut blocked: libc::sigset_t = std::mem::zeroed();
        let mut old: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut blocked);
        for signal in admm_ta_transport::signals::TERMINATION {
            libc::sigaddset(&mut blocked, signal);
        }
        libc::pthread_sigmask(libc::SIG_BLOCK, &blocked, &mut old);
        Restore(old)
    };
    build()
}

/// The member's node and its two topics.
struct Face {
    node: Node,
    rows: Subscription<String>,
    answers: Publisher<String>,
}

/// The node `admm_ta` in `namespace`, its parameters, and its topics.
fn face(namespace: &str, parameters: Vec<(&str, ParameterValue)>) -> Result<Face, Ros2Error> {
    let participant = participant()?
        .build()
        .map_err(|e| Ros2Error::node("could not join DDS", e))?;
    let context = Context::from_domain_participant(participant)
        .map_err(|e| Ros2Error::node("could not start", e))?;
    let declared: Vec<(String, ParameterValue)> = parameters
        .iter()
        .map(|(name, value)| ((*name).to_string(), value.clone()))
        .collect();
    // Read-only: a set to the value it has is allowed (the declaration is one).
    let read_only = move |name: &str, value: &ParameterValue| match declared
        .iter()
        .find(|(declared, _)| declared == name)
    {
        Some((_, was)) if was == value => Ok(()),
        _ => Err(format!("{name} is read-only: it comes from the team file")),
    };
    let options = parameters.into_iter().fold(
        NodeOptions::new()
            .enable_rosout(true)
            .parameter_validator(Box::new(read_only)),
        |options, (name, value)| options.declare_parameter(name, value),
    );
    let name =
        NodeName::new(namespace, NODE_NAME).map_err(|e| Ros2Error::node("has no valid name", e))?;
    let mut node = context
        .new_node(name, options)
        .map_err(|e| Ros2Error::node("could not start", e))?;
    let private = format!("{}/{NODE_NAME}", namespace.trim_end_matches('/'));
    let topic = |base: &str, qos: &QosProfile| {
        let name = Name::new(&private, base).map_err(|e| Ros2Error::node("topic name", e))?;
        node.create_topic(&name, MessageTypeName::new("std_msgs", "String"), qos)
            .map_err(|e| Ros2Error::node("could not make a topic", e))
    };
    let rows_qos = QosProfile::subscription_default()
        .reliability_reliable(WhenFull::Wait(DELIVERY))
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: ROWS_DEPTH });
    let answers_qos = QosProfile::publisher_default()
        .reliability_reliable(WhenFull::Wait(DELIVERY))
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth: 1 });
    let rows_topic = topic("costs", &rows_qos)?;
    let answers_topic = topic("assignment", &answers_qos)?;
    let rows = node
        .create_subscription::<String>(&rows_topic, Some(rows_qos))
        .map_err(|e| Ros2Error::node("could not subscribe to its rows", e))?;
    let answers = node
        .create_publisher::<String>(&answers_topic, Some(answers_qos))
        .map_err(|e| Ros2Error::node("could not publish its answers", e))?;
    Ok(Face {
        node,
        rows,
        answers,
    })
}

/// The rows' topic as the robot program's lines, taken in the serving thread itself (no
/// thread between DDS and the team: one wake-up less per row).
struct TopicRows {
    rows: Subscription<String>,
    poll: Poll,
    events: Events,
    /// Messages taken and not yet served (the poll is edge-triggered: a wake-up takes all).
    taken: VecDeque<Input>,
}

impl TopicRows {
    fn new(rows: Subscription<String>) -> Result<Self, Ros2Error> {
        let mut rows = rows;
        let poll = Poll::new().map_err(|e| Ros2Error::node("has no poll for its rows", e))?;
        poll.registry()
            .register(&mut rows, Token(0), Interest::READABLE)
            .map_err(|e| Ros2Error::node("cannot wait for its rows", e))?;
        Ok(Self {
            rows,
            poll,
            events: Events::with_capacity(4),
            taken: VecDeque::new(),
        })
    }

    fn take_all(&mut self) {
        loop {
            match self.rows.take() {
                Ok(Some((line, _))) => self.taken.push_back(Input::Line(line)),
                Ok(None) => return,
                Err(e) => self.taken.push_back(Input::Bad(format!(
                    "an unreadable message on the rows' topic: {e:?}"
                ))),
            }
        }
    }
}

impl Lines for TopicRows {
    fn next_line(&mut self, timeout: Duration) -> Result<Input, RecvTimeoutError> {
        if self.taken.is_empty() {
            self.take_all();
        }
        if self.taken.is_empty() {
            // An interrupted poll (a signal) is a timeout: the caller looks at the team.
            let _ = self.poll.poll(&mut self.events, Some(timeout));
            self.take_all();
        }
        self.taken.pop_front().ok_or(RecvTimeoutError::Timeout)
    }
}

/// The sidecar's output as messages: each line written (without its newline) goes to
/// `publish`.
struct LineMessages<P: FnMut(String) -> std::io::Result<()>> {
    publish: P,
    line: Vec<u8>,
}

impl<P: FnMut(String) -> std::io::Result<()>> Write for LineMessages<P> {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        for part in bytes.split_inclusive(|&b| b == b'\n') {
            self.line.extend_from_slice(part);
            if self.line.ends_with(b"\n") {
                self.line.pop();
                let text = String::from_utf8_lossy(&self.line).into_owned();
                self.line.clear();
                (self.publish)(text)?;
            }
        }
        Ok(bytes.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Serves robot `id` of the private team in `team_path` to the ROS 2 node(s) publishing its
/// rows and reading its answers under `namespace` (see [`namespace`]), until a `{"leave":
/// true}` row (the robot leaves), the team goes on without it, or the team fails. The last
/// answer or error stays on the answers' topic until this process ends.
pub fn serve_ros2(
    team_path: &Path,
    id: usize,
    namespace: Option<&str>,
) -> Result<ServeEnd, MemberError> {
    let _signals = admm_ta_transport::signals::install();
    let team = Team::read(team_path).map_err(MemberError::refused)?;
    let namespace = self::namespace(&team, id, namespace).map_err(MemberError::refused)?;
    let count = |n: usize| ParameterValue::Integer(i64::try_from(n).unwrap_or(i64::MAX));
    let parameters = vec![
        ("robot", count(id)),
        ("robots", count(team.file.robots)),
        ("tasks", count(team.file.tasks.unwrap_or(team.file.robots))),
        (
            "team_file",
            ParameterValue::String(team_path.display().to_string()),
        ),
    ];
    wait_for_slot(id);
    let (mut lines, answers, node) = with_signals_blocked(|| {
        let Face {
            mut node,
            rows,
            answers,
        } = face(&namespace, parameters)?;
        let lines = TopicRows::new(rows)?;
        let spinner = node
            .spinner()
            .map_err(|e| Ros2Error::node("has no spinner", e))?;
        std::thread::Builder::new()
            .name("ros2-spin".into())
            .spawn(move || {
                let _ = futures::executor::block_on(spinner.spin());
            })
            .map_err(|e| Ros2Error::node("could not start a thread", e))?;
        Ok::<_, Ros2Error>((lines, answers, node))
    })
    .map_err(|e| match e {
        // DDS or the system failed it; the rest is the user's to change.
        Ros2Error::Node { .. } => MemberError::failed(e),
        _ => MemberError::refused(e),
    })?;
    let mut output = LineMessages {
        publish: |text| {
            answers
                .publish(text)
                .map_err(|e| std::io::Error::other(format!("{e:?}")))
        },
        line: Vec::new(),
    };
    tracing::info!(%namespace, node = NODE_NAME, "ROS 2 node up: joining the team");
    // A member that cannot join says why on the answers' topic too (the robot program
    // reads no standard error).
    let served = TeamMember::join(team_path, id)
        .inspect_err(|e| {
            // The robot's node may not have matched yet (the join can fail fast).
            let deadline = Instant::now() + DELIVERY;
            while answers.get_subscription_count(&node) == 0 && Instant::now() < deadline {
                std::thread::sleep(Duration::from_millis(20));
            }
            tell_failure(&mut output, 0, id, e);
        })
        .and_then(|mut member| serve_from(&mut member, &mut lines, &mut output));
    drop(output);
    linger(&node, &answers);
    served
}

/// Waits for this robot's turn to start its DDS participant (see [`DDS_STAGGER`]), or
/// until a termination signal comes.
fn wait_for_slot(id: usize) {
    let slot = u32::try_from(id % STAGGER_SLOTS).unwrap_or(0);
    let start = Instant::now() + DDS_STAGGER * slot;
    while Instant::now() < start && admm_ta_transport::signals::stop_requested().is_none() {
        std::thread::sleep(
            Duration::from_millis(5).min(start.saturating_duration_since(Instant::now())),
        );
    }
}

/// Gives the subscribers of the answers' topic a moment to take the last answer (or error)
/// before the process ends: `ros2-client` does not say when they acknowledged it, and on
/// one machine a reliable message arrives in a millisecond or, lost, is sent again within
/// a few heartbeats.
fn linger(node: &Node, answers: &Publisher<String>) {
    if answers.get_subscription_count(node) > 0 {
        std::thread::sleep(LINGER);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_checked() {
        assert!(is_token("robot3"));
        assert!(is_token("_uav"));
        assert!(!is_token("3robot"));
        assert!(!is_token("uav-3"));
        assert!(!is_token(""));
    }

    #[test]
    fn each_line_written_is_one_message() {
        let mut sent = Vec::new();
        {
            let mut out = LineMessages {
                publish: |text| {
                    sent.push(text);
                    Ok(())
                },
                line: Vec::new(),
            };
            write!(out, "{{\"a\":").unwrap();
            writeln!(out, "1}}").unwrap();
            out.write_all(b"x\ny\n\nz").unwrap();
        }
        assert_eq!(sent, ["{\"a\":1}", "x", "y", ""]);
    }
}
