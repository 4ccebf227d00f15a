//! A standing team's plane across machines ([`crate::standing::plane::TeamPlane`]) as Zenoh
//! liveliness tokens, through the robot's host router: a robot in the team holds
//! `<team>/alive/<i>` (the token the hosts count, as an agent's), a robot asking to join
//! `<team>/joining/<i>`, a robot in (or forming) a roster `<team>/rosters/in/<name>/<bitmap>/<i>`
//! and, once the roster synced, `<team>/rosters/formed/<name>/<bitmap>/<i>`. A token
//! vanishes when its robot withdraws it, when its process dies (its session closes), or
//! when its host is cut off (after Zenoh's lease): so a robot gone here may be alive on the
//! other side of a cut ([`TeamPlane::exact`] is `false`).

#[cfg(not(feature = "zenoh"))]
pub(crate) fn open(
    _team: &crate::team::team_file::Team,
    _scenario: &crate::process::scenario::Scenario,
    _id: usize,
    _deadline: std::time::Instant,
) -> Result<Box<dyn crate::standing::plane::TeamPlane>, crate::process::member_error::MemberError> {
    Err(crate::process::member_error::MemberError::refused(
        admm_ta_transport::zenoh_net::error::ZenohNotBuilt,
    ))
}

#[cfg(feature = "zenoh")]
pub(crate) use built::open;

#[cfg(feature = "zenoh")]
mod built {
    use crate::process::member_error::MemberError;
    use crate::process::scenario::Scenario;
    use crate::process::team_digest::TeamDigest;
    use crate::standing::plane::TeamPlane;
    use crate::standing::roster::{EpochId, Roster};
    use crate::team::team_file::Team;
    use admm_ta_transport::exchange::ExchangeError;
    use admm_ta_transport::zenoh_net::error::ZenohError;
    use admm_ta_transport::zenoh_net::links::ZenohLinks;
    use admm_ta_transport::zenoh_net::session::{self, Role, alive_keys, missing_hosts};
    use std::collections::{BTreeMap, BTreeSet};
    use std::sync::{Arc, Mutex, MutexGuard};
    use std::time::{Duration, Instant};
    use zenoh::liveliness::LivelinessToken;
    use zenoh::sample::{Sample, SampleKind};
    use zenoh::{Session, Wait};

    /// How often a robot asks the network for the plane's tokens (a liveliness subscriber
    /// can miss tokens declared while its own declaration propagates).
    const REFRESH_EVERY: Duration = Duration::from_millis(500);

    /// What the plane's tokens say, kept up to date by Zenoh's callbacks.
    #[derive(Default)]
    struct Tokens {
        /// Every token's key present now, and when each key was last withdrawn.
        present: BTreeSet<String>,
        withdrawn: BTreeMap<String, Instant>,
        stop: Option<i32>,
        /// When the network was last asked.
        refreshed: Option<Instant>,
    }

    /// A standing team's plane on Zenoh (see the module).
    struct ZenohPlane {
        id: usize,
        robots: usize,
        links: ZenohLinks,
        tokens: Arc<Mutex<Tokens>>,
        member: Mutex<Option<LivelinessToken>>,
        joining: Mutex<Option<LivelinessToken>>,
        /// This robot's roster tokens, by key.
        rosters: Mutex<BTreeMap<String, LivelinessToken>>,
        _subscribers: Vec<zenoh::pubsub::Subscriber<()>>,
        session: Option<Session>,
    }

    fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
        m.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Robot `id`'s plane of the private team in `team` whose scenario (this robot's, on its
    /// host) is `scenario`: a Zenoh session to its host's router, once every host is up and
    /// the running team's file is this one's.
    pub(crate) fn open(
        team: &Team,
        scenario: &Scenario,
        id: usize,
        deadline: Instant,
    ) -> Result<Box<dyn TeamPlane>, MemberError> {
        let host = team
            .host_of(id)
            .ok_or_else(|| MemberError::refused(ZenohError::new("robot's host", "none")))?;
        let links = ZenohLinks {
            hosts: vec![host.name.clone()],
            ..team.zenoh_links(host)
        };
        let within = deadline.saturating_duration_since(Instant::now());
        let session = session::open(&Role::Agent { within }, &[], &links.connect)
            .map_err(MemberError::failed)?;
        await_hosts(&session, &links, id, deadline)?;
        let digest = TeamDigest::of(scenario).to_hex();
        let running = alive_keys(&session, links.digest_all())
            .map_err(MemberError::failed)?
            .iter()
            .filter_map(|k| links.of_digest_key(k))
            .min_by(|a, b| (a.1, &a.2).cmp(&(b.1, &b.2)))
            .map(|(hex, _, _)| hex);
        if let Some(running) = running.filter(|r| *r != digest) {
            return Err(MemberError::refused(ExchangeError::OtherTeam {
                agent: id,
                running,
            }));
        }
        let tokens = Arc::new(Mutex::new(Tokens::default()));
        let subscribers = watch(&session, &links, &tokens).map_err(MemberError::failed)?;
        let plane = ZenohPlane {
            id,
            robots: team.file.robots,
            links,
            tokens,
            member: Mutex::new(None),
            joining: Mutex::new(None),
            rosters: Mutex::new(BTreeMap::new()),
            _subscribers: subscribers,
            session: Some(session),
        };
        plane.refresh();
        let present = plane.present();
        if present.contains(&plane.links.alive_key(id))
            || present.contains(&plane.links.joining_key(id))
        {
            return Err(MemberError::refused(
                crate::team::errors::JoinError::AlreadyOnTheNetwork { slot: id },
            ));
        }
        Ok(Box::new(plane))
    }

    /// Waits for robot `id`'s host (its token), until `deadline`. (A roster waits for the
    /// hosts of its robots when it forms: the team's first for every host; a robot that
    /// joins a running team does not wait for a host lost meanwhile.)
    fn await_hosts(
        session: &Session,
        links: &ZenohLinks,
        id: usize,
        deadline: Instant,
    ) -> Result<(), MemberError> {
        loop {
            let missing = missing_hosts(session, links).map_err(MemberError::failed)?;
            if missing.is_empty() {
                return Ok(());
            }
            if let Some(signal) = admm_ta_transport::signals::received() {
                return Err(MemberError::failed(ExchangeError::Stopped {
                    agent: id,
                    signal,
                }));
            }
            if Instant::now() >= deadline {
                return Err(MemberError::failed(ZenohError::new(
                    format!(
                        "the team's host(s) {missing:?} did not come up before the start-up deadline"
                    ),
                    "start `admm-ta host --team FILE --name NAME` on each machine",
                )));
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Keeps `tokens` up to date with the plane's tokens and the team's stop requests.
    fn watch(
        session: &Session,
        links: &ZenohLinks,
        tokens: &Arc<Mutex<Tokens>>,
    ) -> Result<Vec<zenoh::pubsub::Subscriber<()>>, ZenohError> {
        let mut subscribers = Vec::new();
        for key in [links.alive_all(), links.joining_all(), links.epoch_all()] {
            let tokens = Arc::clone(tokens);
            subscribers.push(
                session
                    .liveliness()
                    .declare_subscriber(&key)
                    .history(true)
                    .callback(move |sample: Sample| {
                        let key = sample.key_expr().as_str().to_string();
                        let mut t = lock(&tokens);
                        match sample.kind() {
                            SampleKind::Put => {
                                t.present.insert(key);
                            }
                            SampleKind::Delete => {
                                t.present.remove(&key);
                                t.withdrawn.insert(key, Instant::now());
                            }
                        }
                    })
                    .wait()
                    .map_err(|e| ZenohError::new(format!("cannot watch {key}"), e))?,
            );
        }
        let stops = Arc::clone(tokens);
        subscribers.push(session::watch_stops(session, links, move |signal| {
            lock(&stops).stop.get_or_insert(signal);
        })?);
        Ok(subscribers)
    }

    impl ZenohPlane {
        /// The session (`None` once the robot left the team).
        fn session(&self) -> Option<&Session> {
            self.session.as_ref()
        }

        /// Asks the network for the plane's tokens (at most every [`REFRESH_EVERY`]): the
        /// tokens a subscriber missed are added; none withdrawn since the question are.
        fn refresh(&self) {
            let asked = Instant::now();
            {
                let mut t = lock(&self.tokens);
                if t.refreshed.is_some_and(|r| r.elapsed() < REFRESH_EVERY) {
                    return;
                }
                t.refreshed = Some(asked);
            }
            let Some(session) = self.session() else {
                return;
            };
            let mut found = Vec::new();
            for key in [
                self.links.alive_all(),
                self.links.joining_all(),
                self.links.epoch_all(),
            ] {
                if let Ok(keys) = alive_keys(session, key) {
                    found.extend(keys);
                }
            }
            let mut t = lock(&self.tokens);
            for key in found {
                if t.withdrawn.get(&key).is_none_or(|&w| w < asked) {
                    t.present.insert(key);
                }
            }
            // Withdrawals older than the question matter no more.
            t.withdrawn.retain(|_, &mut w| w >= asked);
        }

        fn present(&self) -> BTreeSet<String> {
            self.refresh();
            lock(&self.tokens).present.clone()
        }

        fn members(&self) -> BTreeSet<usize> {
            self.present()
                .iter()
                .filter_map(|k| self.links.agent_of_alive_key(k))
                .collect()
        }

        /// Every roster key: formed or in, name, bitmap, robot.
        fn roster_keys(&self) -> Vec<(bool, String, String, usize)> {
            self.present()
                .iter()
                .filter_map(|k| self.links.of_epoch_key(k))
                .map(|(f, n, r, i)| (f, n.to_string(), r.to_string(), i))
                .collect()
        }

        fn declare(&self, key: String) -> Option<LivelinessToken> {
            let token = self.session()?.liveliness().declare_token(&key).wait().ok();
            if token.is_some() {
                lock(&self.tokens).present.insert(key);
            }
            token
        }

        /// Withdraws `token` (whose key is `key`).
        fn withdraw(&self, key: &str, token: LivelinessToken) {
            let _ = token.undeclare().wait();
            let mut t = lock(&self.tokens);
            t.present.remove(key);
            t.withdrawn.insert(key.to_string(), Instant::now());
        }

        fn roster_key(&self, formed: bool, epoch: &EpochId) -> String {
            self.links.epoch_key(
                formed,
                &epoch.name(),
                &epoch.roster.to_hex(self.robots),
                self.id,
            )
        }
    }

    impl TeamPlane for ZenohPlane {
        fn set_member(&self) {
            let mut member = lock(&self.member);
            if member.is_none() {
                *member = self.declare(self.links.alive_key(self.id));
            }
            if let Some(token) = lock(&self.joining).take() {
                self.withdraw(&self.links.joining_key(self.id), token);
            }
        }

        fn set_joining(&self) {
            let mut joining = lock(&self.joining);
            if joining.is_none() {
                *joining = self.declare(self.links.joining_key(self.id));
            }
            if let Some(token) = lock(&self.member).take() {
                self.withdraw(&self.links.alive_key(self.id), token);
            }
        }

        fn joiners(&self) -> Vec<usize> {
            let members = self.members();
            self.present()
                .iter()
                .filter_map(|k| self.links.robot_of_joining_key(k))
                .filter(|&j| j != self.id && j < self.robots && !members.contains(&j))
                .collect()
        }

        fn gone(&self, slots: &[usize]) -> Vec<usize> {
            let members = self.members();
            slots
                .iter()
                .copied()
                .filter(|s| *s != self.id && !members.contains(s))
                .collect()
        }

        fn absent(&self, slots: &[usize]) -> Vec<usize> {
            let present = self.present();
            let here = |s: usize| {
                present.contains(&self.links.alive_key(s))
                    || present.contains(&self.links.joining_key(s))
            };
            slots
                .iter()
                .copied()
                .filter(|&s| s != self.id && !here(s))
                .collect()
        }

        fn exact(&self) -> bool {
            false
        }

        fn enter_epoch(&self, epoch: &EpochId) {
            let key = self.roster_key(false, epoch);
            let mut rosters = lock(&self.rosters);
            if !rosters.contains_key(&key)
                && let Some(token) = self.declare(key.clone())
            {
                rosters.insert(key, token);
            }
        }

        fn leave_epoch(&self, epoch: &EpochId) {
            let mut rosters = lock(&self.rosters);
            for formed in [false, true] {
                let key = self.roster_key(formed, epoch);
                if let Some(token) = rosters.remove(&key) {
                    self.withdraw(&key, token);
                }
            }
        }

        fn in_epoch(&self, epoch: &EpochId) -> Vec<usize> {
            let name = epoch.name();
            let members = self.members();
            let robots: BTreeSet<usize> = self
                .roster_keys()
                .into_iter()
                .filter(|(formed, n, _, i)| !formed && *n == name && members.contains(i))
                .map(|(_, _, _, i)| i)
                .filter(|&i| epoch.roster.contains(i))
                .collect();
            robots.into_iter().collect()
        }

        fn set_formed(&self, epoch: &EpochId) {
            let key = self.roster_key(true, epoch);
            let mut rosters = lock(&self.rosters);
            if !rosters.contains_key(&key)
                && let Some(token) = self.declare(key.clone())
            {
                rosters.insert(key, token);
            }
        }

        fn formed(&self, epoch: &EpochId) -> bool {
            let name = epoch.name();
            self.roster_keys()
                .iter()
                .any(|(formed, n, _, _)| *formed && *n == name)
        }

        fn epochs(&self) -> Vec<EpochId> {
            let mut epochs: Vec<EpochId> = self
                .roster_keys()
                .into_iter()
                .filter_map(|(_, name, bitmap, _)| {
                    let number = EpochId::number_of(&name)?;
                    let roster = Roster::from_hex(&bitmap, self.robots)?;
                    let epoch = EpochId { number, roster };
                    (epoch.name() == name).then_some(epoch)
                })
                .collect();
            epochs.sort_by_key(|e| (e.number, e.name()));
            epochs.dedup();
            epochs
        }

        fn request_stop(&self, signal: i32, _by: usize) {
            if let Some(session) = self.session() {
                session::announce_stop(session, &self.links, signal);
            }
            lock(&self.tokens).stop.get_or_insert(signal);
        }

        fn stop_requested(&self) -> Option<i32> {
            lock(&self.tokens).stop
        }

        fn leave_team(&mut self) {
            let rosters = std::mem::take(&mut *lock(&self.rosters));
            for (key, token) in rosters {
                self.withdraw(&key, token);
            }
            for (key, slot) in [
                (self.links.alive_key(self.id), &self.member),
                (self.links.joining_key(self.id), &self.joining),
            ] {
                if let Some(token) = lock(slot).take() {
                    self.withdraw(&key, token);
                }
            }
            if let Some(session) = self.session.take() {
                session::close(&session);
            }
        }
    }

    impl Drop for ZenohPlane {
        fn drop(&mut self) {
            self.leave_team();
        }
    }
}
