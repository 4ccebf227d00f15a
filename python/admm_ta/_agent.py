"""One agent process of a team this package launched (``python -m admm_ta._agent agent
--run ... --index I --scenario FILE``): the command line's ``agent`` subcommand. Not for
direct use; the package starts these."""

import sys

if __name__ == "__main__":
    from admm_ta import _core

    sys.exit(_core.main(["admm-ta", *sys.argv[1:]]))
