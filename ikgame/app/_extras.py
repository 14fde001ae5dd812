"""Optional dependencies, imported when a command needs them, with the install command when not."""

from __future__ import annotations

import importlib
import os
from types import ModuleType

__all__ = ["MissingExtra", "require"]


class MissingExtra(ImportError):
    """An optional dependency is not installed; the message says how to install it."""


def require(module: str, extra: str, purpose: str) -> ModuleType:
    """Import ``module`` from the optional extra ``extra``, or raise :class:`MissingExtra`
    saying that ``purpose`` needs it and how to install it.

    >>> require("json", "play", "the window").__name__
    'json'
    """
    # pygame greets on import; a command line tool's output is not the place for it.
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    try:
        return importlib.import_module(module)
    except ImportError:
        raise MissingExtra(
            f"{purpose} needs {module}, which is not installed; install the '{extra}' extra: "
            f"python -m pip install 'ikgame[{extra}]'"
        ) from None
