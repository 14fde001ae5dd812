"""Where the shipped levels and assets are on disk, for the modules that read them (the level
library, the renderer's themes), which must not import each other.

In a checkout, installed editable or not at all, ``levels/`` and ``assets/`` sit beside the
package; an installed wheel carries them inside it (``pyproject.toml`` maps them there).
"""

from __future__ import annotations

from pathlib import Path
from typing import Final

__all__ = ["LEVELS_DIR", "ASSETS_DIR", "THEMES_DIR"]

_PACKAGE: Final = Path(__file__).resolve().parent
_ROOT: Final = _PACKAGE if (_PACKAGE / "levels").is_dir() else _PACKAGE.parent
LEVELS_DIR: Final = _ROOT / "levels"
ASSETS_DIR: Final = _ROOT / "assets"
THEMES_DIR: Final = ASSETS_DIR / "themes"
