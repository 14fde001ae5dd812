"""Pure inverse-kinematics math on numpy arrays (no pymunk, no Pillow).

The Jacobian itself stays in its module (``ikgame.kinematics.jacobian.jacobian``): exported
here, the function would hide the module of the same name.
"""

from ikgame.kinematics.ccd import CCDResult, ccd_iteration, solve_ccd, wrap_angle
from ikgame.kinematics.fabrik import solve_fabrik
from ikgame.kinematics.jacobian import solve_dls, solve_jacobian_transpose
from ikgame.kinematics.recovery import RobustSolver
from ikgame.kinematics.registry import SOLVERS, get_solver
from ikgame.kinematics.skeleton import Skeleton, forward_kinematics
from ikgame.kinematics.solver import Solution, Solver, SolveStatus

__all__ = [
    "CCDResult",
    "RobustSolver",
    "SOLVERS",
    "Skeleton",
    "Solution",
    "SolveStatus",
    "Solver",
    "ccd_iteration",
    "forward_kinematics",
    "get_solver",
    "solve_ccd",
    "solve_dls",
    "solve_fabrik",
    "solve_jacobian_transpose",
    "wrap_angle",
]
