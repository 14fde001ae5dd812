"""``python -m ikgame`` and the ``ikgame`` command: the command-line interface."""

import sys


def run() -> int:
    """:func:`ikgame.cli.main`, with a Ctrl-C while the command line loads reported in one line
    (exit 130) rather than as a traceback."""
    try:
        from ikgame.cli import main
    except KeyboardInterrupt:
        sys.stderr.write("interrupted: nothing was written\n")
        return 130
    return main()


if __name__ == "__main__":
    raise SystemExit(run())
