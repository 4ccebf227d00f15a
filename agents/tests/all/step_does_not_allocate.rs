//! The per-round step works in buffers allocated at construction: after the first rounds,
//! a primal step (fused update + Newton projection + rounding inspection) and a dual or
//! inexact-dual step (multiplier update, x-update, certificate) allocate nothing.

use admm_ta_agents::agent::ConsensusAgent;
use admm_ta_agents::method::agent::MethodAgent;
use admm_ta_agents::method::team::{AgentInit, TeamContext, TeamParams};
use admm_ta_agents::methods::{Contender, Method};
use admm_ta_agents::problem::{AssignmentCase, CaseChoice, CostMatrix, TaskAssignmentProblem};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// Counts the allocations of the current thread only (the test harness allocates on its
/// own threads meanwhile).
struct CountingAllocator;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|count| count.set(count.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// `method` in `variant` (a name of its variant setting; ignored by methods without
/// variants).
fn contender(method: Method, variant: &'static str) -> Contender {
    Contender {
        method,
        variant: method.variant_setting().map(|_| variant),
    }
}

fn team_rounds(
    method: Method,
    variant: &'static str,
    robots: usize,
    tasks: usize,
    case: AssignmentCase,
    rounds: usize,
) -> usize {
    let costs = CostMatrix::uniform(robots, tasks, 11).unwrap();
    team_rounds_on(method, variant, &costs, case, rounds)
}

/// As [`team_rounds`] on given costs (a normalised problem's, say).
fn team_rounds_on(
    method: Method,
    variant: &'static str,
    costs: &CostMatrix,
    case: AssignmentCase,
    rounds: usize,
) -> usize {
    let (robots, tasks) = (costs.robots(), costs.tasks());
    let setup = method
        .setup(&contender(method, variant).settings())
        .unwrap()
        .unwrap();
    let rho = setup.default_rho(costs, (robots - 1) as f64).unwrap_or(0.0);
    let problem = TaskAssignmentProblem::internal_from(costs.clone(), case).unwrap();
    let graph = admm_ta_topologies::generate::complete(robots).unwrap();
    let params = TeamParams {
        rho,
        diameter: 1,
        tolerance: 1e-9,
    };
    let team = setup.team(TeamContext {
        problem: &problem,
        graph: &graph,
        params,
    });
    let mut agents: Vec<MethodAgent> = (0..robots)
        .map(|i| {
            MethodAgent::new(team.agent(AgentInit {
                index: i,
                costs: costs.row(i).to_vec(),
                robots,
                case,
                degree: robots - 1,
            }))
        })
        .collect();
    let len = setup.payload_len(robots, tasks);
    let mut current = vec![0.0; len * robots];
    for (i, agent) in agents.iter().enumerate() {
        agent.write_initial_payload(&mut current[i * len..(i + 1) * len]);
    }
    let mut next = vec![0.0; len * robots];
    let mut allocations_in_steps = 0;
    for round in 0..rounds {
        for (i, agent) in agents.iter_mut().enumerate() {
            // The inbox is the runner's business: built outside the measured window.
            let inbox: Vec<&[f64]> = (0..robots)
                .filter(|&j| j != i)
                .map(|j| &current[j * len..(j + 1) * len])
                .collect();
            let before = allocations();
            agent.step(&inbox, &mut next[i * len..(i + 1) * len]);
            // The round loop checks the certificate after a step (Algorithm 1: an `m × n`
            // assignment problem in the agent's scratch).
            std::hint::black_box(agent.certificate_slack());
            if round >= 2 {
                allocations_in_steps += allocations() - before;
            }
        }
        std::mem::swap(&mut current, &mut next);
    }
    allocations_in_steps
}

#[test]
fn every_method_steps_without_allocating_after_warm_up() {
    // The distributed Hungarian allocates once, when it solves the full problem.
    for method in [
        Method::Primal,
        Method::Dual,
        Method::InexactDual,
        Method::Cbaa,
        Method::Market,
    ] {
        for variant in ["paper", "fast"] {
            assert_eq!(
                team_rounds(method, variant, 12, 12, AssignmentCase::One, 40),
                0,
                "{method:?} ({variant})"
            );
            assert_eq!(
                team_rounds(method, variant, 14, 6, AssignmentCase::Two, 40),
                0,
                "{method:?} ({variant})"
            );
        }
        // The normalised problems of forbidden pairs, of idle robots and of unserved tasks
        // (transposed: the tasks are the agents).
        for (text, choice) in [
            (forbidden_text(), CaseChoice::Auto),
            (idle_text(), CaseChoice::Forced(AssignmentCase::Idle)),
            (wide_text(), CaseChoice::Forced(AssignmentCase::Idle)),
        ] {
            let problem =
                TaskAssignmentProblem::new(CostMatrix::from_csv_str(&text).unwrap(), choice)
                    .unwrap();
            let internal = problem.internal();
            for variant in ["paper", "fast"] {
                assert_eq!(
                    team_rounds_on(method, variant, internal.costs(), internal.case(), 40),
                    0,
                    "{method:?} ({variant:?}) on {choice:?}"
                );
            }
        }
    }
}

/// 10 × 10 with every third pair forbidden (`inf`), feasible.
fn forbidden_text() -> String {
    (0..10)
        .map(|i| {
            (0..10)
                .map(|j| {
                    if (i + 2 * j) % 3 == 1 && i != j {
                        "inf".to_string()
                    } else {
                        format!("{}", ((i * 7 + j * 3) % 11) as f64 / 11.0 + 0.01 * j as f64)
                    }
                })
                .collect::<Vec<_>>()
                .join(",")
                + "\n"
        })
        .collect()
}

/// 12 robots, 5 tasks, scipy's idle meaning.
fn idle_text() -> String {
    (0..12)
        .map(|i| {
            (0..5)
                .map(|j| format!("{}", ((i * 5 + j * 7) % 13) as f64 + 0.001 * i as f64))
                .collect::<Vec<_>>()
                .join(",")
                + "\n"
        })
        .collect()
}

#[test]
fn the_fast_primal_steps_and_reads_its_assignment_without_allocating() {
    // The readout's local assignment problem runs in its preallocated workspace, the
    // closed-form projection in its own scratch.
    for (robots, tasks, case) in [(12, 12, AssignmentCase::One), (14, 6, AssignmentCase::Two)] {
        assert_eq!(
            team_rounds(Method::Primal, "fast", robots, tasks, case, 40),
            0,
            "{robots}×{tasks}"
        );
    }
}

/// 5 robots, 12 tasks (one forbidden pair), scipy's idle meaning: 7 tasks unserved.
fn wide_text() -> String {
    (0..5)
        .map(|i| {
            (0..12)
                .map(|j| {
                    if i == 1 && j == 4 {
                        "inf".to_string()
                    } else {
                        format!("{}", ((i * 7 + j * 5) % 13) as f64 + 0.001 * j as f64)
                    }
                })
                .collect::<Vec<_>>()
                .join(",")
                + "\n"
        })
        .collect()
}
