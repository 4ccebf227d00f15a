"""admm_ta.linear_sum_assignment against scipy.optimize.linear_sum_assignment: the same
assignment (indices, not only the cost: the same algorithm breaks ties the same way), the
same exceptions with the same messages, on random and edge-case matrices."""

import threading

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment as scipy_lsap

import admm_ta

INF = np.inf


def outcome(f, *args, **kwargs):
    """The result, or the exception's type and message."""
    try:
        rows, cols = f(*args, **kwargs)
    except Exception as e:  # noqa: BLE001 - the type is compared
        return (type(e), str(e))
    return (rows.dtype, rows.tolist(), cols.dtype, cols.tolist())


def assert_same(cost, **kwargs):
    expected = outcome(scipy_lsap, cost, **kwargs)
    got = outcome(admm_ta.linear_sum_assignment, cost, **kwargs)
    assert got == expected, f"cost={cost!r} {kwargs}"


def random_matrices(seed, count):
    """Square, wide and tall; uniform, integer (tie-heavy), forbidden pairs; minimising
    and maximising."""
    rng = np.random.default_rng(seed)
    for k in range(count):
        rows, cols = (int(x) for x in rng.integers(1, 12, size=2))
        kind = k % 5
        if kind == 0:
            cost = rng.random((rows, cols))
        elif kind == 1:
            cost = rng.integers(0, 3, size=(rows, cols)).astype(float)
        elif kind == 2:
            cost = rng.integers(-5, 6, size=(rows, cols)).astype(np.int64)
        elif kind == 3:
            cost = rng.normal(size=(rows, cols)) * 1e6
        else:
            cost = rng.integers(0, 4, size=(rows, cols)).astype(float)
            cost[rng.random((rows, cols)) < 0.4] = INF
        maximize = bool(k % 2)
        if maximize and cost.dtype == float:
            cost = np.where(cost == INF, -INF, cost)
        yield cost, maximize


@pytest.mark.parametrize("seed", range(8))
def test_random_matrices_give_scipy_s_assignment(seed):
    for cost, maximize in random_matrices(seed, 400):
        assert_same(cost, maximize=maximize)


def test_a_large_square_and_rectangles():
    rng = np.random.default_rng(42)
    for shape in [(200, 200), (150, 300), (300, 150), (400, 401)]:
        cost = rng.random(shape)
        assert_same(cost)
        integer = rng.integers(0, 10, size=shape)
        assert_same(integer)
        assert_same(integer, maximize=True)


def test_tie_heavy_matrices():
    for n in range(1, 9):
        assert_same(np.ones((n, n)))
        assert_same(np.zeros((n, n + 2)))
        assert_same(np.eye(n))
        assert_same(np.eye(n), maximize=True)
        assert_same(np.arange(n * n).reshape(n, n) % 3)


@pytest.mark.parametrize(
    "cost",
    [
        np.zeros((0, 0)),
        np.zeros((0, 3)),
        np.zeros((3, 0)),
        [[]],
        [],
        [[5]],
        [[1, 2], [3, 4]],
        [[True, False], [False, True]],
        np.eye(3, dtype=np.float32),
        np.eye(3, dtype=np.int8),
        np.eye(3, dtype=np.uint64),
        np.eye(3, dtype=np.float16),
        np.asfortranarray(np.arange(12.0).reshape(3, 4)),
        np.arange(24.0).reshape(4, 6)[:, ::2],
        np.arange(9.0).reshape(3, 3)[::-1],
        ((1, 2), (3, 4)),
        [["1.5", "2"], ["3", "0"]],
        [[np.nan]],
        [[1, np.nan], [2, 3]],
        [[-INF, 1], [1, 2]],
        [[INF]],
        [[INF, 1], [INF, 2]],
        [[1, INF], [INF, 1]],
        [[10, INF, INF], [INF, INF, 1], [INF, 7, INF]],
        np.zeros((2, 2, 2)),
        [1, 2, 3],
        5,
        [["a"]],
        [[1 + 1j]],
        np.array([[1 + 1j]]),
        [[1, 2], [3]],
        np.array([[1.0]], dtype=object),
        [[None]],
        np.array([["2020-01-01"]], dtype="datetime64[D]"),
        np.array([[1.0]], dtype=np.longdouble),
        [[1e308, 1e308], [1e308, 1e308]],
        [[-1e308, 0], [0, 1e308]],
    ],
    ids=repr,
)
@pytest.mark.parametrize("maximize", [False, True])
def test_edge_cases_and_bad_input_as_scipy(cost, maximize):
    assert_same(cost, maximize=maximize)


def test_maximize_takes_any_truth_value_and_keywords():
    cost = [[1, 2], [3, 5]]
    for value in ["yes", [], [0], 0, 1, None, np.bool_(True)]:
        assert_same(cost, maximize=value)
    assert outcome(admm_ta.linear_sum_assignment, cost_matrix=cost) == outcome(
        scipy_lsap, cost_matrix=cost
    )
    with pytest.raises(TypeError):
        admm_ta.linear_sum_assignment()
    with pytest.raises(TypeError):
        admm_ta.linear_sum_assignment(cost, False, 3)


@pytest.mark.filterwarnings("ignore::PendingDeprecationWarning")
def test_array_likes():
    class ArrayLike:
        def __array__(self, dtype=None, copy=None):
            return np.array([[3, 1], [1, 3]])

    assert_same(ArrayLike())
    assert_same(np.matrix([[3.0, 1.0], [1.0, 3.0]]))


def test_the_input_is_not_modified():
    cost = np.array([[4.0, 1.0], [2.0, INF], [3.0, 2.0]])
    before = cost.copy()
    admm_ta.linear_sum_assignment(cost, maximize=False)
    admm_ta.linear_sum_assignment(-cost, maximize=True)
    np.testing.assert_array_equal(cost, before)


def test_the_interpreter_is_released_while_a_large_matrix_is_solved():
    """Another Python thread runs while a solve is in progress."""
    cost = np.random.default_rng(0).random((700, 700))
    ticks = []
    done = threading.Event()

    def tick():
        while not done.is_set():
            ticks.append(1)
            done.wait(0.001)

    thread = threading.Thread(target=tick)
    thread.start()
    try:
        before = len(ticks)
        admm_ta.linear_sum_assignment(cost)
        during = len(ticks) - before
    finally:
        done.set()
        thread.join()
    assert during > 2, during


def test_concurrent_calls_from_threads_agree():
    rng = np.random.default_rng(5)
    costs = [rng.random((60, 80)) for _ in range(8)]
    expected = [scipy_lsap(c) for c in costs]
    results = [None] * len(costs)

    def run(k):
        for _ in range(5):
            results[k] = admm_ta.linear_sum_assignment(costs[k])

    threads = [threading.Thread(target=run, args=(k,)) for k in range(len(costs))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for (er, ec), (gr, gc) in zip(expected, results):
        np.testing.assert_array_equal(er, gr)
        np.testing.assert_array_equal(ec, gc)
