//! The refusal of a solve too large for the machine, before anything large is built.

use crate::solve::error::SolveError;
use admm_ta_agents::method::info::Numbers;
use admm_ta_agents::methods::Method;
use admm_ta_agents::problem::TaskAssignmentProblem;
use admm_ta_topologies::Graph;

/// A solve whose method needs more memory than this (by its registry entry's estimate:
/// agent state plus round buffers, or the centralized solver's) is refused up front.
pub const MEMORY_LIMIT_BYTES: f64 = 8.0 * (1u64 << 30) as f64;

/// Refuses a solve whose method would need more than [`MEMORY_LIMIT_BYTES`] on the
/// `solved` shape (`robots × tasks` of the problem it runs), plus `extra` bytes (the team's
/// graph); the error names the user's shape `user`.
fn refuse_beyond_memory(
    method: Method,
    user: (usize, usize),
    solved: (usize, usize),
    extra: f64,
) -> Result<(), SolveError> {
    let memory = &method.info().memory;
    let bytes = (memory.bytes)(solved.0, solved.1) + extra;
    if bytes > MEMORY_LIMIT_BYTES {
        return Err(SolveError::TooLarge {
            robots: user.0,
            tasks: user.1,
            method: method.name(),
            solved_as: (solved != user).then_some(solved),
            gib: bytes / (1u64 << 30) as f64,
            of: memory.of,
            because: memory.because,
        });
    }
    Ok(())
}

/// The memory check of a solve, done on the user's problem before anything large is
/// built: a team that solves the user's own numbers (the distributed Hungarian method) on the
/// user's shape; the centralized solver and a team on the normalised shape they solve (the
/// tasks are the agents when `n < m` is transposed), a team with the edges of the graph it
/// then runs on (counted, not built: each pair of hosts that are the same or neighbours
/// links every task of one with every task of the other).
pub(super) fn check_size(
    problem: &TaskAssignmentProblem,
    graph: &Graph,
    method: Method,
) -> Result<(), SolveError> {
    let user = (problem.robots(), problem.tasks());
    let team = method.team().is_some();
    if team && method.info().numbers == Numbers::Exact {
        return refuse_beyond_memory(method, user, user, 0.0);
    }
    let internal = problem.internal();
    let solved = (internal.robots(), internal.tasks());
    if !team {
        return refuse_beyond_memory(method, user, solved, 0.0);
    }
    let (agents, hosts) = (internal.robots(), graph.robots());
    let mut edges = 0.0;
    if agents != hosts && problem.robots() == hosts {
        // Agent `a` runs on host `a mod hosts`.
        let per_host = |h: usize| ((agents + hosts - 1 - h) / hosts) as f64;
        for h in 0..hosts {
            let c = per_host(h);
            edges += c * (c - 1.0) / 2.0;
            for &g in graph.neighbours(h).iter().filter(|&&g| g > h) {
                edges += c * per_host(g);
            }
        }
    }
    // Two adjacency entries per edge, and the edge list they are built from.
    refuse_beyond_memory(method, user, solved, 32.0 * edges)
}
