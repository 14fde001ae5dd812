"""ikgame: a 2D physics sandbox for procedural animation.

A motorised pymunk chain is driven each tick by an inverse-kinematics controller toward targets
that a level script sets, and the run is rendered headless with Pillow.

>>> import ikgame
>>> sim = ikgame.Simulation(ikgame.load_level(ikgame.DEFAULT_LEVEL))
>>> sim.step().tick
1
"""

from ikgame.compare import Comparison, compare_level
from ikgame.kinematics import SOLVERS, Skeleton, Solution, SolveStatus, get_solver
from ikgame.level import DEFAULT_LEVEL, Level, LevelError, load_level, parse_level
from ikgame.render import Camera, PillowDrawOptions, export_run, load_theme, render_snapshot
from ikgame.sim import RunResult, Simulation, TickInfo, run_level
from ikgame.skins import skin_scene
from ikgame.snapshot import Scene, Snapshot, Sprite

__version__ = "0.1.0"

__all__ = [
    "DEFAULT_LEVEL",
    "SOLVERS",
    "Camera",
    "Comparison",
    "Level",
    "LevelError",
    "PillowDrawOptions",
    "RunResult",
    "Scene",
    "Simulation",
    "Skeleton",
    "Snapshot",
    "Sprite",
    "Solution",
    "SolveStatus",
    "TickInfo",
    "compare_level",
    "export_run",
    "get_solver",
    "load_level",
    "load_theme",
    "parse_level",
    "render_snapshot",
    "run_level",
    "skin_scene",
]
