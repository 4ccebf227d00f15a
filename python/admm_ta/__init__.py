"""Decentralized task assignment for robot teams by consensus ADMM.

Two calls:

* :func:`linear_sum_assignment` — scipy's ``scipy.optimize.linear_sum_assignment`` (same
  arguments, results, exceptions and tie-breaking), centralized, on the project's exact
  shortest-augmenting-path solver, with the interpreter released while it runs.
* :func:`solve` — the decentralized solve of the ``admm-ta solve`` command line: every
  robot an agent that talks only to its neighbours (in this process, in threads, or as
  agent processes over iceoryx2 shared memory), with every option the command line has.
* :class:`TeamMember` — one robot of a standing team whose robots keep their own costs:
  join once, then ``assign(my_costs)`` episode after episode.

>>> import admm_ta
>>> admm_ta.linear_sum_assignment([[4, 1, 3], [2, 0, 5], [3, 2, 2]])
(array([0, 1, 2]), array([1, 0, 2]))
>>> result = admm_ta.solve([[4, 1, 3], [2, 0, 5], [3, 2, 2]], topology="chain", check=True)
>>> result.assignment, result.cost, result.certified
([1, 0, 2], 5.0, True)
"""

from __future__ import annotations

import sys as _sys

from . import _core
from ._core import LeaveRefused, linear_sum_assignment
from ._errors import NotCertifiedError, NotOptimalError, SolveError
from ._result import SolveResult
from ._solve import solve
from ._team import TeamMember

__all__ = [
    "linear_sum_assignment",
    "solve",
    "SolveResult",
    "SolveError",
    "NotCertifiedError",
    "NotOptimalError",
    "TeamMember",
    "LeaveRefused",
    "__version__",
]

__version__: str = _core.__version__

# Agent processes of a process transport run this package's command line with the same
# interpreter: nothing on PATH and no binary of the repository needed. (`-c`, not `-m`:
# an agent starts in ~15 ms, and runpy alone would add 3.)
_AGENT = "import sys; from admm_ta._core import main; sys.exit(main(['admm-ta', *sys.argv[1:]]))"
if _sys.executable:
    _core.set_agent_command(_sys.executable, ["-c", _AGENT])
