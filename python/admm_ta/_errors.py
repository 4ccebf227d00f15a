"""The package's exceptions: a solve that ran and failed, or ended without the certificate.

Bad input (a malformed matrix, an unknown option, an infeasible problem, a disconnected
graph) raises :class:`ValueError`, as scipy does; Ctrl-C raises :class:`KeyboardInterrupt`.
"""

from __future__ import annotations

# `typing` costs an agent process (which imports this package) several ms: annotations
# only, as mypy reads them.
TYPE_CHECKING = False

if TYPE_CHECKING:
    from typing import Optional

    from ._result import SolveResult


class SolveError(RuntimeError):
    """A solve that failed: an agent or the transport failed, or (the subclasses) the
    team's answer is not the certified optimum.

    ``str(error)`` is the command line's message; ``exit_code`` its exit code (see the
    guide's docs/command-line.md); ``result`` the report when the team produced one.
    """

    def __init__(self, message: str, exit_code: int, result: Optional[SolveResult] = None):
        super().__init__(message)
        self.exit_code = exit_code
        self.result = result


class NotCertifiedError(SolveError):
    """The round limit ended the run before the team certified an assignment (exit code 5).

    ``result`` holds the best assignment found when the run stopped.
    """


class NotOptimalError(SolveError):
    """``check=True``: the centralized optimum is better than the team's answer (exit code
    6). ``result`` holds the team's answer and the check.
    """
