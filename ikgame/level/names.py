"""The solver names a level file may use, apart from the model so that the command line can list
them without building the model (see :mod:`ikgame.level.model`)."""

from __future__ import annotations

from typing import Final, Literal, get_args

__all__ = ["SOLVER_NAMES", "SolverName"]

SolverName = Literal["ccd", "jacobian_transpose", "dls", "fabrik"]
SOLVER_NAMES: Final = get_args(SolverName)
"""The solvers a level may name (``ikgame.kinematics.SOLVERS`` has one of each, by test).

>>> SOLVER_NAMES[0]
'ccd'
"""
