"""Level files: the validated model, the loader, the script runner and the shipped library.

Names are imported on first use: finding a level does not build the pydantic model.
"""

from typing import TYPE_CHECKING

from ikgame._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "ikgame.level.library": ["DEFAULT_LEVEL", "LEVELS_DIR", "resolve_level", "shipped_levels"],
        "ikgame.level.loader": ["LevelError", "Problem", "load_level", "parse_level"],
        "ikgame.level.model": ["Level"],
        "ikgame.level.script": ["ScriptRunner", "StepOutcome"],
    },
)

if TYPE_CHECKING:
    from ikgame.level.library import DEFAULT_LEVEL, LEVELS_DIR, resolve_level, shipped_levels
    from ikgame.level.loader import LevelError, Problem, load_level, parse_level
    from ikgame.level.model import Level
    from ikgame.level.script import ScriptRunner, StepOutcome
