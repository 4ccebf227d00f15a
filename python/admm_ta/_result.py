"""The report of a decentralized solve, as Python reads it."""

from __future__ import annotations

# `typing` costs an agent process (which imports this package) several ms: annotations
# only, as mypy reads them.
TYPE_CHECKING = False

if TYPE_CHECKING:
    from typing import Any, Dict, List, Optional

    from ._core import Report


class SolveResult:
    """The report of a solve: the library's report, its common fields as attributes and
    the whole of it as the command line's ``--json`` prints it (``to_dict()``, same fields).

    ``assignment[i]`` is robot ``i``'s task, or ``None`` for an idle robot.
    """

    __slots__ = ("_report",)

    def __init__(self, report: Report):
        self._report = report

    def to_dict(self) -> Dict[str, Any]:
        """The report as the command line's ``--json`` prints it (a new copy each call)."""
        return self._report.to_dict()

    @property
    def assignment(self) -> List[Optional[int]]:
        """Robot ``i``'s task, ``None`` for an idle robot."""
        return self._report.assignment

    @property
    def cost(self) -> float:
        """The assignment's total cost (its profit with ``maximize=True``)."""
        return self._report.cost

    @property
    def certified(self) -> bool:
        """Whether the team certified its assignment optimal (the decentralized stop)."""
        return self._report.certified

    @property
    def converged(self) -> bool:
        """Whether the run stopped by its stop rule (not by the round limit)."""
        return self._report.converged

    @property
    def rounds(self) -> int:
        """Rounds the team ran."""
        return self._report.iterations

    @property
    def stop(self) -> str:
        """The stop rule (``local``: the decentralized certified stop)."""
        return str(self._report.stop)

    @property
    def method(self) -> str:
        return self._report.method

    @property
    def transport(self) -> str:
        return self._report.transport

    @property
    def bytes_per_agent(self) -> int:
        """Bytes each agent sent to finish."""
        return self._report.bytes_per_agent

    @property
    def wall_time_ms(self) -> float:
        return self._report.wall_time_ms

    @property
    def round_latency_us(self) -> Optional[Dict[str, Dict[str, float]]]:
        """Round latency percentiles in µs (``round``, ``wait``, ``compute``, ``publish``,
        ``barrier``: each with ``p50``, ``p90``, ``p99``, ``p999``, ``max``, ``mean``,
        ``count``), or ``None`` where rounds are not measured (the lockstep simulation)."""
        latency: Optional[Dict[str, Dict[str, float]]] = self._report.round_latency_us
        return latency

    @property
    def critical_path(self) -> Optional[Dict[str, Any]]:
        """With ``timeline="FILE"``: whom the team waited for (``rounds``: per round the agent
        most agents waited for; ``top``: the agents most waited for and the share of round
        time spent waiting for each; ``waiting_share``); else ``None``."""
        path: Optional[Dict[str, Any]] = self._report.critical_path
        return path

    @property
    def optimal(self) -> Optional[bool]:
        """``check=True``: whether the centralized optimum agrees; else ``None``."""
        return self._report.optimal

    def __repr__(self) -> str:
        return (
            f"SolveResult(assignment={self.assignment}, cost={self.cost!r}, "
            f"certified={self.certified}, rounds={self.rounds}, method={self.method!r}, "
            f"transport={self.transport!r})"
        )
