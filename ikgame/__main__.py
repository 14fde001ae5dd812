"""``python -m ikgame`` and the ``ikgame`` command: the command-line interface."""

import gc
import os
import sys


def run() -> int:
    """:func:`ikgame.cli.main`, with a Ctrl-C while the command line loads reported in one line
    (exit 130) rather than as a traceback."""
    # numpy's OpenBLAS starts a pool of threads as it loads, which takes longer (about 50 ms
    # here) than the BLAS work of a run, whose matrices are a few rows of a chain's Jacobian.
    # Set before numpy is imported; a value the user gives is kept.
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    try:
        from ikgame.cli import main
    except KeyboardInterrupt:
        sys.stderr.write("interrupted: nothing was written\n")
        return 130
    code = main()
    # The command is done. At exit the interpreter would collect every module, class and
    # validator it loaded and free them one by one (about 2% of a short run); frozen, they are
    # left for the operating system to reclaim with the process. atexit handlers still run.
    gc.freeze()
    return code


if __name__ == "__main__":
    raise SystemExit(run())
