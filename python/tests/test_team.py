"""admm_ta.TeamMember: robots that keep their own costs, one member per thread as separate
robot programs would be, every episode the optimum of the stacked rows (scipy as the
oracle), bad rows refused without touching the team, unavailable robots relaying; the
primal and both dual methods."""

import os
import threading

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment as scipy_lsap

import admm_ta


def team_file(tmp_path, run, robots, tasks, extra=""):
    path = tmp_path / "team.toml"
    path.write_text(
        f'run = "{run}-{os.getpid()}"\nrobots = {robots}\ntasks = {tasks}\n'
        f'costs = "private"\ntopology = "ring"\nround_timeout = 20.0\n{extra}'
    )
    return path


def optimum(rows, maximize=False):
    """The team's problem (every robot does one task, every task gets a robot: the paper's
    Case 2 when there are more robots than tasks) by scipy: the tasks, plus one column per
    surplus robot in which each robot pays its best task."""
    bad = -np.inf if maximize else np.inf
    cost = np.array([[bad if c is None else c for c in row] for row in rows], dtype=float)
    n, m = cost.shape
    best = cost.max(axis=1) if maximize else cost.min(axis=1)
    square = np.hstack([cost, np.repeat(best[:, None], n - m, axis=1)])
    r, c = scipy_lsap(square, maximize=maximize)
    return float(square[r, c].sum())


def run_team(team, robots, script):
    """Every robot's member in its own thread: `script(member, robot)` returns its answers."""
    answers = [None] * robots
    errors = []

    def robot(i):
        try:
            with admm_ta.TeamMember(team, i) as member:
                answers[i] = script(member, i)
        except Exception as error:  # reported below
            errors.append((i, error))

    threads = [threading.Thread(target=robot, args=(i,)) for i in range(robots)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    assert not any(t.is_alive() for t in threads), "a member hung"
    assert not errors, errors
    return answers


METHODS = ["primal", "dual", "inexact-dual"]


@pytest.mark.parametrize("method", METHODS)
def test_every_episode_is_the_optimum_of_the_stacked_rows(tmp_path, method):
    n, m = 6, 4
    team = team_file(tmp_path, f"pyteam{method[:2]}", n, m, f'method = "{method}"\n')
    rng = np.random.default_rng(5)
    episodes = [rng.random((n, m)).tolist() for _ in range(3)]
    ints = rng.integers(0, 3, (n, m)).astype(float).tolist()
    ints[0][1] = None
    ints[3][2] = float("inf")
    episodes.append(ints)

    def script(member, i):
        assert (member.robot, member.robots, member.tasks) == (i, n, m)
        out = []
        for rows in episodes:
            if i == 2:
                with pytest.raises(ValueError, match="costs"):
                    member.assign([1.0] * (m + 1))
            out.append(member.assign(rows[i]))
        return out

    answers = run_team(team, n, script)
    for e, rows in enumerate(episodes):
        best = optimum(rows)
        views = [answers[i][e] for i in range(n)]
        assert all(a["certified"] for a in views), views[0]
        assert len({str(a["assignment"]) for a in views}) == 1
        assert views[0]["total_cost"] == pytest.approx(best)
        assert [a["task"] for a in views] == views[0]["assignment"]


@pytest.mark.parametrize("method", METHODS)
def test_an_unavailable_robot_relays(tmp_path, method):
    n, m = 5, 4
    extra = f'maximize = true\nmethod = "{method}"\n'
    team = team_file(tmp_path, f"pyrelay{method[:2]}", n, m, extra)
    rows = np.random.default_rng(9).random((n, m)).tolist()

    def script(member, i):
        return member.unavailable() if i == 1 else member.assign(rows[i])

    answers = run_team(team, n, script)
    taking = [rows[i] for i in range(n) if i != 1]
    for a in answers:
        assert a["unavailable"] == [1] and a["certified"]
        assert a["total_cost"] == pytest.approx(optimum(taking, maximize=True))
    assert answers[1]["task"] is None and answers[0]["assignment"][1] is None


def test_a_team_file_that_is_not_private_is_refused(tmp_path):
    path = tmp_path / "plain.toml"
    path.write_text('run = "pyplain"\nrobots = 4\ncosts = "random"\ntasks = 4\n')
    with pytest.raises(ValueError, match="private"):
        admm_ta.TeamMember(path, 0)
    with pytest.raises(ValueError, match="nan"):
        admm_ta._team._row([1.0, float("nan")])
    assert admm_ta._team._row([1, float("inf")]) == [1.0, None]
    assert admm_ta._team._row([1, float("-inf")], maximize=True) == [1.0, None]
    with pytest.raises(ValueError, match="-inf"):
        admm_ta._team._row([1, float("-inf")])
