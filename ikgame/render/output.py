"""What an export may write: the frame size limits and the output folder check.

Apart from :mod:`ikgame.render.export` so that the command line checks its options before
anything is drawn, without loading Pillow (a run with ``--no-frames`` never needs it).
"""

from __future__ import annotations

import os
import re
from numbers import Integral
from pathlib import Path

__all__ = [
    "MAX_PIXELS",
    "MAX_SIDE",
    "MIN_SIDE",
    "check_export_size",
    "check_out_dir",
    "parse_size",
    "whole_pixels",
]

MIN_SIDE = 16  # px: below this the HUD and markers cannot fit
MAX_SIDE = 3840  # px, either side
MAX_PIXELS = 3840 * 2160  # a 4K frame; more is a typo or a hostile level, not a devlog GIF
_SIZE = re.compile(r"(-?\d+)\s*[xX]\s*(-?\d+)")


def parse_size(text: str) -> tuple[int, int]:
    """Parse ``"WIDTHxHEIGHT"`` into ``(width, height)``, within the export size limits.

    >>> parse_size("960x540")
    (960, 540)
    """
    match = _SIZE.fullmatch(text.strip()) if isinstance(text, str) else None
    if match is None:
        raise ValueError(f"size must be WIDTHxHEIGHT in pixels, like 960x540; got {text!r}")
    return check_export_size((int(match[1]), int(match[2])))


def whole_pixels(size: object) -> tuple[int, int]:
    """``size`` as a ``(width, height)`` pair of ints, else ``ValueError``. NumPy integers count
    as whole pixels; bools do not ((True, True) is a mistake, not a 1x1 image).

    >>> whole_pixels((64, 48))
    (64, 48)
    """
    try:
        width, height = size  # type: ignore[misc]
    except (TypeError, ValueError) as exc:
        raise ValueError(f"size must be a pair (width, height), got {size!r}") from exc
    if any(isinstance(v, bool) or not isinstance(v, Integral) for v in (width, height)):
        raise ValueError(f"size must be whole pixels (width, height), got {size!r}")
    return int(width), int(height)


def check_export_size(size: object) -> tuple[int, int]:
    """``size`` as ``(width, height)`` ints if it is a frame size an export accepts, else
    ``ValueError`` saying why. NumPy integers count as whole pixels; bools do not.

    >>> check_export_size((64, 48))
    (64, 48)
    """
    width, height = whole_pixels(size)
    if not (
        MIN_SIDE <= width <= MAX_SIDE
        and MIN_SIDE <= height <= MAX_SIDE
        and width * height <= MAX_PIXELS
    ):
        raise ValueError(
            f"size {width}x{height} is out of range: each side must be {MIN_SIDE}..{MAX_SIDE} px "
            f"and the frame at most {MAX_PIXELS} pixels (3840x2160)"
        )
    return int(width), int(height)


def check_out_dir(path: str | os.PathLike[str], force: bool) -> Path:
    """Return ``path`` as a Path if an export may write there, or raise ``ValueError``.

    A missing or empty folder is fine; a folder with files in it only with ``force``.

    >>> check_out_dir("runs/not-there-yet", force=False).name
    'not-there-yet'
    """
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise ValueError(f"output path {out} exists and is not a folder")
    if out.is_dir() and not force and any(out.iterdir()):
        raise ValueError(f"output folder {out} is not empty; use --force to overwrite its files")
    return out
