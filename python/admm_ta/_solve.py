"""The decentralized solve: ``admm-ta solve`` as a function."""

from __future__ import annotations

import os
# `typing` costs an agent process (which imports this package) several ms: annotations
# only, as mypy reads them.
TYPE_CHECKING = False

from . import _core
from ._errors import NotCertifiedError, NotOptimalError, SolveError

if TYPE_CHECKING:
    from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union


class SolveResult:
    """The report of a solve: the command line's JSON report (``to_dict()``, same fields)
    with the common fields as attributes.

    ``assignment[i]`` is robot ``i``'s task, or ``None`` for an idle robot.
    """

    __slots__ = ("_report",)

    def __init__(self, report: Mapping[str, Any]):
        self._report = dict(report)

    def to_dict(self) -> Dict[str, Any]:
        """The report as the command line's ``--json`` prints it (a copy)."""
        import json

        copy: Dict[str, Any] = json.loads(json.dumps(self._report))
        return copy

    @property
    def assignment(self) -> List[Optional[int]]:
        """Robot ``i``'s task, ``None`` for an idle robot."""
        return list(self._report["assignment"])

    @property
    def cost(self) -> float:
        """The assignment's total cost (its profit with ``maximize=True``)."""
        return float(self._report["cost"])

    @property
    def certified(self) -> bool:
        """Whether the team certified its assignment optimal (the decentralized stop)."""
        return bool(self._report["certified"])

    @property
    def converged(self) -> bool:
        """Whether the run stopped by its stop rule (not by the round limit)."""
        return bool(self._report["converged"])

    @property
    def rounds(self) -> int:
        """Rounds the team ran."""
        return int(self._report["iterations"])

    @property
    def stop(self) -> str:
        """The stop rule (``local``: the decentralized certified stop)."""
        return str(self._report["stop"])

    @property
    def method(self) -> str:
        return str(self._report["method"])

    @property
    def transport(self) -> str:
        return str(self._report["transport"])

    @property
    def bytes_per_agent(self) -> int:
        """Bytes each agent sent to finish."""
        return int(self._report["bytes_per_agent"])

    @property
    def wall_time_ms(self) -> float:
        return float(self._report["wall_time_ms"])

    @property
    def round_latency_us(self) -> Optional[Dict[str, Dict[str, float]]]:
        """Round latency percentiles in µs (``round``, ``wait``, ``compute``, ``publish``,
        ``barrier``: each with ``p50``, ``p90``, ``p99``, ``p999``, ``max``, ``mean``,
        ``count``), or ``None`` where rounds are not measured (the lockstep simulation)."""
        latency = self._report.get("round_latency_us")
        if latency is None:
            return None
        return {part: dict(values) for part, values in latency.items()}

    @property
    def critical_path(self) -> Optional[Dict[str, Any]]:
        """With ``timeline="FILE"``: whom the team waited for (``rounds``: per round the agent
        most agents waited for; ``top``: the agents most waited for and the share of round
        time spent waiting for each; ``waiting_share``); else ``None``."""
        path = self._report.get("critical_path")
        return None if path is None else dict(path)

    @property
    def optimal(self) -> Optional[bool]:
        """``check=True``: whether the centralized optimum agrees; else ``None``."""
        check = self._report.get("check")
        return None if check is None else bool(check["optimal"])

    def __repr__(self) -> str:
        return (
            f"SolveResult(assignment={self.assignment}, cost={self.cost!r}, "
            f"certified={self.certified}, rounds={self.rounds}, method={self.method!r}, "
            f"transport={self.transport!r})"
        )


def _flag(name: str, value: Any) -> List[str]:
    """``name=value`` as command-line words: ``True`` is the bare flag, ``False`` and
    ``None`` leave it out, a list or tuple is comma-joined."""
    flag = "--" + name.replace("_", "-")
    if value is None or value is False:
        return []
    if value is True:
        return [flag]
    if isinstance(value, (list, tuple)):
        return [flag, ",".join(str(v) for v in value)]
    if isinstance(value, os.PathLike):
        return [flag, os.fspath(value)]
    return [flag, str(value)]


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
    argv: List[str] = ["--json"]
    argv += _flag("method", method)
    argv += _flag("transport", transport)
    argv += _flag("maximize", maximize)
    argv += _flag("check", check)
    for name, value in options.items():
        if name in ("json", "costs"):
            raise ValueError(f"unexpected option '{name}': give the costs as `cost`")
        argv += _flag(name, value)
    matrix = None
    robots: Optional[int] = options.get("robots")
    if isinstance(cost, (str, os.PathLike)):
        argv += ["--costs", os.fspath(cost)]
    elif cost is not None:
        matrix = cost
        robots = _rows(cost)
    graph = None
    if isinstance(topology, (str, os.PathLike)):
        argv += ["--topology", os.fspath(topology)]
    else:
        graph = _graph(topology, robots)
    import json

    code, report, message = _core.solve(argv, matrix, graph)
    result = None if report is None else SolveResult(json.loads(report))
    if code == 0 and result is not None:
        return result
    if code in (2, 3):
        raise ValueError(message)
    if code == 5:
        raise NotCertifiedError(message, code, result)
    if code == 6:
        raise NotOptimalError(message, code, result)
    raise SolveError(message, code, result)
