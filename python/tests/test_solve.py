"""admm_ta.solve: every method over every transport on small problems, the options of
the command line, the result object, and errors as Python exceptions."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment as scipy_lsap

import admm_ta

METHODS = ["primal", "dual", "inexact-dual", "market", "dist-hungarian"]
TRANSPORTS = ["sim", "threads", "shm", "ipc", "uds"]


def optimum(cost, maximize=False):
    rows, cols = scipy_lsap(cost, maximize=maximize)
    return float(np.asarray(cost, dtype=float)[rows, cols].sum())


@pytest.mark.parametrize("transport", TRANSPORTS)
@pytest.mark.parametrize("method", METHODS)
def test_every_method_over_every_transport_is_optimal_and_certified(method, transport):
    cost = np.random.default_rng(3).random((5, 5))
    result = admm_ta.solve(
        cost, topology="ring", method=method, transport=transport, check=True, seed=2
    )
    assert result.certified and result.optimal
    assert result.cost == pytest.approx(optimum(cost))
    assert sorted(result.assignment) == list(range(5))
    assert result.method == method and result.transport == transport
    assert result.rounds > 0 and result.bytes_per_agent > 0
    if transport == "sim":
        assert result.round_latency_us is None
    else:
        assert result.round_latency_us["round"]["count"] > 0
        assert result.round_latency_us["round"]["p99"] >= result.round_latency_us["round"]["p50"]


def test_the_result_is_the_command_line_s_json_report():
    cost = [[4.0, 1.0, 3.0], [2.0, 0.0, 5.0], [3.0, 2.0, 2.0]]
    result = admm_ta.solve(cost, topology="chain", check=True)
    report = result.to_dict()
    cli = subprocess.run(
        [sys.executable, "-m", "admm_ta", "solve", "--topology", "chain", "--check", "--json",
         "--costs", "-"],
        input="4,1,3\n2,0,5\n3,2,2\n", capture_output=True, text=True, check=True,
    )
    from_cli = json.loads(cli.stdout)
    assert set(report) == set(from_cli)
    for key in ["assignment", "cost", "iterations", "certified", "method", "case", "rho"]:
        assert report[key] == from_cli[key], key
    assert result.assignment == [1, 0, 2] and result.cost == 5.0
    report["assignment"].append(99)  # a copy
    assert result.to_dict()["assignment"] == [1, 0, 2]
    assert "certified=True" in repr(result)


def test_rectangular_maximize_forbidden_and_idle():
    rng = np.random.default_rng(7)
    profits = rng.integers(0, 20, size=(4, 7)).astype(float)
    profits[0, :3] = -np.inf
    result = admm_ta.solve(profits, maximize=True, case="idle", check=True)
    assert result.optimal and result.cost == pytest.approx(optimum(profits, maximize=True))
    assert all(profits[r, t] != -np.inf for r, t in enumerate(result.assignment))
    tall = rng.random((6, 3))
    result = admm_ta.solve(tall, case="idle", check=True, method="dual")
    assert result.assignment.count(None) == 3
    assert result.cost == pytest.approx(optimum(tall))


def test_topologies_as_names_edge_lists_and_graph_objects():
    cost = np.random.default_rng(1).random((4, 4))
    best = optimum(cost)
    for topology in ["star", [(0, 1), (1, 2), (2, 3)], [(1, 0), (0, 1), (2, 1), (3, 2)]]:
        assert admm_ta.solve(cost, topology=topology).cost == pytest.approx(best)

    class Graph:  # networkx's interface: nodes() and edges()
        def nodes(self):
            return ["a", "b", "c", "d"]

        def edges(self):
            return [("a", "b"), ("b", "c"), ("c", "d", {"weight": 1})]

    assert admm_ta.solve(cost, topology=Graph()).cost == pytest.approx(best)


def test_random_costs_and_options_by_name():
    result = admm_ta.solve(
        robots=6, tasks=4, seed=3, cost_model="geometric", method="primal", rho=2.5,
        max_iters=3000, perturb="off", transport="threads", round_timeout=5, check=True,
    )
    assert result.optimal and len(result.assignment) == 6
    result = admm_ta.solve(robots=5, tasks=5, transport="threads", global_barrier=True)
    assert result.to_dict()["global_barrier"] is True


def test_cost_files(tmp_path):
    path = tmp_path / "costs.csv"
    path.write_text("robot,t1,t2\nr1,1,5\nr2,4,2\n")
    result = admm_ta.solve(path, check=True)
    assert result.assignment == [0, 1] and result.cost == 3.0
    assert admm_ta.solve(str(path)).cost == 3.0


@pytest.mark.parametrize(
    "kwargs, needle",
    [
        ({"cost": [[np.nan]]}, "NaN"),
        ({"cost": [[np.inf, 1], [np.inf, 2]]}, "infeasible"),
        ({"cost": [[1, 2]], "frobnicate": 3}, "--frobnicate"),
        ({"cost": [[1, 2]], "method": "magic"}, "magic"),
        ({"cost": [[1, 2], [2, 1]], "topology": [(0, 0)]}, "self"),
        ({"cost": [[1, 2], [2, 1], [3, 3]], "topology": [(0, 1)]}, "connected"),
        ({"cost": [[1, 2], [2, 1]], "topology": "nonsense"}, "nonsense"),
        ({"cost": [[1, 2]], "rho": -1}, "ρ"),
        ({"cost": np.zeros((0, 3))}, "robots"),
        ({"cost": [1, 2, 3]}, "2-D"),
        ({"cost": [[1, 2]], "robots": 3, "tasks": 3}, "given already"),
        ({"cost": None}, "--robots"),
        ({"cost": [[1, 2]], "round_timeout": 5}, "sim"),
        ({"cost": [[1, 2]], "transport": "zenoh"}, "zenoh"),
        ({"cost": [[1, 2]], "costs": "x.csv"}, "cost"),
        ({"robots": 4}, "--tasks"),
        ({"cost": [[1, 2]], "max_iters": "many"}, "--max-iters"),
        ({"cost": [[1, 2]], "trace": True}, "--check"),
        ({"cost": [[1, 2]], "stop": "whenever"}, "whenever"),
        ({"cost": [[1, 2]], "dual_variant": "paper"}, "--method"),
        ({"cost": [[1, 2]], "global_barrier": "yes"}, "--global-barrier"),
    ],
)
def test_bad_input_raises_value_error_with_the_command_line_s_message(kwargs, needle):
    with pytest.raises(ValueError) as error:
        admm_ta.solve(**kwargs)
    assert needle.lower() in str(error.value).lower()
    assert "\n" not in str(error.value)


def test_a_run_without_certificate_raises_with_the_best_assignment():
    cost = np.random.default_rng(11).random((12, 12))
    with pytest.raises(admm_ta.NotCertifiedError) as error:
        admm_ta.solve(cost, method="dual", max_iters=5)
    assert error.value.exit_code == 5
    assert isinstance(error.value, admm_ta.SolveError)
    assert error.value.result is not None and not error.value.result.certified
    assert len(error.value.result.assignment) == 12


def test_the_tests_fault_switch_is_not_in_the_package():
    """`ADMM_TA_FAULT` (the Rust tests' fault injection) is compiled out of the package: an
    agent told to exit at round 3 runs on, and the team is optimal."""
    code = (
        "import admm_ta, numpy\n"
        "r = admm_ta.solve(numpy.eye(4), transport='ipc', round_timeout=2, check=True)\n"
        "print(r.optimal)\n"
    )
    env = dict(os.environ, ADMM_TA_FAULT="2:3:exit")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["True"]


def test_ipc_needs_nothing_but_the_installed_package(tmp_path):
    """Agent processes start from this interpreter: no cargo, no repository, no binary on
    PATH, from another directory."""
    code = (
        "import admm_ta, numpy\n"
        "r = admm_ta.solve(numpy.random.default_rng(0).random((6, 6)), transport='ipc',"
        " topology='ring', check=True)\n"
        "print(r.certified, r.optimal, r.transport)\n"
    )
    env = {"PATH": "/nonexistent", "HOME": str(tmp_path)}
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["True", "True", "ipc"]


def test_the_command_line_script():
    out = subprocess.run([sys.executable, "-m", "admm_ta", "solve", "--robots", "4", "--tasks",
                          "4", "--check"], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert "optimal" in out.stdout
    out = subprocess.run([sys.executable, "-m", "admm_ta", "solve", "--bogus"],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 2 and "--bogus" in out.stderr


def test_a_timeline_and_the_critical_path(tmp_path):
    trace = tmp_path / "t.json"
    result = admm_ta.solve(np.random.default_rng(2).random((6, 6)), topology="ring",
                           transport="ipc", timeline=trace)
    path = result.critical_path
    assert path is not None and 0.0 <= path["waiting_share"] <= 1.0
    assert len(path["rounds"]) == result.rounds - 1
    events = json.loads(trace.read_text())["traceEvents"]
    assert {e["pid"] for e in events} == set(range(6))
    assert admm_ta.solve([[1, 2], [2, 1]]).critical_path is None


def test_the_report_is_read_from_the_library_not_from_text():
    """`solve` hands the library its options and reads the report's fields: the result
    wraps the extension's report object, and `to_dict()` is a fresh copy every call."""
    result = admm_ta.solve(np.eye(3), transport="threads", check=True, seed=4)
    assert type(result._report).__name__ == "Report"
    first, second = result.to_dict(), result.to_dict()
    assert first == second and first is not second
    assert first["assignment"] == result.assignment and first["check"]["optimal"] is True
    assert isinstance(first["round_latency_us"]["round"]["count"], int)
