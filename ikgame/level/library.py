"""Where the shipped levels and assets live, and which level runs by default."""

from __future__ import annotations

from pathlib import Path
from typing import Final

from ikgame import _shipped

__all__ = [
    "LEVELS_DIR",
    "ASSETS_DIR",
    "THEMES_DIR",
    "SCHEMA_FILE",
    "DEFAULT_LEVEL",
    "shipped_levels",
    "resolve_level",
]

LEVELS_DIR: Final = _shipped.LEVELS_DIR
"""The shipped levels, numbered in learning order."""
ASSETS_DIR: Final = _shipped.ASSETS_DIR
"""Themes, the level JSON Schema, sprites."""
THEMES_DIR: Final = _shipped.THEMES_DIR
"""Shipped colour themes, one ``<name>.json`` each."""
SCHEMA_FILE: Final = ASSETS_DIR / "level.schema.json"
"""The level format's JSON Schema, for editors (kept equal to ``level_schema()`` by a test)."""
DEFAULT_LEVEL: Final = LEVELS_DIR / "01_first_reach.toml"
"""What ``ikgame run`` plays without a level argument."""


def shipped_levels() -> list[Path]:
    """The shipped level files, in learning order.

    >>> shipped_levels()[0].name
    '01_first_reach.toml'
    """
    return sorted(LEVELS_DIR.glob("*.toml"))


def resolve_level(name: str | Path | None) -> Path:
    """A level path from a path, a shipped level's file name or stem (``02_tentacle``), or None
    for the default level.

    >>> resolve_level("01_first_reach") == DEFAULT_LEVEL
    True
    """
    if name is None:
        return DEFAULT_LEVEL
    path = Path(name)
    if path.exists() or path.suffix == ".toml" and len(path.parts) > 1:
        return path
    for candidate in (LEVELS_DIR / path, LEVELS_DIR / f"{path}.toml"):
        if candidate.is_file():
            return candidate
    matches = [p for p in shipped_levels() if p.stem.split("_", 1)[-1] == str(path)]
    return matches[0] if len(matches) == 1 else path
