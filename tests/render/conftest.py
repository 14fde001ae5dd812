"""Synthetic runs for the render tests: the renderer reads only Scene and Snapshot, so no
simulation is needed to exercise it."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from ikgame.snapshot import PropShape, Scene, Snapshot

LINK = 40.0  # px, every link of the synthetic chain


def chain_joints(angles: np.ndarray, base=(0.0, 0.0)) -> np.ndarray:
    """Joint positions of a chain of LINK-long links with local ``angles``."""
    world = np.cumsum(angles)
    steps = np.c_[np.cos(world), np.sin(world)] * LINK
    return np.vstack([base, np.asarray(base) + np.cumsum(steps, axis=0)])


def make_scene(links: int = 3, fps: float = 30.0, **overrides) -> Scene:
    fields = dict(
        level_name="Synthetic",
        segments=np.array([[-150.0, -20.0, 150.0, -20.0, 4.0]]),
        circles=np.array([[-90.0, 60.0, 15.0]]),
        link_widths=np.full(links, 10.0),
        reach=LINK * links,
        targets=np.array([[60.0, 80.0], [-70.0, 50.0]]),
        goals=np.array([[70.0, 0.0, 110.0, 40.0]]),
        props=(PropShape("ball", (8.0, 8.0)), PropShape("box", (20.0, 12.0))),
        step_count=2,
        fps=fps,
    )
    fields.update(overrides)
    return Scene(**fields)


def make_snapshots(scene: Scene, count: int) -> list[Snapshot]:
    """A chain sweeping from pointing right to pointing up, one snapshot per frame."""
    links = len(scene.link_widths)
    snaps = []
    for k in range(count):
        sweep = k / max(1, count - 1)
        angles = np.r_[sweep * math.pi / 2, np.full(links - 1, 0.25 * sweep)]
        joints = chain_joints(angles)
        step = 0 if k < count / 2 else 1
        target = scene.targets[step] if len(scene.targets) else None
        error = float("nan") if target is None else float(np.hypot(*(joints[-1] - target)))
        snaps.append(
            Snapshot(
                time=k / scene.fps,
                tick=8 * k,
                joints=joints,
                angles=angles,
                world_angles=np.cumsum(angles),
                target=target,
                step_index=step,
                error=error,
                solver_status="success" if k % 2 else "processing",
                torque_limited=np.arange(links) == (k % links),
                props=np.array([[-40.0 + k, -12.0, 0.1 * k], [40.0, -10.0, 0.2]])[
                    : len(scene.props)
                ],
            )
        )
    return snaps


# A trunk with two arms of two links each: the arms' tips are the effectors.
TREE_PARENTS = np.array([-1, 0, 1, 0, 3])
TREE_EFFECTORS = np.array([2, 4])
TREE_NAMES = ("left", "right")


def tree_pose(angles: np.ndarray, base=(0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """(2n, 2) link starts then link ends, and (n,) world angles, of the tree TREE_PARENTS of
    LINK-long links with local ``angles``."""
    n = len(TREE_PARENTS)
    world, starts, ends = np.zeros(n), np.zeros((n, 2)), np.zeros((n, 2))
    for i, p in enumerate(TREE_PARENTS):
        world[i] = angles[i] + (world[p] if p >= 0 else 0.0)
        starts[i] = ends[p] if p >= 0 else base
        ends[i] = starts[i] + LINK * np.array([math.cos(world[i]), math.sin(world[i])])
    return np.vstack([starts, ends]), world


def make_tree_scene(**overrides) -> Scene:
    fields = dict(
        level_name="Tree",
        segments=np.zeros((0, 5)),
        circles=np.zeros((0, 3)),
        link_widths=np.full(len(TREE_PARENTS), 12.0),
        reach=3 * LINK,
        step_count=2,
        parents=TREE_PARENTS,
        effector_links=TREE_EFFECTORS,
        effector_names=TREE_NAMES,
        effector_targets=(
            np.array([[-70.0, 60.0], [-80.0, 20.0]]),
            np.array([[70.0, 60.0], [90.0, 90.0]]),
        ),
    )
    fields.update(overrides)
    return Scene(**fields)


def make_tree_snapshots(scene: Scene, count: int) -> list[Snapshot]:
    """Both arms opening from straight up to a V, one snapshot per frame; the right arm has
    no target in the first frame."""
    snaps = []
    for k in range(count):
        spread = 0.3 + 0.6 * k / max(1, count - 1)
        angles = np.array([math.pi / 2, spread, 0.2, -spread, -0.2])
        joints, world = tree_pose(angles)
        targets = np.array([scene.effector_targets[0][0], scene.effector_targets[1][0]])
        if k == 0:
            targets[1] = np.nan
        tips = joints[len(TREE_PARENTS) :][TREE_EFFECTORS]
        errors = np.linalg.norm(tips - targets, axis=1)
        largest = float(np.nanmax(errors))
        snap = Snapshot(k / scene.fps, 8 * k, joints, angles, world, error=largest)
        snaps.append(replace(snap, targets=targets, errors=errors))
    return snaps


@pytest.fixture
def tree_run():
    """``tree_run(count, **scene_overrides) -> (scene, snapshots)``: a two-armed tree."""

    def make(count: int = 4, **overrides):
        scene = make_tree_scene(**overrides)
        return scene, make_tree_snapshots(scene, count)

    return make


@pytest.fixture
def run():
    """``run(count, **scene_overrides) -> (scene, snapshots)``."""

    def make(count: int = 6, links: int = 3, fps: float = 30.0, **overrides):
        scene = make_scene(links, fps, **overrides)
        return scene, make_snapshots(scene, count)

    return make
