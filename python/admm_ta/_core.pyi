"""Type stubs of the Rust extension module ``admm_ta._core`` (see ``python/src/lib.rs``)."""

from os import PathLike
from typing import Any, Optional, Sequence, Tuple, Union, final

import numpy as np
import numpy.typing as npt

__all__ = [
    "linear_sum_assignment",
    "solve",
    "main",
    "set_agent_command",
    "TeamMember",
    "__version__",
]
__version__: str

def linear_sum_assignment(
    cost_matrix: npt.ArrayLike, maximize: Any = False
) -> Tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]: ...
def solve(
    argv: Sequence[str],
    cost: Optional[npt.ArrayLike] = None,
    graph: Optional[Tuple[int, Sequence[Tuple[int, int]]]] = None,
) -> Tuple[int, Optional[str], str]: ...
def main(argv: Sequence[str]) -> int: ...
def set_agent_command(program: Union[str, PathLike[str]], args: Sequence[str]) -> None: ...

@final
class TeamMember:
    def __new__(cls, team: Union[str, PathLike[str]], robot: int) -> TeamMember: ...
    def assign(self, costs: Sequence[Optional[float]]) -> str: ...
    def unavailable(self) -> str: ...
    def abstain(self) -> str: ...
    def leave(self) -> None: ...
    @property
    def robot(self) -> int: ...
    @property
    def robots(self) -> int: ...
    @property
    def tasks(self) -> int: ...
    @property
    def maximize(self) -> bool: ...
