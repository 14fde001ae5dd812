"""Colour palettes for the renderer, loaded from JSON so artists can add one without code.

A theme file maps every :class:`Theme` field to a colour, written ``"#rrggbb"`` or
``[r, g, b]``; ``name`` and ``description`` keys are allowed and ignored. Shipped themes live in
``assets/themes/<name>.json``.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, fields
from pathlib import Path

import ikgame

__all__ = ["RGB", "Theme", "available_themes", "load_theme", "THEMES_DIR"]

RGB = tuple[int, int, int]

# The repo is installed editable, so assets sit beside the package rather than inside it.
THEMES_DIR = Path(ikgame.__file__).resolve().parent.parent / "assets" / "themes"
# Keys a theme file may carry besides colours: documentation for whoever edits it.
_INFO_KEYS = frozenset({"name", "description"})


@dataclass(frozen=True)
class Theme:
    """The renderer's colours, each an ``(r, g, b)`` tuple of 0..255 ints.

    >>> load_theme("light").background
    (246, 242, 233)
    """

    background: RGB
    grid: RGB
    obstacle: RGB
    obstacle_outline: RGB
    goal: RGB
    prop: RGB
    prop_outline: RGB
    link: RGB
    link_outline: RGB
    torque_limited: RGB
    joint: RGB
    base: RGB
    target: RGB
    target_upcoming: RGB
    trail: RGB
    effector: RGB
    hud_text: RGB
    hud_muted: RGB
    hud_panel: RGB
    success: RGB
    failure: RGB

    def colors(self) -> list[RGB]:
        """Every colour of the theme, in field order.

        >>> len(load_theme("dark").colors())
        21
        """
        return [getattr(self, f.name) for f in fields(self)]


def available_themes() -> list[str]:
    """Names of the shipped themes, sorted.

    >>> available_themes()
    ['dark', 'light']
    """
    return sorted(path.stem for path in THEMES_DIR.glob("*.json"))


def load_theme(name_or_path: str | os.PathLike[str]) -> Theme:
    """Load a shipped theme by name (``"light"``) or any theme JSON file by path.

    >>> load_theme("dark").link
    (90, 169, 255)
    """
    text = os.fspath(name_or_path)
    looks_like_path = (
        isinstance(name_or_path, os.PathLike)
        or text.endswith(".json")
        or (os.sep in text or "/" in text)
    )
    if looks_like_path:
        path = Path(text)
        if not path.is_file():
            raise ValueError(f"theme file not found: {path}")
    else:
        path = THEMES_DIR / f"{text}.json"
        if not path.is_file():
            names = ", ".join(available_themes())
            raise ValueError(f"unknown theme {text!r}; available: {names}")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"theme {path}: cannot read JSON: {exc}") from exc
    return _theme_from_dict(data, path)


def _theme_from_dict(data: object, path: Path) -> Theme:
    if not isinstance(data, dict):
        raise ValueError(f"theme {path}: expected a JSON object of colours")
    names = [f.name for f in fields(Theme)]
    unknown = sorted(set(data) - set(names) - _INFO_KEYS)
    if unknown:
        raise ValueError(f"theme {path}: unknown keys {unknown}; expected {names}")
    missing = [name for name in names if name not in data]
    if missing:
        raise ValueError(f"theme {path}: missing colours {missing}")
    return Theme(**{name: _parse_color(data[name], f"theme {path}: {name}") for name in names})


def _parse_color(value: object, where: str) -> RGB:
    if isinstance(value, str) and len(value) == 7 and value.startswith("#"):
        try:
            return (int(value[1:3], 16), int(value[3:5], 16), int(value[5:7], 16))
        except ValueError:
            pass
    elif (
        isinstance(value, list)
        and len(value) == 3
        and all(isinstance(c, int) and not isinstance(c, bool) and 0 <= c <= 255 for c in value)
    ):
        return (value[0], value[1], value[2])
    raise ValueError(f"{where}: expected '#rrggbb' or [r, g, b] with 0..255 ints, got {value!r}")
