//! A host's team identity: before its token, a host announces its team file's digest and
//! start time and waits for the other hosts' announcements; a host whose file differs from
//! that of a host that started earlier is refused by name.

use crate::process::member_error::MemberError;
use crate::process::team_digest::TeamDigest;
use crate::team::errors::HostError;
use crate::team::membership::team_scenario;
use crate::team::team_file::Team;
use admm_ta_transport::zenoh_net::error::ZenohError;
use admm_ta_transport::zenoh_net::links::ZenohLinks;
use admm_ta_transport::zenoh_net::session::alive_keys;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
use zenoh::Wait;

/// How often a host asks for the other hosts' team-digest tokens while it waits for them.
const DIGEST_POLL: Duration = Duration::from_millis(100);

/// Declares host `name`'s team-digest token and waits (until `deadline`, or a termination
/// signal) for every other host's; refuses this host if a host that started earlier runs a
/// team file that differs (the running team is the earlier one's, as on an `ipc` board the
/// first member's). Returns the token, to hold while the host runs.
pub(crate) fn check_team_digest(
    team: &Team,
    name: &str,
    links: &ZenohLinks,
    session: &zenoh::Session,
    deadline: Instant,
) -> Result<zenoh::liveliness::LivelinessToken, MemberError> {
    let digest = TeamDigest::of(&team_scenario(team).map_err(MemberError::refused)?);
    let started_ms = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64);
    let token = session
        .liveliness()
        .declare_token(links.digest_key(&digest.to_hex(), started_ms, name))
        .wait()
        .map_err(|e| {
            MemberError::failed(ZenohError::new(
                "cannot declare the host's team-digest token",
                e,
            ))
        })?;
    let others = team.file.hosts.len().saturating_sub(1);
    loop {
        let mut seen: Vec<(String, u64, String)> = alive_keys(session, links.digest_all())
            .map_err(MemberError::failed)?
            .iter()
            .filter_map(|k| links.of_digest_key(k))
            .filter(|(_, _, host)| host != name)
            .collect();
        seen.sort_by(|a, b| (a.1, &a.2).cmp(&(b.1, &b.2)));
        seen.dedup_by(|a, b| a.2 == b.2);
        let earlier_differing = seen.iter().find(|(hex, ms, host)| {
            hex != &digest.to_hex() && (*ms, host.as_str()) < (started_ms, name)
        });
        if let Some((hex, _, _)) = earlier_differing {
            let running = TeamDigest::from_hex(hex)
                .ok_or_else(|| MemberError::failed(HostError::MalformedDigest(hex.clone())))?;
            digest
                .compare(&running, &format!("host {name}"))
                .map_err(MemberError::refused)?;
        }
        if seen.len() >= others || Instant::now() >= deadline {
            return Ok(token);
        }
        if admm_ta_transport::signals::received().is_some() {
            // The main loop reports the stop.
            return Ok(token);
        }
        std::thread::sleep(DIGEST_POLL);
    }
}
