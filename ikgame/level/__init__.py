"""Level files: the validated model, the loader, the script runner and the shipped library."""

from ikgame.level.library import DEFAULT_LEVEL, LEVELS_DIR, resolve_level, shipped_levels
from ikgame.level.loader import LevelError, Problem, load_level, parse_level
from ikgame.level.model import Level
from ikgame.level.script import ScriptRunner, StepOutcome

__all__ = [
    "DEFAULT_LEVEL",
    "LEVELS_DIR",
    "Level",
    "LevelError",
    "Problem",
    "ScriptRunner",
    "StepOutcome",
    "load_level",
    "parse_level",
    "resolve_level",
    "shipped_levels",
]
