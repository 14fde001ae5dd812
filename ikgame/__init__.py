"""ikgame: a 2D physics sandbox for procedural animation.

A motorised pymunk chain is driven each tick by an inverse-kinematics controller toward targets
that a level script sets, and the run is rendered headless with Pillow.

The names below are imported on first use (see :mod:`ikgame._lazy`), so ``import ikgame`` is
cheap and a command loads only what it needs.

>>> import ikgame
>>> sim = ikgame.Simulation(ikgame.load_level(ikgame.DEFAULT_LEVEL))
>>> sim.step().tick
1
"""

from typing import TYPE_CHECKING

from ikgame._lazy import lazy_exports

__version__ = "0.1.0"

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "ikgame.compare": ["Comparison", "compare_level"],
        "ikgame.kinematics": ["SOLVERS", "Skeleton", "Solution", "SolveStatus", "get_solver"],
        "ikgame.level": ["DEFAULT_LEVEL", "Level", "LevelError", "load_level", "parse_level"],
        "ikgame.render": [
            "Camera",
            "PillowDrawOptions",
            "export_run",
            "load_theme",
            "render_snapshot",
        ],
        "ikgame.sim": ["RunResult", "Simulation", "TickInfo", "run_level"],
        "ikgame.skins": ["skin_scene"],
        "ikgame.snapshot": ["Scene", "Snapshot", "Sprite"],
    },
)

if TYPE_CHECKING:
    from ikgame.compare import Comparison, compare_level
    from ikgame.kinematics import SOLVERS, Skeleton, Solution, SolveStatus, get_solver
    from ikgame.level import DEFAULT_LEVEL, Level, LevelError, load_level, parse_level
    from ikgame.render import Camera, PillowDrawOptions, export_run, load_theme, render_snapshot
    from ikgame.sim import RunResult, Simulation, TickInfo, run_level
    from ikgame.skins import skin_scene
    from ikgame.snapshot import Scene, Snapshot, Sprite
