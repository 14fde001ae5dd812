"""The world <-> image transform: world pixels with y up, image pixels with y down.

Image coordinates are continuous: the image spans ``[0, width] x [0, height]`` and pixel
``(i, j)`` covers ``[i, i + 1] x [j, j + 1]``, so its centre is at ``(i + 0.5, j + 0.5)``.
Both axes share one scale, so circles stay round and angles stay true.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ikgame.render.output import whole_pixels
from ikgame.snapshot import Scene, Snapshot

__all__ = ["Camera", "check_size"]

# Fit margin, as a fraction of the image's shorter side: room around the geometry so the chain
# never touches the frame edge.
DEFAULT_MARGIN = 0.06
# Smallest world extent a fit will zoom to, px: a scene with nothing in it still gets a sane view.
MIN_EXTENT = 100.0


def check_size(size: object) -> tuple[int, int]:
    """Return ``size`` as ``(width, height)`` positive ints, or raise ``ValueError``.

    >>> check_size((320, 180))
    (320, 180)
    """
    width, height = whole_pixels(size)
    if width <= 0 or height <= 0:
        raise ValueError(f"size must be positive, got {width}x{height}")
    return width, height


@dataclass(frozen=True)
class Camera:
    """Maps world points (px, y up) to image points (px, y down) and back.

    >>> cam = Camera((200, 100), center=(0.0, 0.0), scale=2.0)
    >>> cam.world_to_pixel([[10.0, 5.0]]).tolist()
    [[120.0, 40.0]]

    Attributes:
        size: image ``(width, height)``, px.
        center: the world point at the image centre, px.
        scale: image pixels per world pixel.
    """

    size: tuple[int, int]
    center: tuple[float, float] = (0.0, 0.0)
    scale: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "size", check_size(self.size))
        cx, cy = (float(v) for v in self.center)
        if not (np.isfinite(cx) and np.isfinite(cy)):
            raise ValueError(f"camera center must be finite, got {self.center!r}")
        object.__setattr__(self, "center", (cx, cy))
        scale = float(self.scale)
        if not (np.isfinite(scale) and scale > 0):
            raise ValueError(f"camera scale must be a positive number, got {self.scale!r}")
        object.__setattr__(self, "scale", scale)

    def world_to_pixel(self, points: object) -> np.ndarray:
        """Image coordinates of world ``points`` (k, 2): y flips, the centre maps to mid-image.

        >>> Camera((100, 100)).world_to_pixel([[0.0, 10.0]]).tolist()
        [[50.0, 40.0]]
        """
        pts = _as_points(points)
        out = np.empty_like(pts)
        out[:, 0] = (pts[:, 0] - self.center[0]) * self.scale + self.size[0] / 2
        out[:, 1] = self.size[1] / 2 - (pts[:, 1] - self.center[1]) * self.scale
        return out

    def pixel_to_world(self, points: object) -> np.ndarray:
        """World coordinates of image ``points`` (k, 2); the inverse of :meth:`world_to_pixel`.

        >>> Camera((100, 100)).pixel_to_world([[50.0, 40.0]]).tolist()
        [[0.0, 10.0]]
        """
        pts = _as_points(points)
        out = np.empty_like(pts)
        out[:, 0] = (pts[:, 0] - self.size[0] / 2) / self.scale + self.center[0]
        out[:, 1] = (self.size[1] / 2 - pts[:, 1]) / self.scale + self.center[1]
        return out

    def scaled(self, factor: float) -> Camera:
        """The same view on an image ``factor`` times larger (supersampling, thumbnails).

        >>> Camera((160, 90), scale=0.5).scaled(3)
        Camera(size=(480, 270), center=(0.0, 0.0), scale=1.5)
        """
        if not factor > 0:
            raise ValueError(f"scale factor must be positive, got {factor!r}")
        width = max(1, round(self.size[0] * factor))
        height = max(1, round(self.size[1] * factor))
        return Camera((width, height), self.center, self.scale * factor)

    @classmethod
    def fit(
        cls,
        scene: Scene,
        snapshots_or_base: Sequence[Snapshot] | object,
        size: tuple[int, int] = (960, 540),
        margin: float = DEFAULT_MARGIN,
    ) -> Camera:
        """A camera that shows everything a run can touch, centred, at one scale on both axes.

        Without ``scene.bounds`` the view holds the obstacles, the goals, the script's targets
        (every effector's, for a tree) and the links: given a run's snapshots, every place its
        joints, props and a tree's current targets went; given
        only a base point, the square around the chain's full reach. ``margin`` (a fraction of
        the shorter image side) is added all around. With ``scene.bounds`` the view fits those
        bounds exactly.

        >>> scene = Scene("demo", np.zeros((0, 5)), np.zeros((0, 3)), np.full(2, 8.0), 100.0)
        >>> Camera.fit(scene, (0.0, 0.0), size=(200, 200), margin=0.0)
        Camera(size=(200, 200), center=(0.0, 0.0), scale=1.0)
        """
        width, height = check_size(size)
        if not 0.0 <= margin < 0.5:
            raise ValueError(f"margin must be in [0, 0.5), got {margin!r}")
        if scene.bounds is not None:
            xmin, ymin, xmax, ymax = (float(v) for v in scene.bounds)
            if not (xmax > xmin and ymax > ymin):
                raise ValueError(
                    f"scene bounds must have xmax > xmin, ymax > ymin, got {scene.bounds}"
                )
            pad = 0.0
        else:
            xmin, ymin, xmax, ymax = _scene_box(scene, _chain_box(scene, snapshots_or_base))
            pad = margin * min(width, height)
        extent_x = max(xmax - xmin, MIN_EXTENT)
        extent_y = max(ymax - ymin, MIN_EXTENT)
        scale = min((width - 2 * pad) / extent_x, (height - 2 * pad) / extent_y)
        return cls((width, height), ((xmin + xmax) / 2, (ymin + ymax) / 2), scale)


def _as_points(points: object) -> np.ndarray:
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"points must have shape (k, 2), got shape {pts.shape}")
    return pts


def _chain_box(scene: Scene, snapshots_or_base: Sequence[Snapshot] | object) -> np.ndarray:
    """(2, 2) low and high corner of where the chain must be seen: everywhere a recorded run's
    links and props went, or the square of the chain's full reach around a lone base."""
    if (
        isinstance(snapshots_or_base, Sequence)
        and snapshots_or_base
        and isinstance(snapshots_or_base[0], Snapshot)
    ):
        # Where the chain went, not the circle it could sweep: a chain on a floor never
        # reaches below it, and the full circle would leave half of every frame empty.
        parts = [snap.joints for snap in snapshots_or_base]
        parts += [snap.props[:, :2] for snap in snapshots_or_base if len(snap.props)]
        # A tree's current targets too (a chain frames the scene's targets only).
        for snap in snapshots_or_base:
            targets = snap.target_points if snap.targets is not None else np.zeros((0, 2))
            parts.append(targets[np.all(np.isfinite(targets), axis=1)])
        points = np.concatenate(parts).astype(float)
        pad = float(np.max(scene.link_widths, initial=0.0)) / 2.0
        return np.array([points.min(axis=0) - pad, points.max(axis=0) + pad])
    base = np.asarray(snapshots_or_base, dtype=float)
    if base.shape != (2,):
        raise ValueError(
            f"expected a list of snapshots or a base point (x, y), got shape {base.shape}"
        )
    return np.array([base - scene.reach, base + scene.reach])


def _scene_box(scene: Scene, chain: np.ndarray) -> tuple[float, float, float, float]:
    """The bounding box of the static geometry, targets, goals and the chain's box."""
    lows = [chain[0]]
    highs = [chain[1]]
    segments = np.asarray(scene.segments, dtype=float).reshape(-1, 5)
    if len(segments):
        ends = np.concatenate([segments[:, 0:2], segments[:, 2:4]])
        radii = np.concatenate([segments[:, 4], segments[:, 4]])[:, None]
        lows.append((ends - radii).min(axis=0))
        highs.append((ends + radii).max(axis=0))
    circles = np.asarray(scene.circles, dtype=float).reshape(-1, 3)
    if len(circles):
        lows.append((circles[:, :2] - circles[:, 2:3]).min(axis=0))
        highs.append((circles[:, :2] + circles[:, 2:3]).max(axis=0))
    targets = np.concatenate(
        [np.asarray(scene.targets, dtype=float).reshape(-1, 2), *scene.effector_targets]
    )
    if len(targets):
        lows.append(targets.min(axis=0))
        highs.append(targets.max(axis=0))
    goals = np.asarray(scene.goals, dtype=float).reshape(-1, 4)
    if len(goals):
        lows.append(goals[:, 0:2].min(axis=0))
        highs.append(goals[:, 2:4].max(axis=0))
    low = np.min(lows, axis=0)
    high = np.max(highs, axis=0)
    return float(low[0]), float(low[1]), float(high[0]), float(high[1])
