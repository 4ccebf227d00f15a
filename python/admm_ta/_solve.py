"""The decentralized solve: `admm_ta.solve`'s keyword arguments as the library's solve request
(the options of ``admm-ta solve``, by name), its report as a :class:`SolveResult`."""

from __future__ import annotations

import os
# `typing` costs an agent process (which imports this package) several ms: annotations
# only, as mypy reads them.
TYPE_CHECKING = False

from . import _core
from ._errors import NotCertifiedError, NotOptimalError, SolveError
from ._result import SolveResult

if TYPE_CHECKING:
    from typing import Any, Dict, Iterable, List, Optional, Sequence, Tuple, Union


def _rows(cost: Any) -> Optional[int]:
    """The number of rows of an array-like, when it tells."""
    shape = getattr(cost, "shape", None)
    try:
        return int(shape[0]) if shape is not None and len(shape) > 0 else len(cost)
    except TypeError:
        return None


def _graph(topology: Any, robots: Optional[int]) -> Tuple[int, List[Tuple[int, int]]]:
    """A graph object (networkx-like: ``nodes()`` and ``edges()``) or an edge list, as
    ``(robots, edges)`` on robots ``0..n``. A graph's nodes are its robots in the order
    ``nodes()`` lists them (integers ``0..n-1`` are themselves); an edge list's robots are
    the cost matrix's rows. Both directions of an edge are one edge."""
    if hasattr(topology, "edges") and hasattr(topology, "nodes"):
        nodes = list(topology.nodes())
        if all(isinstance(v, int) for v in nodes) and set(nodes) == set(range(len(nodes))):
            index = {v: v for v in nodes}
        else:
            index = {v: k for k, v in enumerate(nodes)}
        pairs: Iterable[Any] = ((index[a], index[b]) for a, b, *_ in topology.edges())
        robots = len(nodes)
    else:
        pairs = topology
    edges = set()
    for pair in pairs:
        try:
            a, b = pair
            a, b = int(a), int(b)
        except (TypeError, ValueError):
            raise ValueError(f"an edge is a pair of robot indices, got {pair!r}") from None
        if a < 0 or b < 0:
            raise ValueError(f"edge ({a}, {b}): robot indices start at 0")
        edges.add((min(a, b), max(a, b)))
    if robots is None:
        robots = 1 + max((b for _, b in edges), default=-1)
    return robots, sorted(edges)


def solve(
    cost: Any = None,
    *,
    topology: Union[str, Sequence[Tuple[int, int]], Any] = "complete",
    method: str = "primal",
    transport: str = "sim",
    maximize: bool = False,
    check: bool = False,
    **options: Any,
) -> SolveResult:
    """Solve the task assignment decentralized: every robot (row of ``cost``) an agent that
    talks only to its neighbours in ``topology``, as ``admm-ta solve`` does.

    Parameters
    ----------
    cost : array_like, str or os.PathLike, optional
        Robot-by-task costs as for :func:`linear_sum_assignment` (``inf`` forbidden, ``-inf``
        with ``maximize``), or the path of a cost file (CSV, as ``--costs``); ``None`` with
        ``robots=N, tasks=M`` draws random costs (``seed``, ``cost_model``).
    topology : str, list of pairs or graph
        A topology name (``complete``, ``chain``, ``ring``, ``star``, ``grid``,
        ``random:P``, ``geometric:R``) or a topology file, an edge list ``[(0, 1), ...]``
        on the rows, or a networkx-like graph (its ``nodes()`` are the rows in order).
    method : str
        ``primal``, ``dual``, ``inexact-dual``, ``cbaa``, ``market``, ``dist-hungarian``
        or ``hungarian``.
    transport : str
        ``sim`` (lockstep, one thread), ``threads``, ``shm``, ``ipc`` (one agent process
        per robot over iceoryx2 shared memory), ``uds``.
    maximize : bool
        The matrix holds profits.
    check : bool
        Compare with the centralized optimum (``result.optimal``).
    **options
        Any other option of ``admm-ta solve``, by its name with ``_`` for ``-``:
        ``seed=3``, ``rho=0.5``, ``max_iters=2000``, ``round_timeout=5``,
        ``global_barrier=True``, ``case="idle"``, ``forbidden="pairs.txt"``,
        ``dual_variant="paper"`` (Algorithm 2 as published; the default ``fast``),
        ``timeline="trace.json"`` (every agent's rounds as Chrome trace JSON, and
        ``result.critical_path``), ... ``True`` gives a flag, ``False`` or ``None`` leaves
        it out.

    Returns
    -------
    SolveResult

    Raises
    ------
    ValueError
        Bad input or options (the command line's exit codes 2 and 3: an unknown option, a
        NaN cost, an infeasible matrix, a disconnected graph, ...).
    NotCertifiedError
        The round limit ended the run before the team certified an assignment.
    NotOptimalError
        ``check=True`` found the team's assignment not optimal.
    SolveError
        An agent or the transport failed (the command line's message and exit code).
    KeyboardInterrupt
        Ctrl-C: the team was stopped, its agent processes reaped and its shared memory
        released before this is raised.

    Examples
    --------
    >>> import admm_ta
    >>> r = admm_ta.solve([[1.0, 5.0], [4.0, 2.0], [3.0, 4.0]], topology=[(0, 1), (1, 2)])
    >>> r.assignment, r.certified
    ([0, 1, 0], True)
    >>> r = admm_ta.solve(robots=6, tasks=6, seed=1, method="dual", transport="threads")
    >>> r.certified and r.round_latency_us["round"]["count"] > 0
    True
    """
    for name in ("json", "costs"):
        if name in options:
            raise ValueError(f"unexpected option '{name}': give the costs as `cost`")
    given: Dict[str, Any] = dict(options)
    given.update(method=method, transport=transport, maximize=maximize, check=check)
    matrix = None
    costs_file = None
    robots: Optional[int] = options.get("robots")
    if isinstance(cost, (str, os.PathLike)):
        costs_file = os.fspath(cost)
    elif cost is not None:
        matrix = cost
        robots = _rows(cost)
    graph = None
    if isinstance(topology, (str, os.PathLike)):
        given["topology"] = os.fspath(topology)
    else:
        graph = _graph(topology, robots)
    code, report, message = _core.solve(matrix, costs_file, graph, given)
    result = None if report is None else SolveResult(report)
    if code == 0 and result is not None:
        return result
    if code in (2, 3):
        raise ValueError(message)
    if code == 5:
        raise NotCertifiedError(message, code, result)
    if code == 6:
        raise NotOptimalError(message, code, result)
    raise SolveError(message, code, result)
