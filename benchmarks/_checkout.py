"""Imported first by the benchmark scripts, so that they measure the ikgame of the checkout they
live in, not whichever one is installed (``pip install -e`` of another worktree, say): run from
``benchmarks/``, Python puts this folder on the path, not the checkout's root."""

import sys
from pathlib import Path

_ROOT = str(Path(__file__).resolve().parents[1])
if sys.path[:1] != [_ROOT]:
    sys.path.insert(0, _ROOT)
