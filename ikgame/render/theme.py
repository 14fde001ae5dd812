"""Colour palettes for the renderer, loaded from JSON so artists can add one without code.

A theme file maps every :class:`Theme` field to a colour, written ``"#rrggbb"`` or
``[r, g, b]``, except ``effector_palette``: an optional list of colours, one per end effector of a
tree (default: :data:`EFFECTOR_PALETTE`). ``name`` and ``description`` keys are allowed and
ignored. Shipped themes live in ``assets/themes/<name>.json``.
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import astuple, dataclass, fields
from pathlib import Path

from ikgame._shipped import THEMES_DIR

__all__ = [
    "EFFECTOR_PALETTE",
    "RGB",
    "EffectorStyle",
    "Theme",
    "ThemeError",
    "available_themes",
    "load_theme",
    "THEMES_DIR",
]

RGB = tuple[int, int, int]

EFFECTOR_PALETTE: tuple[RGB, ...] = (
    (213, 94, 0),
    (204, 121, 167),
    (0, 158, 115),
    (230, 159, 0),
    (86, 180, 233),
    (0, 0, 0),
)
"""Okabe and Ito's colours, told apart with every common colour-vision deficiency (the green
third: the first two stay clear of a goal region's usual green): the effector colours of a theme
file that names none."""
UPCOMING_FADE = 0.45  # opacity of a tree effector's colour over the background, for its upcoming

# Keys a theme file may carry besides colours: documentation for whoever edits it.
_INFO_KEYS = frozenset({"name", "description"})
MAX_THEME_BYTES = 1_000_000
"""A theme is a few hundred bytes."""


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
    effector_palette: tuple[RGB, ...] = EFFECTOR_PALETTE

    def __post_init__(self) -> None:
        if not self.effector_palette:
            raise ValueError("effector_palette needs at least one colour")

    def colors(self) -> list[RGB]:
        """Every single colour of the theme, in field order (not the effector palette: see
        :meth:`effector_styles`).

        >>> len(load_theme("dark").colors())
        21
        """
        return [getattr(self, name) for name in _COLOUR_NAMES]

    def effector_styles(self, count: int) -> tuple[EffectorStyle, ...]:
        """The colours of ``count`` end effectors. A lone effector (a chain's tip) keeps the
        theme's ``target``, ``trail``, ``effector`` and ``target_upcoming``; several take one
        palette colour each (in turn, if there are more effectors than colours) for their
        marker, trail and tip alike, so each effector's things read as one.

        >>> light = load_theme("light")
        >>> light.effector_styles(1)[0].target == light.target
        True
        >>> [s.target for s in light.effector_styles(2)] == list(light.effector_palette[:2])
        True
        """
        if count == 1:
            return (EffectorStyle(self.target, self.trail, self.effector, self.target_upcoming),)
        styles = []
        for j in range(count):
            color = self.effector_palette[j % len(self.effector_palette)]
            faded = tuple(
                round(b + (c - b) * UPCOMING_FADE)
                for b, c in zip(self.background, color, strict=True)
            )
            styles.append(EffectorStyle(color, color, color, faded))  # type: ignore[arg-type]
        return tuple(styles)


@dataclass(frozen=True)
class EffectorStyle:
    """The colours of one end effector: its target marker, its trail, the dot on its tip, and
    its upcoming targets."""

    target: RGB
    trail: RGB
    tip: RGB
    upcoming: RGB

    def colors(self) -> list[RGB]:
        """The four colours, in field order."""
        return list(astuple(self))


_COLOUR_NAMES = tuple(f.name for f in fields(Theme) if f.name != "effector_palette")


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
            raise ThemeError(path, None, "", "theme file not found")
    else:
        path = THEMES_DIR / f"{text}.json"
        if not path.is_file():
            names = ", ".join(available_themes())
            raise ValueError(f"unknown theme {text!r}; available: {names}")
    try:
        with path.open("rb") as handle:
            raw = handle.read(MAX_THEME_BYTES + 1)
    except OSError as exc:
        raise ThemeError(path, None, "", f"cannot be read ({exc.strerror})") from None
    if len(raw) > MAX_THEME_BYTES:
        raise ThemeError(path, None, "", f"larger than {MAX_THEME_BYTES} bytes")
    try:
        source = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise ThemeError(path, line, "", f"not UTF-8 text ({exc.reason})") from None
    try:
        data = json.loads(source)
    except json.JSONDecodeError as exc:
        raise ThemeError(path, exc.lineno, "", f"cannot read JSON: {exc.msg}") from None
    except RecursionError:
        raise ThemeError(path, None, "", "cannot read JSON: nested too deeply") from None
    return _theme_from_dict(data, path, source)


class ThemeError(ValueError):
    """A theme file that cannot be used, with where (``file``, ``line`` or None, ``field``)
    and what is wrong (``reason``).

    >>> str(ThemeError(Path("t.json"), 3, "link", "expected a colour"))
    't.json:3: link: expected a colour'
    """

    def __init__(self, file: Path, line: int | None, field: str, reason: str) -> None:
        self.file, self.line, self.field, self.reason = file, line, field, reason
        where = str(file) if line is None else f"{file}:{line}"
        super().__init__(f"{where}: {field}: {reason}" if field else f"{where}: {reason}")


def _theme_from_dict(data: object, path: Path, source: str) -> Theme:
    if not isinstance(data, dict):
        raise ThemeError(path, 1, "", "expected a JSON object of colours")
    names = list(_COLOUR_NAMES)
    unknown = sorted(set(data) - set(names) - {"effector_palette"} - _INFO_KEYS)
    if unknown:
        raise ThemeError(
            path,
            _key_line(source, unknown[0]),
            unknown[0],
            f"unknown keys {unknown}; expected {names}",
        )
    missing = [name for name in names if name not in data]
    if missing:
        raise ThemeError(path, None, "", f"missing colours {missing}")
    colours = {}
    for name in names:
        try:
            colours[name] = _parse_color(data[name])
        except ValueError as exc:
            raise ThemeError(path, _key_line(source, name), name, str(exc)) from None
    palette = EFFECTOR_PALETTE
    if "effector_palette" in data:
        line = _key_line(source, "effector_palette")
        value = data["effector_palette"]
        if not isinstance(value, list) or not value:
            raise ThemeError(path, line, "effector_palette", "expected a non-empty list of colours")
        try:
            palette = tuple(_parse_color(c) for c in value)
        except ValueError as exc:
            raise ThemeError(path, line, "effector_palette", str(exc)) from None
    return Theme(**colours, effector_palette=palette)


def _key_line(source: str, key: str) -> int | None:
    """The line of ``"key":`` in the JSON text, or None."""
    match = re.search(rf'"{re.escape(key)}"\s*:', source)
    return None if match is None else source.count("\n", 0, match.start()) + 1


def _parse_color(value: object) -> RGB:
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
    shown = repr(value) if len(repr(value)) <= 60 else repr(value)[:57] + "..."
    raise ValueError(f"expected '#rrggbb' or [r, g, b] with 0..255 ints, got {shown}")
