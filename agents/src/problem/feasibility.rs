//! Hall's condition before any agent starts: a maximum bipartite matching on the allowed
//! robot–task pairs (Hopcroft–Karp, `O(E √V)`), and, when the side the case must saturate
//! is not saturated, a blocking set found from the matching (König): the tasks reachable by
//! alternating paths from an unmatched task, with their too-few robots (or the same from an
//! unmatched robot when every robot needs a task).

use std::collections::VecDeque;

const NONE: usize = usize::MAX;

/// The allowed pairs as adjacency lists of the robots (compressed rows).
pub struct AllowedGraph {
    robots: usize,
    tasks: usize,
    start: Vec<usize>,
    task_of: Vec<usize>,
}

impl AllowedGraph {
    /// From a row-major `robots × tasks` mask (`true`: allowed).
    pub fn from_mask(robots: usize, tasks: usize, allowed: &[bool]) -> Self {
        let mut start = Vec::with_capacity(robots + 1);
        let mut task_of = Vec::new();
        start.push(0);
        for i in 0..robots {
            for t in 0..tasks {
                if allowed[i * tasks + t] {
                    task_of.push(t);
                }
            }
            start.push(task_of.len());
        }
        Self {
            robots,
            tasks,
            start,
            task_of,
        }
    }

    fn of_robot(&self, i: usize) -> &[usize] {
        &self.task_of[self.start[i]..self.start[i + 1]]
    }
}

/// A maximum matching: task of each robot and robot of each task (`usize::MAX`: none).
pub struct Matching {
    pub task_of_robot: Vec<usize>,
    pub robot_of_task: Vec<usize>,
}

/// Hopcroft–Karp maximum matching of the allowed pairs.
pub fn maximum_matching(g: &AllowedGraph) -> Matching {
    let (n, m) = (g.robots, g.tasks);
    let mut task_of_robot = vec![NONE; n];
    let mut robot_of_task = vec![NONE; m];
    let mut dist = vec![0usize; n];
    let mut queue = VecDeque::new();
    loop {
        // BFS layers from the free robots.
        queue.clear();
        for i in 0..n {
            if task_of_robot[i] == NONE {
                dist[i] = 0;
                queue.push_back(i);
            } else {
                dist[i] = NONE;
            }
        }
        let mut found = false;
        while let Some(i) = queue.pop_front() {
            for &t in g.of_robot(i) {
                let r = robot_of_task[t];
                if r == NONE {
                    found = true;
                } else if dist[r] == NONE {
                    dist[r] = dist[i] + 1;
                    queue.push_back(r);
                }
            }
        }
        if !found {
            break;
        }
        // DFS along the layers (iterative, with a per-robot edge cursor).
        let mut cursor: Vec<usize> = (0..n).map(|i| g.start[i]).collect();
        for root in 0..n {
            if task_of_robot[root] != NONE {
                continue;
            }
            let mut stack = vec![root];
            while let Some(&i) = stack.last() {
                if cursor[i] == g.start[i + 1] {
                    dist[i] = NONE;
                    stack.pop();
                    continue;
                }
                let t = g.task_of[cursor[i]];
                cursor[i] += 1;
                let r = robot_of_task[t];
                if r == NONE {
                    // Augment along the stack: each robot takes the task its cursor just passed.
                    for &robot in stack.iter().rev() {
                        let task = g.task_of[cursor[robot] - 1];
                        task_of_robot[robot] = task;
                        robot_of_task[task] = robot;
                    }
                    break;
                } else if dist[r] != NONE && dist[r] == dist[i] + 1 {
                    stack.push(r);
                }
            }
        }
    }
    Matching {
        task_of_robot,
        robot_of_task,
    }
}

/// Which side must be matched completely.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Saturate {
    /// Every task gets a robot (Case 1, Case 2, `idle` with `n ≥ m`).
    Tasks,
    /// Every robot gets a task (`idle` with `n < m`).
    Robots,
}

/// `None` when the side is saturated; otherwise the blocking-set sentence (without the
/// `infeasible: ` prefix).
pub fn blocking_set(g: &AllowedGraph, matching: &Matching, side: Saturate) -> Option<String> {
    let (own, other, own_name, other_name, verb) = match side {
        Saturate::Tasks => (
            &matching.robot_of_task,
            &matching.task_of_robot,
            "task",
            "robot",
            "can only be done by",
        ),
        Saturate::Robots => (
            &matching.task_of_robot,
            &matching.robot_of_task,
            "robot",
            "task",
            "can only do",
        ),
    };
    let free = own.iter().position(|&x| x == NONE)?;
    // Neighbours on the other side of one vertex of the saturated side.
    let tasks_robots = match side {
        Saturate::Tasks => robots_of_tasks(g),
        Saturate::Robots => Vec::new(),
    };
    let neighbours = |v: usize| -> Vec<usize> {
        match side {
            Saturate::Tasks => tasks_robots[v].clone(),
            Saturate::Robots => g.of_robot(v).to_vec(),
        }
    };
    let mut seen_own = vec![false; own.len()];
    let mut seen_other = vec![false; other.len()];
    let mut queue = VecDeque::from([free]);
    seen_own[free] = true;
    while let Some(v) = queue.pop_front() {
        for w in neighbours(v) {
            if !seen_other[w] {
                seen_other[w] = true;
                let back = other[w];
                if back != NONE && !seen_own[back] {
                    seen_own[back] = true;
                    queue.push_back(back);
                }
            }
        }
    }
    let set: Vec<usize> = (0..own.len()).filter(|&v| seen_own[v]).collect();
    let helpers: Vec<usize> = (0..other.len()).filter(|&w| seen_other[w]).collect();
    let who = |name: &str, list: &[usize]| {
        format!(
            "{}{} {}",
            name,
            if list.len() == 1 { "" } else { "s" },
            abbreviate(list)
        )
    };
    Some(if helpers.is_empty() {
        let what = match side {
            Saturate::Tasks => "has no allowed robot",
            Saturate::Robots => "has no allowed task",
        };
        format!("{} {what}", who(own_name, &set))
    } else {
        format!(
            "{} {verb} {}",
            who(own_name, &set),
            who(other_name, &helpers)
        )
    })
}

fn robots_of_tasks(g: &AllowedGraph) -> Vec<Vec<usize>> {
    let mut out = vec![Vec::new(); g.tasks];
    for i in 0..g.robots {
        for &t in g.of_robot(i) {
            out[t].push(i);
        }
    }
    out
}

/// `3, 7, 9` or `0, 1, 2, 3, 4, 5, 6, 7, … (40 in all)`.
pub fn abbreviate(list: &[usize]) -> String {
    const SHOWN: usize = 8;
    let head: Vec<String> = list.iter().take(SHOWN).map(|v| v.to_string()).collect();
    if list.len() > SHOWN {
        format!("{}, … ({} in all)", head.join(", "), list.len())
    } else {
        head.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mask(rows: &[&str]) -> (usize, usize, Vec<bool>) {
        let m = rows[0].len();
        let v = rows
            .iter()
            .flat_map(|r| r.chars().map(|c| c == '1'))
            .collect();
        (rows.len(), m, v)
    }

    #[test]
    fn finds_maximum_matchings_and_blocking_sets() {
        let (n, m, v) = mask(&["110", "100", "011"]);
        let g = AllowedGraph::from_mask(n, m, &v);
        let mm = maximum_matching(&g);
        assert!(mm.task_of_robot.iter().all(|&t| t != NONE));
        assert_eq!(blocking_set(&g, &mm, Saturate::Tasks), None);

        // Tasks 1 and 2 can only be done by robot 2.
        let (n, m, v) = mask(&["100", "100", "011"]);
        let g = AllowedGraph::from_mask(n, m, &v);
        let mm = maximum_matching(&g);
        let text = blocking_set(&g, &mm, Saturate::Tasks).unwrap();
        assert_eq!(text, "tasks 1, 2 can only be done by robot 2");

        let (n, m, v) = mask(&["10", "10", "00"]);
        let g = AllowedGraph::from_mask(n, m, &v);
        let mm = maximum_matching(&g);
        assert_eq!(
            blocking_set(&g, &mm, Saturate::Tasks).unwrap(),
            "task 1 has no allowed robot"
        );
        let (n, m, v) = mask(&["1000", "1000"]);
        let g = AllowedGraph::from_mask(n, m, &v);
        let mm = maximum_matching(&g);
        assert_eq!(
            blocking_set(&g, &mm, Saturate::Robots).unwrap(),
            "robots 0, 1 can only do task 0"
        );
    }

    #[test]
    fn matching_is_maximum_on_random_masks() {
        let mut state = 7u64;
        for _ in 0..200 {
            let n = 1 + (state % 7) as usize;
            let m = 1 + ((state >> 8) % 7) as usize;
            let v: Vec<bool> = (0..n * m)
                .map(|_| {
                    state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
                    (state >> 33).is_multiple_of(3)
                })
                .collect();
            let g = AllowedGraph::from_mask(n, m, &v);
            let mm = maximum_matching(&g);
            let size = mm.task_of_robot.iter().filter(|&&t| t != NONE).count();
            // Brute force: the largest matching by trying every injective map (small sizes).
            assert_eq!(size, brute(&v, n, m, 0, &mut vec![false; m]));
            for (i, &t) in mm.task_of_robot.iter().enumerate() {
                if t != NONE {
                    assert!(v[i * m + t] && mm.robot_of_task[t] == i);
                }
            }
        }
    }

    fn brute(v: &[bool], n: usize, m: usize, i: usize, used: &mut Vec<bool>) -> usize {
        if i == n {
            return 0;
        }
        let mut best = brute(v, n, m, i + 1, used);
        for t in 0..m {
            if v[i * m + t] && !used[t] {
                used[t] = true;
                best = best.max(1 + brute(v, n, m, i + 1, used));
                used[t] = false;
            }
        }
        best
    }
}
