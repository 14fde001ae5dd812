"""Every raw solver by the name a level file uses for it.

Its own module so that the recovery layer, which restarts solvers by name, can use it without
importing the package it is part of.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Final

from ikgame.kinematics.ccd import solve_ccd
from ikgame.kinematics.fabrik import solve_fabrik
from ikgame.kinematics.jacobian import solve_dls, solve_jacobian_transpose
from ikgame.kinematics.solver import Solver

__all__ = ["SOLVERS", "get_solver"]

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
