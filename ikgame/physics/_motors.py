"""A long chain's motor writes and impulse reads in one compiled loop, when numba is installed
(the ``fast`` extra: ``python -m pip install 'ikgame[fast]'``).

pymunk has no batch API for constraints, so a tick sets each motor's rate and torque limit and
reads its impulse with a call into chipmunk per motor: four calls and two reads a link, about a
microsecond each from Python, on a chain with the return sweep. Compiled, the loop calls the
very same chipmunk functions (``cpSimpleMotorSetRate``, ``cpConstraintSetMaxForce``,
``cpConstraintGetImpulse``, through their addresses) with the same floats in the same order, so
the space is left exactly as the Python loop leaves it (tests compare the two bit for bit). Only
chains of more than :data:`~ikgame.physics.world.SWEEP_LINKS` links use it: compiling takes
about half a second once numba's compiler is up (numba's import and the compiler's start about
two seconds more, shared with :mod:`ikgame.kinematics._compiled`), which the shorter chains'
runs would not win back. ``IKGAME_COMPILED=0`` in the environment turns it off.
"""

from __future__ import annotations

import ctypes
import functools
from collections.abc import Callable
from types import ModuleType
from typing import Any

import numpy as np
from pymunk import _chipmunk_cffi as _chipmunk

from ikgame._numba import compiled, turned_off

__all__ = ["CompiledMotors", "compiled_motors"]


class CompiledMotors:
    """Motors, given as pymunk's C structs (``cpConstraint *``), written and read in one call.

    Attributes:
        count: number of motors.
    """

    def __init__(self, structs: list[Any], kernels: tuple[Callable[..., None], ...]) -> None:
        cast = _chipmunk.ffi.cast
        self._pointers = np.array([int(cast("uintptr_t", s)) for s in structs], dtype=np.uintp)
        self._write, self._read = kernels
        self.count = len(structs)

    def write(self, rates: np.ndarray, budgets: np.ndarray) -> None:
        """Set each motor's rate to the negated ``rates`` entry and its torque limit to the
        ``budgets`` entry, motor by motor: ``cpSimpleMotorSetRate(m, -rate)`` then
        ``cpConstraintSetMaxForce(m, budget)``."""
        self._write(self._pointers, _floats(rates, self.count), _floats(budgets, self.count))

    def impulses(self) -> np.ndarray:
        """(count,) each motor's impulse of the last step (``cpConstraintGetImpulse``)."""
        out = np.empty(self.count)
        self._read(self._pointers, out)
        return out


def compiled_motors(structs: list[Any]) -> CompiledMotors | None:
    """``structs``' writes and reads compiled, or None: no numba, or turned off."""
    kernels = None if turned_off() else _kernels()
    return None if kernels is None else CompiledMotors(structs, kernels)


def _floats(values: np.ndarray, count: int) -> np.ndarray:
    array = np.ascontiguousarray(values, dtype=np.float64)
    if array.shape != (count,):
        raise ValueError(f"expected ({count},) values, got shape {array.shape}")
    return array


@functools.cache
def _kernels() -> tuple[Callable[..., None], Callable[..., None]] | None:
    """The write and read loops compiled, or None (see :func:`ikgame._numba.compiled`)."""
    lib, ffi = _chipmunk.lib, _chipmunk.ffi

    def function(name: str, result: Any, *arguments: Any) -> Any:
        # A struct pointer goes as its address: the same register as the pointer on every ABI
        # numba targets, and numba passes integers where it would not pass a pointer.
        address = int(ffi.cast("uintptr_t", ffi.addressof(lib, name)))
        return ctypes.CFUNCTYPE(result, ctypes.c_size_t, *arguments)(address)

    def build(numba: ModuleType) -> tuple[Callable[..., None], Callable[..., None]]:
        set_rate = function("cpSimpleMotorSetRate", None, ctypes.c_double)
        set_max_force = function("cpConstraintSetMaxForce", None, ctypes.c_double)
        impulse = function("cpConstraintGetImpulse", ctypes.c_double)

        @numba.njit(nogil=True)
        def write(motors: np.ndarray, rates: np.ndarray, budgets: np.ndarray) -> None:
            for i in range(len(motors)):
                # SimpleMotor drives (b.w - a.w) toward -rate.
                set_rate(motors[i], -rates[i])
                set_max_force(motors[i], budgets[i])

        @numba.njit(nogil=True)
        def read(motors: np.ndarray, out: np.ndarray) -> None:
            for i in range(len(motors)):
                out[i] = impulse(motors[i])

        # Compiled now, on no motors, so that a numba that cannot compile them is found here
        # rather than in the middle of a run.
        none = np.zeros(0, dtype=np.uintp)
        write(none, np.zeros(0), np.zeros(0))
        read(none, np.zeros(0))
        return write, read

    return compiled("the motor loops", build)
