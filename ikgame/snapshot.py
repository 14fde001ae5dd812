"""Plain data that leaves the simulation: the static scene of a run and per-frame snapshots.

Nothing here holds a pymunk object, so snapshots can be pickled to worker processes, rendered
long after the run, or kept by a game loop. Positions are world pixels (y up), angles radians,
times seconds.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Scene", "Snapshot", "PropShape", "Sprite"]


@dataclass(frozen=True)
class PropShape:
    """The shape of a dynamic prop: ``kind`` is ``"ball"`` (size = (radius, radius)) or ``"box"``
    (size = (width, height)), px.

    >>> PropShape("ball", (10.0, 10.0)).kind
    'ball'
    """

    kind: str
    size: tuple[float, float]


@dataclass(frozen=True, eq=False)
class Sprite:
    """An image drawn on a link or a prop in place of its shape, decoded once per run.

    The image's +x axis (to the right) points along the link, or along the prop's angle; the
    image is drawn upright, not mirrored, when that direction is the world's +x.

    >>> Sprite(np.zeros((4, 8, 4), dtype=np.uint8), (0.0, 2.0), 2.5).size
    (8, 4)

    Attributes:
        rgba: (height, width, 4) uint8 pixels with straight (not premultiplied) alpha, rows
            from the top.
        pivot: the image point (x right, y down, image px from the top-left corner) that sits
            on the link's joint or the prop's centre.
        scale: world px per image px.
    """

    rgba: np.ndarray
    pivot: tuple[float, float]
    scale: float

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) of the image, px."""
        return int(self.rgba.shape[1]), int(self.rgba.shape[0])


@dataclass(frozen=True, eq=False)
class Scene:
    """What stays the same for a whole run: geometry and names the renderer needs.

    >>> Scene("demo", np.zeros((0, 5)), np.zeros((0, 3)), np.full(3, 8.0), 300.0).step_count
    0

    Attributes:
        level_name: the level's display name.
        segments: (k, 5) static segment obstacles as ``(ax, ay, bx, by, radius)``, px.
        circles: (m, 3) static circle obstacles as ``(x, y, radius)``, px.
        link_widths: (n,) link thickness, px.
        reach: the chain's full length, px (for fitting the camera around the base).
        targets: (t, 2) every point the script will aim at, in order, px (camera fit, and the
            renderer's faded "upcoming" markers).
        goals: (g, 4) goal regions as ``(xmin, ymin, xmax, ymax)``, px.
        props: the shape of each dynamic prop, in the order of ``Snapshot.props``.
        bounds: explicit camera bounds ``(xmin, ymin, xmax, ymax)`` from the level, or None.
        step_count: number of script steps.
        fps: recorded frames per second.
        link_sprites: one entry per link (None: drawn as a capsule), or empty when no link has
            a sprite.
        prop_sprites: one entry per prop (None: drawn as its shape), or empty.
    """

    level_name: str
    segments: np.ndarray
    circles: np.ndarray
    link_widths: np.ndarray
    reach: float
    targets: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    goals: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))
    props: tuple[PropShape, ...] = ()
    bounds: tuple[float, float, float, float] | None = None
    step_count: int = 0
    fps: float = 30.0
    link_sprites: tuple[Sprite | None, ...] = ()
    prop_sprites: tuple[Sprite | None, ...] = ()


@dataclass(frozen=True, eq=False)
class Snapshot:
    """The state of a run at one recorded frame.

    >>> snap = Snapshot(0.0, 0, np.zeros((2, 2)), np.zeros(1), np.zeros(1))
    >>> snap.joints.shape
    (2, 2)

    Attributes:
        time: simulated time, s.
        tick: physics tick count.
        joints: (n + 1, 2) world positions: joint 0 (the base) .. joint n-1, then the end effector.
        angles: (n,) measured local joint angles, radians.
        world_angles: (n,) world angle of each link, radians.
        target: (2,) the current target, or None when the script has none.
        step_index: index of the running script step (== step_count once the script is done).
        error: distance from the end effector to the target, px (nan without a target).
        solver_status: the solver's state this tick: ``"success"``, ``"processing"``,
            ``"failure"``, or ``"blocked"`` (the chain makes no progress toward a target the
            solver reaches, so it holds its pose).
        torque_limited: (n,) which motors are at their torque limit.
        props: (p, 3) each prop's ``(x, y, angle)``.
    """

    time: float
    tick: int
    joints: np.ndarray
    angles: np.ndarray
    world_angles: np.ndarray
    target: np.ndarray | None = None
    step_index: int = 0
    error: float = float("nan")
    solver_status: str = "processing"
    torque_limited: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    props: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
