"""Pure inverse-kinematics math on numpy arrays (no pymunk, no Pillow).

The Jacobian itself stays in its module (``ikgame.kinematics.jacobian.jacobian``): exported
here, the function would hide the module of the same name.
"""

from ikgame.kinematics.ccd import CCDResult, ccd_iteration, solve_ccd, wrap_angle
from ikgame.kinematics.fabrik import solve_fabrik
from ikgame.kinematics.jacobian import solve_dls, solve_jacobian_transpose
from ikgame.kinematics.multi_ccd import solve_ccd_targets
from ikgame.kinematics.multi_fabrik import solve_fabrik_targets
from ikgame.kinematics.multi_jacobian import solve_dls_targets, solve_jacobian_transpose_targets
from ikgame.kinematics.recovery import RobustSolver
from ikgame.kinematics.registry import SOLVERS, TARGET_SOLVERS, get_solver, get_target_solver
from ikgame.kinematics.skeleton import Skeleton, forward_kinematics
from ikgame.kinematics.solver import Solution, Solver, SolveStatus, TargetSolver
from ikgame.kinematics.targets import TargetSet, stacked_jacobian

__all__ = [
    "CCDResult",
    "RobustSolver",
    "SOLVERS",
    "Skeleton",
    "Solution",
    "SolveStatus",
    "Solver",
    "TARGET_SOLVERS",
    "TargetSet",
    "TargetSolver",
    "ccd_iteration",
    "forward_kinematics",
    "get_solver",
    "get_target_solver",
    "solve_ccd",
    "solve_ccd_targets",
    "solve_dls",
    "solve_dls_targets",
    "solve_fabrik",
    "solve_fabrik_targets",
    "solve_jacobian_transpose",
    "solve_jacobian_transpose_targets",
    "stacked_jacobian",
    "wrap_angle",
]
