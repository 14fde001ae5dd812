"""``python -m ikgame``: the command-line interface."""

import sys

if __name__ == "__main__":
    try:
        from ikgame.cli import main
    except KeyboardInterrupt:  # Ctrl-C while numpy and pymunk load: no traceback
        sys.stderr.write("interrupted: nothing was written\n")
        raise SystemExit(130) from None
    raise SystemExit(main())
