"""``python -m ikgame``: the command-line interface."""

from ikgame.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
