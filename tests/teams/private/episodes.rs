//! Every episode of a standing team is the optimum of the stacked rows.

use super::*;
use admm_ta_topologies::rng::SeededRng;
use serde_json::Value;

#[test]
fn private_rows_reach_the_optimum_of_the_stacked_rows() {
    for transport in ["ipc", "shm", "uds"] {
        stacked_rows_optimal_over(transport);
    }
}

fn stacked_rows_optimal_over(transport: &str) {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("priv{transport}-{}", std::process::id());
    let (n, m) = (7, 5);
    let team = team_file(
        dir.path(),
        &run,
        n,
        m,
        &format!("topology = \"ring\"\nseed = 3\ntransport = \"{transport}\"\n"),
    );
    let mut team_of = start_team(&team, n);
    let mut rng = SeededRng::new(11);
    let mut cases: Vec<(&str, Vec<Row>)> = vec![
        ("uniform", uniform(&mut rng, n, m, 1.0, 0.0)),
        ("uniform again", uniform(&mut rng, n, m, 1.0, 0.0)),
        ("distance", distances(&mut rng, n, m)),
        ("ties", ties(&mut rng, n, m, 3)),
        ("forbidden", forbidden(&mut rng, n, m, 0.5)),
        ("shifted", uniform(&mut rng, n, m, 1e-3, 1e9)),
        ("negative", uniform(&mut rng, n, m, 50.0, -80.0)),
        ("constant", vec![vec![Some(4.0); m]; n]),
    ];
    // A small change of the last costs (a warm episode).
    let mut drift = cases[2].1.clone();
    for row in &mut drift {
        for v in row.iter_mut().flatten() {
            *v += rng.uniform();
        }
    }
    cases.insert(3, ("distance, moved", drift));
    for (what, rows) in &cases {
        let answers = episode(&mut team_of, rows);
        assert_optimal(&answers, rows, false, &format!("{transport}: {what}"));
    }
    // No robot may do task 0: no feasible assignment, said by every robot.
    let mut infeasible = uniform(&mut rng, n, m, 1.0, 0.0);
    for row in &mut infeasible {
        row[0] = None;
    }
    for a in episode(&mut team_of, &infeasible) {
        assert_eq!(a["feasible"], false, "{a}");
        assert_eq!(a["certified"], false, "{a}");
        assert!(a["task"].is_null(), "{a}");
    }
    // And the next episode is optimal again.
    let rows = distances(&mut rng, n, m);
    assert_optimal(
        &episode(&mut team_of, &rows),
        &rows,
        false,
        "after infeasible",
    );
    finish_all(team_of);
    assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));
}

#[test]
fn private_profits_are_maximised_on_a_complete_graph() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("privmax-{}", std::process::id());
    let n = 5;
    let team = team_file(
        dir.path(),
        &run,
        n,
        n,
        "maximize = true\nwarm_start = false\n",
    );
    let mut team_of = start_team(&team, n);
    let mut rng = SeededRng::new(4);
    for k in 0..4 {
        let rows = if k % 2 == 0 {
            uniform(&mut rng, n, n, 10.0, 0.0)
        } else {
            forbidden(&mut rng, n, n, 0.3)
        };
        assert_optimal(&episode(&mut team_of, &rows), &rows, true, "maximize");
    }
    finish_all(team_of);
}

/// 100 consecutive episodes of a 10-robot standing team with costs changing every episode:
/// every one optimal, nothing left in shared memory afterwards.
#[test]
fn a_hundred_episodes_of_ten_robots() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("priv100-{}", std::process::id());
    let (n, m) = (10, 8);
    let team = team_file(
        dir.path(),
        &run,
        n,
        m,
        "topology = \"random:0.4\"\nseed = 9\n",
    );
    let mut team_of = start_team(&team, n);
    let mut rng = SeededRng::new(100);
    let mut rows = distances(&mut rng, n, m);
    for k in 0..100 {
        for row in &mut rows {
            for v in row.iter_mut().flatten() {
                *v = (*v + 4.0 * (rng.uniform() - 0.5)).max(0.0);
            }
        }
        let answers = episode(&mut team_of, &rows);
        assert_optimal(&answers, &rows, false, &format!("episode {k}"));
        assert_eq!(answers[0]["episode"], k);
    }
    finish_all(team_of);
    assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));
}

/// Episodes with robots that take no part (unavailable, or without a row and
/// `on_failure = "continue"`) and with fewer tasks than declared: the certified optimum of
/// what takes part, also when most robots only relay; too few robots, or rows of different lengths, solve nothing and say why.
#[test]
fn unavailable_robots_missing_rows_and_fewer_tasks() {
    let dir = tempfile::tempdir().unwrap();
    let run = format!("privpart-{}", std::process::id());
    let (n, m) = (6, 5);
    let team = team_file(
        dir.path(),
        &run,
        n,
        m,
        "topology = \"ring\"\non_failure = \"continue\"\nepisode_timeout = 2.0\n",
    );
    let mut team_of = start_team(&team, n);
    let mut rng = SeededRng::new(31);
    // (robots without a part: unavailable, missing), tasks
    let plans: [(&[usize], &[usize], usize); 7] = [
        (&[], &[], 5),
        (&[2], &[], 5),
        (&[], &[], 3),
        (&[1, 4], &[], 4),
        (&[], &[3], 5),
        // A part of fewer than half the team (it never certified when the tolerance was
        // shared among every slot).
        (&[0, 2, 3, 5], &[], 2),
        (&[], &[], 5),
    ];
    for (k, (unavailable, missing, tasks)) in plans.iter().enumerate() {
        let full = distances(&mut rng, n, *tasks);
        let rows: Vec<Option<Row>> = (0..n)
            .map(|i| (!unavailable.contains(&i) && !missing.contains(&i)).then(|| full[i].clone()))
            .collect();
        for s in &mut team_of {
            match &rows[s.id] {
                Some(row) => s.send_row(row),
                None if unavailable.contains(&s.id) => s.send("{\"available\": false}"),
                None => {}
            }
        }
        let answers: Vec<Value> = team_of.iter_mut().map(Sidecar::next).collect();
        let what = format!("episode {k}");
        assert_optimal_part(&answers, &rows, &what);
        for a in &answers {
            assert_eq!(
                a["unavailable"].as_array().map_or(0, Vec::len),
                unavailable.len()
            );
            assert_eq!(a["missing"].as_array().map_or(0, Vec::len), missing.len());
        }
    }
    // Four robots for five tasks: infeasible, said by every robot.
    let full = uniform(&mut rng, n, m, 1.0, 0.0);
    for s in &mut team_of {
        if s.id < 2 {
            s.send("{\"available\": false}");
        } else {
            s.send_row(&full[s.id]);
        }
    }
    for s in &mut team_of {
        let a = s.next();
        assert!(a["task"].is_null() && a["feasible"] == false, "{a}");
        assert!(
            a["unsolved"].as_str().unwrap().contains("infeasible"),
            "{a}"
        );
    }
    // Rows of different lengths: nothing solved, and why.
    for s in &mut team_of {
        let len = if s.id == 0 { 4 } else { 5 };
        s.send_row(&full[s.id][..len].to_vec());
    }
    for s in &mut team_of {
        let a = s.next();
        assert!(a["task"].is_null(), "{a}");
        assert!(
            a["unsolved"].as_str().unwrap().contains("4 to 5 costs"),
            "{a}"
        );
    }
    // And everybody again.
    let rows = uniform(&mut rng, n, m, 1.0, 0.0);
    assert_optimal(&episode(&mut team_of, &rows), &rows, false, "all again");
    finish_all(team_of);
    assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));
}

/// Robots that take no part on graphs whose robots have different numbers of neighbours (a
/// star's hub and leaves, a chain's ends): each runs its place in the part with its own
/// neighbours.
#[test]
fn parts_on_irregular_graphs() {
    for topology in ["star", "chain"] {
        let dir = tempfile::tempdir().unwrap();
        let run = format!("privirr{topology}-{}", std::process::id());
        let (n, m) = (6, 4);
        let team = team_file(
            dir.path(),
            &run,
            n,
            m,
            &format!("topology = \"{topology}\"\n"),
        );
        let mut team_of = start_team(&team, n);
        let mut rng = SeededRng::new(17);
        for away in [vec![3], vec![0], vec![0, 5]] {
            let full = distances(&mut rng, n, m);
            let rows: Vec<Option<Row>> = (0..n)
                .map(|i| (!away.contains(&i)).then(|| full[i].clone()))
                .collect();
            for s in &mut team_of {
                match &rows[s.id] {
                    Some(row) => s.send_row(row),
                    None => s.send("{\"available\": false, \"episode\": null}"),
                }
            }
            let answers: Vec<Value> = team_of.iter_mut().map(Sidecar::next).collect();
            assert_optimal_part(&answers, &rows, &format!("{topology}, away {away:?}"));
        }
        finish_all(team_of);
        assert!(shm_of(&run).is_empty(), "{:?}", shm_of(&run));
    }
}
