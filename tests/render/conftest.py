"""Synthetic runs for the render tests: the renderer reads only Scene and Snapshot, so no
simulation is needed to exercise it."""

from __future__ import annotations

import math

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


@pytest.fixture
def run():
    """``run(count, **scene_overrides) -> (scene, snapshots)``."""

    def make(count: int = 6, links: int = 3, fps: float = 30.0, **overrides):
        scene = make_scene(links, fps, **overrides)
        return scene, make_snapshots(scene, count)

    return make
