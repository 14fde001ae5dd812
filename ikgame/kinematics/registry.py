"""Every raw solver by the name a level file uses for it.

Its own module so that the recovery layer, which restarts solvers by name, can use it without
importing the package it is part of.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Final, TypeVar

from ikgame.kinematics.ccd import solve_ccd
from ikgame.kinematics.fabrik import solve_fabrik
from ikgame.kinematics.jacobian import solve_dls, solve_jacobian_transpose
from ikgame.kinematics.multi_ccd import solve_ccd_targets
from ikgame.kinematics.multi_fabrik import solve_fabrik_targets
from ikgame.kinematics.multi_jacobian import solve_dls_targets, solve_jacobian_transpose_targets
from ikgame.kinematics.solver import Solver, TargetSolver

__all__ = ["SOLVERS", "TARGET_SOLVERS", "get_solver", "get_target_solver"]

_S = TypeVar("_S", Solver, TargetSolver)

SOLVERS: Final[Mapping[str, Solver]] = MappingProxyType(
    {
        "ccd": solve_ccd,
        "dls": solve_dls,
        "fabrik": solve_fabrik,
        "jacobian_transpose": solve_jacobian_transpose,
    }
)
"""Every solver by the name a level file uses for it (read-only)."""

TARGET_SOLVERS: Final[Mapping[str, TargetSolver]] = MappingProxyType(
    {
        "ccd": solve_ccd_targets,
        "dls": solve_dls_targets,
        "fabrik": solve_fabrik_targets,
        "jacobian_transpose": solve_jacobian_transpose_targets,
    }
)
"""Every multi-target solver (skeleton trees, a :class:`~ikgame.kinematics.targets.TargetSet`)
by the same names (read-only)."""


def get_solver(name: str) -> Solver:
    """The solver called ``name``, or ``ValueError`` naming the choices.

    >>> get_solver("dls") is solve_dls
    True
    """
    return _lookup(SOLVERS, name)


def get_target_solver(name: str) -> TargetSolver:
    """The multi-target solver called ``name``, or ``ValueError`` naming the choices.

    >>> get_target_solver("fabrik") is solve_fabrik_targets
    True
    """
    return _lookup(TARGET_SOLVERS, name)


def _lookup(table: Mapping[str, _S], name: str) -> _S:
    try:
        return table[name]
    except (KeyError, TypeError):
        choices = ", ".join(sorted(table))
        raise ValueError(f"unknown solver {name!r}; choose one of: {choices}") from None
