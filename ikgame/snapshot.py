"""Plain data that leaves the simulation: the static scene of a run and per-frame snapshots.

Nothing here holds a pymunk object, so snapshots can be pickled to worker processes, rendered
long after the run, or kept by a game loop. Positions are world pixels (y up), angles radians,
times seconds.

A run drives either a chain (each link hangs from the one before; one end effector, its tip,
named ``"tip"``) or a tree (``Scene.parents`` says which link each hangs from; several end
effectors, each with its own target). The two lay their joints out differently, so readers go
through :func:`link_segments` and :func:`effector_positions`, and through
:attr:`Snapshot.target_points` and :attr:`Snapshot.effector_errors`, which give one row per
effector for both.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "Scene",
    "Snapshot",
    "PropShape",
    "Sprite",
    "effector_positions",
    "link_segments",
]


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
        parents: (n,) int, the link each link hangs from, -1 for a root (parents come before
            their children); empty for a chain.
        effector_links: (k,) int, the links whose tips are end effectors, for a tree; empty for
            a chain (its one effector is the last link's tip).
        effector_names: (k,) one name per end effector; a chain's is ``("tip",)``.
        effector_targets: for a tree, one (t, 2) array per effector: every point the script
            will aim that effector at, in order (its faded "upcoming" markers); empty when not
            known, and always for a chain, whose upcoming targets are ``targets``.
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
    parents: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    effector_links: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    effector_names: tuple[str, ...] = ("tip",)
    effector_targets: tuple[np.ndarray, ...] = ()

    def __post_init__(self) -> None:
        parents = _indices("parents", self.parents)
        links = _indices("effector_links", self.effector_links)
        names = tuple(self.effector_names)
        if not all(isinstance(name, str) for name in names):
            raise ValueError(f"effector_names must be strings, got {names!r}")
        targets = tuple(
            _points(f"effector_targets[{j}]", points)
            for j, points in enumerate(self.effector_targets)
        )
        if len(parents):
            n = len(np.asarray(self.link_widths).reshape(-1))
            if len(parents) != n:
                raise ValueError(f"parents has {len(parents)} entries for {n} link widths")
            bad = [i for i, p in enumerate(parents.tolist()) if not -1 <= p < i]
            if bad:
                raise ValueError(
                    f"parents[{bad[0]}] = {parents[bad[0]]}: expected -1 (a root) or the index "
                    "of an earlier link"
                )
            if not len(links) or len(set(links.tolist())) != len(links):
                raise ValueError(f"a tree needs distinct effector_links, got {links.tolist()}")
            if links.min() < 0 or links.max() >= n:
                raise ValueError(f"effector_links {links.tolist()} must be link indices 0..{n - 1}")
            if targets and len(targets) != len(links):
                raise ValueError(
                    f"effector_targets has {len(targets)} arrays for {len(links)} effectors"
                )
        elif len(links) or targets:
            raise ValueError("effector_links and effector_targets are for trees (give parents)")
        count = len(links) if len(parents) else 1
        if len(names) != count or len(set(names)) != count:
            raise ValueError(f"expected {count} distinct effector names, got {list(names)}")
        object.__setattr__(self, "parents", parents)
        object.__setattr__(self, "effector_links", links)
        object.__setattr__(self, "effector_names", names)
        object.__setattr__(self, "effector_targets", targets)

    @property
    def is_tree(self) -> bool:
        """Whether the links form a tree (``parents`` given) rather than a chain."""
        return bool(len(self.parents))

    @property
    def link_parents(self) -> np.ndarray:
        """(n,) int: the link each link hangs from, -1 for a root, for chains too.

        >>> Scene("demo", np.zeros((0, 5)), np.zeros((0, 3)), np.full(3, 8.0), 300.0).link_parents
        array([-1,  0,  1])
        """
        if self.is_tree:
            return self.parents
        return np.arange(len(np.asarray(self.link_widths).reshape(-1))) - 1

    @property
    def effectors(self) -> np.ndarray:
        """(k,) int: the links whose tips are end effectors, for chains too (their last link).

        >>> Scene("demo", np.zeros((0, 5)), np.zeros((0, 3)), np.full(3, 8.0), 300.0).effectors
        array([2])
        """
        if self.is_tree:
            return self.effector_links
        return np.array([len(np.asarray(self.link_widths).reshape(-1)) - 1])

    @property
    def target_lists(self) -> tuple[np.ndarray, ...]:
        """Per effector, the points the script will aim it at, in order (see ``targets`` and
        ``effector_targets``); empty when a tree's are not known."""
        if self.is_tree:
            return self.effector_targets
        return (np.asarray(self.targets, dtype=float).reshape(-1, 2),)


@dataclass(frozen=True, eq=False)
class Snapshot:
    """The state of a run at one recorded frame.

    >>> snap = Snapshot(0.0, 0, np.zeros((2, 2)), np.zeros(1), np.zeros(1))
    >>> snap.joints.shape
    (2, 2)

    Attributes:
        time: simulated time, s.
        tick: physics tick count.
        joints: world positions of the joints. A chain's are (n + 1, 2): joint 0 (the base) ..
            joint n-1, then the end effector. A tree's are (2n, 2): the n link starts, then the
            n link ends (as :func:`ikgame.kinematics.forward_kinematics` lays them out). Read
            them with :func:`link_segments` and :func:`effector_positions`.
        angles: (n,) measured local joint angles, radians.
        world_angles: (n,) world angle of each link, radians.
        target: (2,) a chain's current target, or None when the script has none (a tree:
            None; see ``targets``).
        step_index: index of the running script step (== step_count once the script is done).
        error: distance from the end effector to the target, px (nan without a target); for a
            tree, the largest of ``errors``.
        solver_status: the solver's state this tick: ``"success"``, ``"processing"``,
            ``"failure"``, or ``"blocked"`` (the chain makes no progress toward a target the
            solver reaches, so it holds its pose).
        torque_limited: (n,) which motors are at their torque limit.
        props: (p, 3) each prop's ``(x, y, angle)``.
        targets: a tree's (k, 2) current target of each effector, a NaN row for an effector
            without one; None for a chain.
        errors: a tree's (k,) distance of each effector to its target, px (NaN without one);
            None for a chain.
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
    targets: np.ndarray | None = None
    errors: np.ndarray | None = None

    @property
    def target_points(self) -> np.ndarray:
        """(k, 2) each effector's current target, a NaN row where it has none; a chain's one row
        is ``target``.

        >>> Snapshot(0.0, 0, np.zeros((2, 2)), np.zeros(1), np.zeros(1)).target_points.tolist()
        [[nan, nan]]
        """
        if self.targets is not None:
            return np.asarray(self.targets, dtype=float).reshape(-1, 2)
        if self.target is None:
            return np.full((1, 2), np.nan)
        return np.asarray(self.target, dtype=float).reshape(1, 2)

    @property
    def effector_errors(self) -> np.ndarray:
        """(k,) each effector's distance to its target, px (NaN without one); a chain's one
        entry is ``error``.

        >>> Snapshot(0.0, 0, np.zeros((2, 2)), np.zeros(1), np.zeros(1), error=2.5).effector_errors
        array([2.5])
        """
        if self.errors is not None:
            return np.asarray(self.errors, dtype=float).reshape(-1)
        return np.array([float(self.error)])


def link_segments(scene: Scene, snapshot: Snapshot) -> tuple[np.ndarray, np.ndarray]:
    """Where each link starts and ends, (n, 2) each, for a chain or a tree.

    >>> scene = Scene("demo", np.zeros((0, 5)), np.zeros((0, 3)), np.full(2, 8.0), 20.0,
    ...               parents=np.array([-1, -1]), effector_links=np.array([0, 1]),
    ...               effector_names=("left", "right"))
    >>> joints = np.array([[0.0, 0.0], [0.0, 0.0], [-10.0, 0.0], [10.0, 0.0]])
    >>> starts, ends = link_segments(scene, Snapshot(0.0, 0, joints, np.zeros(2), np.zeros(2)))
    >>> ends.tolist()
    [[-10.0, 0.0], [10.0, 0.0]]
    """
    joints = np.asarray(snapshot.joints, dtype=float)
    if joints.ndim != 2 or joints.shape[1] != 2 or len(joints) < 2:
        raise ValueError(f"snapshot.joints must have shape (n + 1, 2), n >= 1; got {joints.shape}")
    n = len(np.asarray(scene.link_widths).reshape(-1))
    if scene.is_tree:
        if joints.shape != (2 * n, 2):
            raise ValueError(
                f"snapshot.joints has shape {joints.shape}; a tree of {n} links needs "
                f"({2 * n}, 2): the link starts, then the link ends"
            )
        return joints[:n], joints[n:]
    if len(joints) != n + 1:
        raise ValueError(f"scene has {n} link widths for a chain of {len(joints) - 1} links")
    return joints[:-1], joints[1:]


def effector_positions(scene: Scene, snapshot: Snapshot) -> np.ndarray:
    """(k, 2) where each end effector is, in the order of ``scene.effector_names``.

    >>> scene = Scene("demo", np.zeros((0, 5)), np.zeros((0, 3)), np.full(1, 8.0), 10.0)
    >>> snap = Snapshot(0.0, 0, np.array([[0.0, 0.0], [10.0, 0.0]]), np.zeros(1), np.zeros(1))
    >>> effector_positions(scene, snap).tolist()
    [[10.0, 0.0]]
    """
    return link_segments(scene, snapshot)[1][scene.effectors]


def _indices(name: str, values: object) -> np.ndarray:
    """``values`` as a 1-D int array; ``ValueError`` for anything that is not whole numbers."""
    array = np.asarray(values)
    if array.size == 0:
        return np.zeros(0, dtype=int)
    if array.ndim != 1 or not np.issubdtype(array.dtype, np.integer):
        raise ValueError(f"{name} must be a 1-D array of ints, got {array.dtype} {array.shape}")
    return array.astype(int)


def _points(name: str, values: object) -> np.ndarray:
    array = np.asarray(values, dtype=float)
    if array.size == 0:
        return np.zeros((0, 2))
    if array.ndim != 2 or array.shape[1] != 2:
        raise ValueError(f"{name} must have shape (t, 2), got {array.shape}")
    return array
