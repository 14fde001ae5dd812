"""Pure inverse-kinematics math on numpy arrays (no pymunk, no Pillow)."""

from ikgame.kinematics.ccd import CCDResult, ccd_iteration, solve_ccd, wrap_angle
from ikgame.kinematics.skeleton import Skeleton, forward_kinematics
from ikgame.kinematics.solver import Solution, SolveStatus, Solver

__all__ = [
    "CCDResult",
    "Skeleton",
    "Solution",
    "SolveStatus",
    "Solver",
    "ccd_iteration",
    "forward_kinematics",
    "solve_ccd",
    "wrap_angle",
]
