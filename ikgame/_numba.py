"""numba, where it is installed (the ``fast`` extra), for ikgame's optional compiled loops.

Each compiled loop is the same operations in the same order as the Python it stands in for, so
a run gives the same results with numba or without it; what differs is only whether numba is
there and can compile. ``IKGAME_COMPILED=0`` in the environment turns the loops off
(:func:`turned_off`: each caller asks, since each also has a size below which compiling does
not pay, and its kernels are built once for the process).
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from types import ModuleType
from typing import TypeVar

__all__ = ["compiled", "turned_off"]

T = TypeVar("T")


def turned_off() -> bool:
    """True when ``IKGAME_COMPILED=0`` is set in the environment: every loop runs in Python."""
    return os.environ.get("IKGAME_COMPILED") == "0"


def compiled(what: str, build: Callable[[ModuleType], T]) -> T | None:
    """``build(numba)``: the kernels it compiles (and runs once, so that a numba that cannot
    compile them is found before a run needs them), or None without numba, or where numba
    fails, with a warning that ``what`` runs in Python.

    >>> compiled("nothing", lambda numba: numba.__name__) in (None, "numba")
    True
    """
    try:
        import numba
    except ImportError:
        return None
    try:
        return build(numba)
    except Exception as exc:  # noqa: BLE001 - an optional speed-up must never stop a run
        warnings.warn(
            f"numba could not compile {what}, which runs in Python: {exc}",
            RuntimeWarning,
            stacklevel=3,
        )
        return None
