"""The compiled CCD pass of long chains: the same floats as the Python pass, bit for bit, and
a run the same with numba or without it."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from ikgame.kinematics import Skeleton, _compiled, ccd, solve_ccd
from ikgame.kinematics._floats import FloatChain

pytest.importorskip("numba", reason="the compiled path needs the 'fast' extra")


def _long_chain(rng: np.random.Generator, links: int) -> Skeleton:
    # Every third joint free, so both the wrapped and the clamped branch run.
    limits = [
        None if i % 3 == 0 else (-rng.uniform(0.2, 2.5), rng.uniform(0.2, 2.5))
        for i in range(links)
    ]
    return Skeleton.chain(
        rng.uniform(4.0, 25.0, links).tolist(),
        limits=limits,
        base=(rng.uniform(-50, 50), rng.uniform(-50, 50)),
        base_angle=rng.uniform(-math.pi, math.pi),
    )


def _python_chain(skeleton: Skeleton) -> ccd._Chain:
    chain = ccd._Chain(skeleton)
    chain._compiled = None
    return chain


@pytest.mark.parametrize("links", [_compiled.COMPILED_LINKS, 200])
def test_a_compiled_pass_gives_the_python_pass_floats_bit_for_bit(links: int) -> None:
    rng = np.random.default_rng(links)
    for _ in range(20):
        skeleton = _long_chain(rng, links)
        compiled, python = ccd._Chain(skeleton), _python_chain(skeleton)
        assert compiled._compiled is not None
        angles = skeleton.clamp(rng.uniform(-1.0, 1.0, links)).tolist()
        reach = float(skeleton.lengths.sum())
        tx, ty = rng.uniform(-reach, reach, 2).tolist()
        for arrival in (1e-6, 0.5 * reach):  # passes that run through, and that arrive early
            status, new = compiled.iterate(angles, tx, ty, arrival * arrival)
            assert (status, new) == python.iterate(angles, tx, ty, arrival * arrival)
            assert all(type(a) is float for a in new)


def test_a_solve_of_a_long_chain_is_the_same_compiled_or_not(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    skeleton = _long_chain(np.random.default_rng(7), 80)
    target = np.array([150.0, -220.0])
    compiled = solve_ccd(skeleton, np.zeros(80), target, max_iterations=25, tolerance=0.01)
    monkeypatch.setenv("IKGAME_COMPILED", "0")
    monkeypatch.setattr(ccd, "_last", None)  # the solver keeps the last skeleton's chain
    python = solve_ccd(skeleton, np.zeros(80), target, max_iterations=25, tolerance=0.01)
    assert compiled.status is python.status
    assert compiled.iterations == python.iterations
    assert compiled.angles.tolist() == python.angles.tolist()


def test_short_chains_and_a_turned_off_switch_stay_in_python(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    rng = np.random.default_rng(3)
    short = FloatChain(_long_chain(rng, _compiled.COMPILED_LINKS - 1))
    assert _compiled.compiled_pass(short) is None
    long = FloatChain(_long_chain(rng, _compiled.COMPILED_LINKS))
    assert _compiled.compiled_pass(long) is not None
    monkeypatch.setenv("IKGAME_COMPILED", "0")
    assert _compiled.compiled_pass(long) is None


def test_a_numba_that_cannot_compile_leaves_the_pass_in_python(numba_without_compiler: str) -> None:
    _compiled._kernel.cache_clear()
    _compiled._forward_kernel.cache_clear()
    try:
        with pytest.warns(RuntimeWarning, match=numba_without_compiler):
            assert _compiled._kernel() is None
        with pytest.warns(RuntimeWarning, match=numba_without_compiler):
            chain = FloatChain(_long_chain(np.random.default_rng(5), _compiled.COMPILED_END_LINKS))
        assert chain._end is None
        assert _compiled.compiled_pass(chain) is None
    finally:
        _compiled._kernel.cache_clear()
        _compiled._forward_kernel.cache_clear()


@pytest.mark.parametrize("links", [_compiled.COMPILED_END_LINKS, 200])
def test_a_compiled_end_is_the_python_forward_kinematics_bit_for_bit(links: int) -> None:
    rng = np.random.default_rng(links + 1)
    for _ in range(20):
        chain = FloatChain(_long_chain(rng, links))
        assert chain._end is not None
        angles = rng.uniform(-3.0, 3.0, links).tolist()
        xs, ys = chain.joints(angles)
        assert chain._end(chain, angles) == (xs[-1], ys[-1])
        tx, ty = rng.uniform(-500.0, 500.0, 2).tolist()
        assert chain.error_sqr(angles, tx, ty) == (xs[-1] - tx) ** 2 + (ys[-1] - ty) ** 2


def test_a_compiled_end_follows_a_chain_copied_for_a_moved_base() -> None:
    chain = FloatChain(_long_chain(np.random.default_rng(9), _compiled.COMPILED_END_LINKS))
    moved = copy.copy(chain)
    moved.base_x, moved.base_y, moved.base_angle = 40.0, -30.0, 0.5
    angles = [0.1] * _compiled.COMPILED_END_LINKS
    xs, ys = moved.joints(angles)
    assert moved.error_sqr(angles, 0.0, 0.0) == xs[-1] ** 2 + ys[-1] ** 2
    assert chain.error_sqr(angles, 0.0, 0.0) != moved.error_sqr(angles, 0.0, 0.0)


def test_short_chains_and_a_turned_off_switch_keep_the_end_in_python(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    rng = np.random.default_rng(4)
    assert FloatChain(_long_chain(rng, _compiled.COMPILED_END_LINKS - 1))._end is None
    assert FloatChain(_long_chain(rng, _compiled.COMPILED_END_LINKS))._end is not None
    monkeypatch.setenv("IKGAME_COMPILED", "0")
    assert FloatChain(_long_chain(rng, _compiled.COMPILED_END_LINKS))._end is None
