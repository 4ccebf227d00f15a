"""A robot of a standing team whose robots keep their own costs (a team file with
``costs = "private"``; see the guide's docs/standing-teams.md)."""

from __future__ import annotations

import json
import math

from . import _core
from ._core import LeaveRefused

TYPE_CHECKING = False

if TYPE_CHECKING:
    from os import PathLike
    from typing import Any, Dict, Iterable, List, Optional, Union


def _row(costs: Iterable[Optional[float]], maximize: bool = False) -> List[Optional[float]]:
    """``None`` and ``inf`` (``-inf`` with ``maximize``, as scipy) mark a task this robot
    may not take."""
    forbidden = -math.inf if maximize else math.inf
    row: List[Optional[float]] = []
    for k, cost in enumerate(costs):
        if cost is None:
            row.append(None)
            continue
        value = float(cost)
        if value == forbidden:
            row.append(None)
        elif not math.isfinite(value):
            raise ValueError(
                f"cost {k} is {value}: give a number (None or {forbidden} for a forbidden task)"
            )
        else:
            row.append(value)
    return row


class TeamMember:
    """One robot of a standing team: it joins once, then gives its own cost row episode
    after episode and gets its task back. No process of the team ever sees another robot's
    costs.

    ``TeamMember(team, robot)`` joins the team of the team file ``team`` as robot ``robot``:
    it starts the team with the others (waiting for them until the file's
    ``startup_timeout``), or, the team running without it (a free slot, or its robot left
    or crashed earlier), asks to join and is admitted at the next episode boundary. Each call
    runs one episode with every other robot of the team and returns this robot's answer, a
    ``dict``: ``episode``, ``task`` (``None``: nothing solved, see ``unsolved``),
    ``certified``, ``rounds``, ``cost``, ``total_cost``, ``assignment``, ``feasible``, and
    when it applies ``missing``, ``unavailable``, ``left``, ``leave_refused``, ``lost``,
    ``joined`` and ``crashed`` (the robots concerned). A row that cannot be used raises
    ``ValueError`` (the team never sees it); a team that failed raises ``RuntimeError``;
    Ctrl-C stops the whole team and raises ``KeyboardInterrupt``. Used as a context manager
    it leaves the team on exit.

    >>> import admm_ta                                             # doctest: +SKIP
    >>> with admm_ta.TeamMember("fleet.toml", 2) as me:            # doctest: +SKIP
    ...     answer = me.assign([3.0, 1.0, None, 7.5])
    ...     answer["task"], answer["certified"]
    (1, True)
    """

    def __init__(self, team: Union[str, PathLike[str]], robot: int) -> None:
        self._member = _core.TeamMember(team, robot)

    @property
    def robot(self) -> int:
        """This robot's number."""
        return self._member.robot

    @property
    def robots(self) -> int:
        """The team's robots (its slots: who takes part changes)."""
        return self._member.robots

    @property
    def tasks(self) -> int:
        """The most costs a row may have (the team's declared tasks)."""
        return self._member.tasks

    @property
    def episode(self) -> int:
        """The episode this robot answers next."""
        return self._member.episode

    @property
    def roster(self) -> List[int]:
        """The robots that take part now."""
        return self._member.roster

    def assign(self, costs: Iterable[Optional[float]]) -> Dict[str, Any]:
        """One episode with this robot's costs, one per task of the episode (``None``, or
        ``inf`` (``-inf`` with ``maximize``): a task it may not take)."""
        row = _row(costs, self._member.maximize)
        answer: Dict[str, Any] = json.loads(self._member.assign(row))
        return answer

    def unavailable(self) -> Dict[str, Any]:
        """One episode in which this robot takes no task: it relays for its neighbours."""
        answer: Dict[str, Any] = json.loads(self._member.unavailable())
        return answer

    def abstain(self) -> Dict[str, Any]:
        """One episode without this robot's row (as if its costs came too late)."""
        answer: Dict[str, Any] = json.loads(self._member.abstain())
        return answer

    def leave(self) -> None:
        """Leaves the team: this robot relays in one more episode, in which the others
        learn it (their answers name it in ``left``), and the team goes on without it. When
        the others would fall apart without it, raises :class:`LeaveRefused` and the robot
        stays: ask again later (each call is an episode in which it relays)."""
        self._member.leave()

    def __enter__(self) -> TeamMember:
        return self

    def __exit__(self, *exc: object) -> None:
        # A failed team or Ctrl-C already stopped every robot; after anything else (an
        # exception in the robot's own code) the robot leaves, so that the others go on
        # without it at once rather than after a failed episode. A refused leave is asked
        # again, relaying meanwhile, until the others can do without this robot.
        if exc[0] is None or not (
            isinstance(exc[1], (KeyboardInterrupt, RuntimeError, SystemExit))
        ):
            while True:
                try:
                    self.leave()
                    return
                except LeaveRefused:
                    continue
