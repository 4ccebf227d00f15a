//! The dual methods in standing teams: each robot's own row feeds its own x-update, the
//! team's messages carry prices and a certificate (`2m + ⌈m/k⌉` values, not the primal's
//! `m × n`), robots that take no part relay, and every episode is the optimum of the
//! stacked rows.

use super::*;
use admm_ta_topologies::rng::SeededRng;
use serde_json::Value;

/// Both dual methods, Case 1 and Case 2, on a ring: every kind of costs, a warm episode, a
/// part of the team, an infeasible episode and the next one.
#[test]
fn dual_methods_reach_the_optimum_of_the_stacked_rows() {
    for method in ["dual", "inexact-dual"] {
        for (n, m) in [(6, 6), (7, 5)] {
            stacked_rows_optimal(method, n, m);
        }
    }
}

fn stacked_rows_optimal(method: &str, n: usize, m: usize) {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("pd{}{n}{m}-{}", &method[..2], std::process::id());
    let extra = format!(
        "topology = \"ring\"\nseed = 5\nmethod = \"{method}\"\non_failure = \"continue\"\n"
    );
    let team = team_file(dir.path(), &run, n, m, &extra);
    let mut team_of = start_team(&team, n);
    let mut rng = SeededRng::new(21);
    let what = |case: &str| format!("{method} {n}×{m}: {case}");
    let mut cases: Vec<(&str, Vec<Row>)> = vec![
        ("uniform", uniform(&mut rng, n, m, 1.0, 0.0)),
        ("distance", distances(&mut rng, n, m)),
        ("ties", ties(&mut rng, n, m, 3)),
        ("forbidden", forbidden(&mut rng, n, m, 0.4)),
        ("shifted", uniform(&mut rng, n, m, 1e-3, 1e9)),
        ("negative", uniform(&mut rng, n, m, 50.0, -80.0)),
        ("constant", vec![vec![Some(4.0); m]; n]),
    ];
    let mut drift = cases[1].1.clone();
    for row in &mut drift {
        for v in row.iter_mut().flatten() {
            *v += 0.5 * rng.uniform();
        }
    }
    cases.insert(2, ("distance, moved a little", drift));
    // One message of the team's size a round: the dual's prices and certificate, 2m + 1
    // values here (and the finish's packed tags, window, alarm and bound: 4 more; a part
    // of the team may be Case 1), or 2n for the closing's costs and tasks (the primal's:
    // n·m).
    let finish = if n >= m { 4 } else { 0 };
    let message = 8 * (2 * m + 1 + finish).max(2 * n) as u64;
    for (case, rows) in &cases {
        let answers = episode(&mut team_of, rows);
        assert_optimal(&answers, rows, false, &what(case));
        let rounds = answers[0]["rounds"].as_u64().unwrap();
        let agreement = answers[0]["agreement_rounds"].as_u64().unwrap();
        assert_eq!(
            answers[0]["sent_bytes"],
            (rounds + agreement) * message,
            "{}",
            what(case)
        );
    }
    // Robot 2 unavailable: the others solve, it relays.
    let full = distances(&mut rng, n, m.min(n - 1));
    let rows: Vec<Option<Row>> = (0..n).map(|i| (i != 2).then(|| full[i].clone())).collect();
    for s in &mut team_of {
        match &rows[s.id] {
            Some(row) => s.send_row(row),
            None => s.send("{\"available\": false}"),
        }
    }
    let answers: Vec<Value> = team_of.iter_mut().map(Sidecar::next).collect();
    assert_optimal_part(&answers, &rows, &what("robot 2 relays"));
    // No robot may do task 0: infeasible, said by every robot; then optimal again.
    let mut infeasible = uniform(&mut rng, n, m, 1.0, 0.0);
    for row in &mut infeasible {
        row[0] = None;
    }
    for a in episode(&mut team_of, &infeasible) {
        assert_eq!(a["feasible"], false, "{a}");
        assert!(a["task"].is_null(), "{a}");
    }
    let rows = uniform(&mut rng, n, m, 1.0, 0.0);
    assert_optimal(&episode(&mut team_of, &rows), &rows, false, &what("after"));
    finish_all(team_of);
    assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));
}

/// Across two hosts (Zenoh between every robot, or between the hosts' bridges) a robot's
/// messages are coded against its last: every episode is optimal as on one machine, and
/// the bytes a robot sent, counted as they went, are a fraction of its messages' values
/// (what `sent_bytes` counts over ipc), the round headers included.
#[cfg(feature = "zenoh")]
#[test]
fn a_dual_team_across_two_hosts_sends_its_messages_coded() {
    for transport in ["zenoh", "mixed"] {
        let (n, m) = (8, 8);
        let dir = tempfile::tempdir().unwrap();
        let run = format!("pdc{}-{}", &transport[..2], std::process::id());
        let hosts = super::elastic::two_hosts(transport, n);
        let extra = format!("topology = \"ring\"\nseed = 5\nmethod = \"dual\"\n{hosts}");
        let team = team_file(dir.path(), &run, n, m, &extra);
        let mut hosts = super::elastic::start_hosts(&team);
        let mut team_of = start_team(&team, n);
        let mut rng = SeededRng::new(7);
        let message = 8 * (2 * m + 1 + 4).max(2 * n) as u64;
        let mut rows = distances(&mut rng, n, m);
        for k in 0..4 {
            let what = format!("{transport} episode {k}");
            let answers = episode(&mut team_of, &rows);
            assert_optimal(&answers, &rows, false, &what);
            let rounds = answers[0]["rounds"].as_u64().unwrap();
            let agreement = answers[0]["agreement_rounds"].as_u64().unwrap();
            let raw = (rounds + agreement) * message;
            let sent = answers[0]["sent_bytes"].as_u64().unwrap();
            if transport == "zenoh" {
                assert!(sent > 0 && 2 * sent < raw, "{what}: {sent} of {raw} bytes");
            } else {
                // Mixed: the robots' own messages go through shared memory, as they are.
                assert_eq!(sent, raw, "{what}");
            }
            for v in rows.iter_mut().flatten().flatten() {
                *v += 0.3 * rng.uniform();
            }
        }
        finish_all(team_of);
        for host in &mut hosts {
            let status = common::wait_with_deadline(host, Duration::from_secs(60));
            assert!(status.success(), "{transport} host: {status}");
        }
        assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));
    }
}

/// Drifting distance costs for `episodes` episodes (a small move each, redrawn every tenth:
/// those start cold): every episode certified optimal; returns the rounds of the cold and of
/// the warm episodes.
fn drifting_episodes(
    team_of: &mut [Sidecar],
    n: usize,
    m: usize,
    episodes: usize,
    what: &str,
) -> (Vec<u64>, Vec<u64>) {
    let mut rng = SeededRng::new(100 + n as u64 + m as u64);
    let mut rows = distances(&mut rng, n, m);
    let (mut cold, mut warm) = (Vec::new(), Vec::new());
    for k in 0..episodes {
        if k % 10 == 0 {
            rows = distances(&mut rng, n, m);
        } else {
            for v in rows.iter_mut().flatten().flatten() {
                *v = (*v + 2.0 * (rng.uniform() - 0.5)).max(0.0);
            }
        }
        let answers = episode(team_of, &rows);
        assert_optimal(&answers, &rows, false, &format!("{what}: episode {k}"));
        assert_eq!(answers[0]["episode"], k);
        let rounds = answers[0]["rounds"].as_u64().unwrap();
        if k % 10 == 0 {
            cold.push(rounds)
        } else {
            warm.push(rounds)
        }
    }
    (cold, warm)
}

fn mean(v: &[u64]) -> f64 {
    v.iter().sum::<u64>() as f64 / v.len().max(1) as f64
}

/// A team of `method` on `topology` (the team's `seed`), `episodes` drifting episodes: every one optimal, warm
/// episodes fewer rounds than cold ones on average, nothing left in shared memory.
fn warm_beats_cold(
    method: &str,
    (n, m): (usize, usize),
    topology: &str,
    seed: u64,
    episodes: usize,
) {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("pd{n}{}{m}-{}", &method[..2], std::process::id());
    let extra = format!("topology = \"{topology}\"\nseed = {seed}\nmethod = \"{method}\"\n");
    let team = team_file(dir.path(), &run, n, m, &extra);
    let mut team_of = start_team(&team, n);
    let what = format!("{method} {n}×{m} on {topology}");
    let (cold, warm) = drifting_episodes(&mut team_of, n, m, episodes, &what);
    eprintln!(
        "{what}: cold {:.1} rounds (mean of {}), warm {:.1} (mean of {})",
        mean(&cold),
        cold.len(),
        mean(&warm),
        warm.len()
    );
    assert!(
        mean(&warm) < mean(&cold),
        "{what}: warm {warm:?}, cold {cold:?}"
    );
    finish_all(team_of);
    assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));
}

/// 100 episodes of a 10-robot ring, both dual methods, Case 1 and Case 2.
#[test]
fn a_hundred_dual_episodes_of_ten_robots_on_a_ring() {
    for method in ["dual", "inexact-dual"] {
        for shape in [(10, 10), (10, 7)] {
            warm_beats_cold(method, shape, "ring", 9, 100);
        }
    }
}

/// 20 episodes of 50 robots (Case 1 and Case 2), as one test runs them on two cores.
#[test]
fn twenty_dual_episodes_of_fifty_robots() {
    for (method, m) in [("dual", 50), ("inexact-dual", 40)] {
        warm_beats_cold(method, (50, m), "random:0.1", 4, 20);
    }
}
