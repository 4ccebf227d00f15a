"""``python -m admm_ta`` and the ``admm-ta`` script: the admm-ta command line, the same
program as the Rust binary (``python -m admm_ta solve --robots 8 --tasks 8 --check``)."""

from __future__ import annotations

import sys


def main() -> int:
    from . import _core

    return int(_core.main(["admm-ta", *sys.argv[1:]]))


if __name__ == "__main__":
    sys.exit(main())
