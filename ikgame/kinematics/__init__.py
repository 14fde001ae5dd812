"""Pure inverse-kinematics math on numpy arrays (no pymunk, no Pillow).

The Jacobian itself stays in its module (``ikgame.kinematics.jacobian.jacobian``): exported
here, the function would hide the module of the same name.
"""

from collections.abc import Mapping
from types import MappingProxyType
from typing import Final

from ikgame.kinematics.ccd import CCDResult, ccd_iteration, solve_ccd, wrap_angle
from ikgame.kinematics.fabrik import solve_fabrik
from ikgame.kinematics.jacobian import solve_dls, solve_jacobian_transpose
from ikgame.kinematics.skeleton import Skeleton, forward_kinematics
from ikgame.kinematics.solver import Solution, Solver, SolveStatus

__all__ = [
    "CCDResult",
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

SOLVERS: Final[Mapping[str, Solver]] = MappingProxyType(
    {
        "ccd": solve_ccd,
        "dls": solve_dls,
        "fabrik": solve_fabrik,
        "jacobian_transpose": solve_jacobian_transpose,
    }
)
"""Every solver by the name a level file uses for it (read-only)."""


def get_solver(name: str) -> Solver:
    """The solver called ``name``, or ``ValueError`` naming the choices.

    >>> get_solver("dls") is solve_dls
    True
    """
    try:
        return SOLVERS[name]
    except (KeyError, TypeError):
        choices = ", ".join(sorted(SOLVERS))
        raise ValueError(f"unknown solver {name!r}; choose one of: {choices}") from None
