"""Package re-exports that import their module on first use.

A package ``__init__`` that imported every submodule would make ``ikgame --version`` pay for
numpy, pymunk, pydantic and Pillow; with these, each command loads only the modules it uses.
Each package still lists its public names in ``__all__`` and, for type checkers, imports them
under ``TYPE_CHECKING``.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping, Sequence

__all__ = ["lazy_exports"]


def lazy_exports(
    package: str, modules: Mapping[str, Sequence[str]]
) -> tuple[list[str], Callable[[str], object], Callable[[], list[str]]]:
    """``__all__``, ``__getattr__`` and ``__dir__`` for ``package``, re-exporting the names
    listed per module in ``modules``; each module is imported when one of its names is first read.

    >>> all_, getattr_, dir_ = lazy_exports("ikgame", {"ikgame.level.library": ["DEFAULT_LEVEL"]})
    >>> all_, getattr_("DEFAULT_LEVEL").name
    (['DEFAULT_LEVEL'], '01_first_reach.toml')
    """
    home = {name: module for module, names in modules.items() for name in names}

    def __getattr__(name: str) -> object:
        module = home.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        # Cached on the package, so later reads are plain attribute lookups.
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(home))

    return sorted(home), __getattr__, __dir__
