"""The compiled gap measure: numpy's gaps bit for bit, built only once a process has measured
enough with numpy, and a run the same with it or without it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ikgame import Simulation, load_level
from ikgame.kinematics import Skeleton, _compiled_gaps
from ikgame.kinematics.clearance import Clearance, Obstacles
from ikgame.level.library import LEVELS_DIR

numba = pytest.importorskip("numba", reason="the compiled path needs the 'fast' extra")


@pytest.fixture(scope="module")
def loop() -> _compiled_gaps.Gaps:
    return _compiled_gaps._measure(_compiled_gaps._compile(numba))


@pytest.fixture
def python_only(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(_compiled_gaps, "_build", _compiled_gaps._Build())
    monkeypatch.setenv("IKGAME_COMPILED", "0")


def _obstacles(rng: np.random.Generator, segments: int, circles: int) -> Obstacles:
    ends = rng.uniform(-250.0, 250.0, (segments, 4))
    # A degenerate segment (both ends one point) is measured as a round obstacle.
    if segments:
        ends[0, 2:] = ends[0, :2]
    seg = np.column_stack((ends, rng.uniform(0.0, 8.0, segments)))
    disc = np.column_stack(
        (rng.uniform(-250.0, 250.0, (circles, 2)), rng.uniform(2.0, 40.0, circles))
    )
    return Obstacles.from_arrays(seg.reshape(-1, 5), disc.reshape(-1, 3))


def _skeleton(rng: np.random.Generator, links: int, tree: bool) -> Skeleton:
    lengths = rng.uniform(20.0, 90.0, links).tolist()
    if not tree:
        return Skeleton.chain(lengths, base=(rng.uniform(-30, 30), 0.0), base_angle=math.pi / 2)
    parents = [-1] + [int(rng.integers(0, i)) for i in range(1, links)]
    return Skeleton.tree(lengths, parents, base_angle=math.pi / 2)


@pytest.mark.parametrize("tree", [False, True])
@pytest.mark.parametrize(("segments", "circles"), [(4, 0), (0, 3), (3, 2)])
def test_the_loop_gives_numpy_s_gaps_bit_for_bit(
    loop: _compiled_gaps.Gaps, python_only: None, tree: bool, segments: int, circles: int
) -> None:
    rng = np.random.default_rng(segments * 10 + circles + tree)
    for _ in range(15):
        links = int(rng.integers(1, 9))
        room = Clearance(
            _skeleton(rng, links, tree),
            rng.uniform(0.0, 8.0, links),
            _obstacles(rng, segments, circles),
        )
        q0, q1 = room._long_ends[0, 0], room._long_ends[1, 0]
        # One pose, a batch, a batch of batches: links through obstacles, beside and far off.
        for shape in ((links,), (7, links), (2, 5, links)):
            pts = room.points(rng.uniform(-math.pi, math.pi, shape))
            picks = [None, np.sort(rng.choice(links, size=max(1, links // 2), replace=False))]
            for picked in picks:
                numpy_gaps = room._gaps(pts, picked)
                starts, ends = room._links(pts)
                round_reach, long_reach = room._round_reach, room._long_reach
                if picked is not None:
                    starts, ends = starts[..., picked, :], ends[..., picked, :]
                    round_reach, long_reach = round_reach[picked], long_reach[picked]
                compiled = loop(starts, ends, room._centers, round_reach, q0, q1, long_reach)
                assert compiled.shape == numpy_gaps.shape
                assert compiled.tobytes() == numpy_gaps.tobytes()


def test_the_loop_is_built_once_enough_pairs_were_measured_and_then_measures_every_gap(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    build = _compiled_gaps._Build()
    monkeypatch.setattr(_compiled_gaps, "_build", build)
    arm = Skeleton.chain([100.0, 100.0], base_angle=math.pi / 2)
    shelf = Obstacles.from_arrays(np.array([[-50.0, 150.0, 50.0, 150.0, 0.0]]), np.empty((0, 3)))
    room = Clearance(arm, np.full(2, 5.0), shelf)
    poses = np.random.default_rng(1).uniform(-2.0, 2.0, (500, 2))
    before = room.smallest_gaps(poses)  # 500 poses of 2 links, 1 obstacle: 1,000 pairs
    assert build.thread is None and build.pairs == 1000
    build.count(_compiled_gaps.COMPILE_AFTER - build.pairs - 1)
    assert build.thread is None
    room.smallest_gaps(poses)
    assert build.thread is not None
    build.thread.join()
    compiled, calls = build.gaps, []
    assert compiled is not None
    monkeypatch.setattr(build, "gaps", lambda *arrays: calls.append(1) or compiled(*arrays))
    assert room.smallest_gaps(poses).tolist() == before.tolist()
    assert calls == [1]


def test_a_turned_off_switch_keeps_every_gap_in_numpy(python_only: None) -> None:
    assert _compiled_gaps.compiled_gaps(2 * _compiled_gaps.COMPILE_AFTER) is None
    assert _compiled_gaps._build.thread is None and _compiled_gaps._build.pairs == 0


def test_a_numba_that_cannot_compile_leaves_the_gaps_to_numpy(numba_without_compiler: str) -> None:
    build = _compiled_gaps._Build()
    with pytest.warns(RuntimeWarning, match=numba_without_compiler):
        build.run()
    assert build.gaps is None


def test_a_run_round_an_obstacle_is_the_same_with_the_loop_or_without(
    monkeypatch: pytest.MonkeyPatch, loop: _compiled_gaps.Gaps
) -> None:
    level = load_level(LEVELS_DIR / "04_around_the_wall.toml")

    def angles_after(ticks: int) -> bytes:
        sim = Simulation(level, record=False)
        for _ in range(ticks):
            sim.step()
        return sim.joint_angles().tobytes()

    build, calls = _compiled_gaps._Build(), []
    monkeypatch.setattr(_compiled_gaps, "_build", build)
    build.gaps = lambda *arrays: calls.append(1) or loop(*arrays)
    compiled = angles_after(480)
    assert len(calls) > 100  # the way round the wall was searched with the loop
    build.gaps = None
    monkeypatch.setenv("IKGAME_COMPILED", "0")
    assert angles_after(480) == compiled
