"""Draw a :class:`~ikgame.snapshot.Snapshot` with Pillow.

The scene is drawn at ``supersample`` times the output size and shrunk with a Lanczos filter:
Pillow's primitives are not anti-aliased, and averaging many sub-pixels is the cheapest way to
get smooth edges. The static scene (background, grid, goals, obstacles) is drawn and shrunk once
per run; each frame redraws and shrinks only the rectangle its moving parts cover, which makes
a frame about three times cheaper. The HUD is drawn after the shrink so its text stays crisp.
Links and props that carry a sprite are drawn as their images instead of their shapes
(:func:`_draw_sprites`, with :mod:`ikgame.render.sprites`), over the shapes, under the crosshair.
Translucent layers (goals, trail, faded targets) are blended with the background colour by hand
instead of alpha compositing a full-size layer, which would cost as much as the rest of a frame.

Sizes below are in output pixels unless a name says otherwise.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from ikgame.render.camera import Camera
from ikgame.render.sprites import draw_sprite, sprite_corners
from ikgame.render.theme import RGB, Theme
from ikgame.snapshot import Scene, Snapshot, Sprite

__all__ = ["render_snapshot", "to_draw_coords"]

MIN_LINK_WIDTH = 3.0  # px: thinner links vanish in a GIF
LINK_OUTLINE = 1.5  # px around each link
OBSTACLE_OUTLINE = 1.5  # px
MIN_OBSTACLE_WIDTH = 3.0  # px: a zero-radius segment is still a wall you should see
GRID_STEP = 64.0  # px between grid lines, about (snapped to 1, 2, 5 x 10^k world px)
GOAL_FILL_ALPHA = 0.22  # goal rectangles: fill opacity over the background
TARGET_RADIUS = 9.0  # px, the crosshair ring
UPCOMING_RADIUS = 5.5  # px, faded rings of targets still to come
TRAIL_WIDTH = (1.0, 4.0)  # px, oldest and newest trail segment
HUD_PANEL_ALPHA = 0.84  # the HUD panel over the scene
MAX_SUPERSAMPLE = 8  # 8x of a 4K frame is already 2 GB of pixels
# Output px a Lanczos shrink reaches on each side (its window is 3 output px), plus 1 for rounding.
LANCZOS_REACH = 4


def to_draw_coords(camera: Camera, points: object) -> np.ndarray:
    """Pillow drawing coordinates of world ``points`` (k, 2).

    Pillow puts integer coordinates on pixel centres while :class:`Camera` puts them on pixel
    corners, hence the half-pixel shift. Every drawing in this module and in
    :mod:`ikgame.render.debug_draw` goes through here.

    >>> to_draw_coords(Camera((10, 10)), [[0.0, 0.0]]).tolist()
    [[4.5, 4.5]]
    """
    return camera.world_to_pixel(points) - 0.5


def render_snapshot(
    scene: Scene,
    snapshot: Snapshot,
    camera: Camera,
    theme: Theme,
    *,
    trail: np.ndarray | None = None,
    hud: bool = True,
    supersample: int = 3,
) -> Image.Image:
    """Draw one frame of a run as an RGB image of ``camera.size``.

    ``trail`` is the end effector's recent path (k, 2), oldest first, drawn as a fading line.
    Same inputs give the same pixels, byte for byte.

    >>> from ikgame.render.theme import load_theme
    >>> scene = Scene("demo", np.zeros((0, 5)), np.zeros((0, 3)), np.full(2, 8.0), 200.0)
    >>> snap = Snapshot(0.0, 0, np.array([[0, 0], [100, 0], [100, 100.0]]), np.zeros(2), np.zeros(2))
    >>> render_snapshot(scene, snap, Camera.fit(scene, snap.joints[0], (160, 90)),
    ...                 load_theme("light")).size
    (160, 90)
    """
    if isinstance(supersample, bool) or not isinstance(supersample, int):
        raise ValueError(f"supersample must be an int, got {supersample!r}")
    if not 1 <= supersample <= MAX_SUPERSAMPLE:
        raise ValueError(f"supersample must be in 1..{MAX_SUPERSAMPLE}, got {supersample}")
    joints = np.asarray(snapshot.joints, dtype=float)
    if joints.ndim != 2 or joints.shape[1] != 2 or len(joints) < 2:
        raise ValueError(f"snapshot.joints must have shape (n + 1, 2), n >= 1; got {joints.shape}")

    big = camera.scaled(supersample)
    static_big, static = _static_layers(scene, camera, theme, supersample)
    # Measure first: only the rectangle the moving parts touch is drawn and resampled, which
    # is most of the saving, since the Lanczos shrink costs more than all the drawing.
    extent = _Extent()
    _draw_dynamic(_Painter(extent, big, theme, supersample), scene, snapshot, trail)
    image = static.copy()
    boxes = None if extent.box is None else _dirty_boxes(extent.box, camera.size, supersample)
    if boxes is not None:
        paste, crop = boxes
        region = static_big.crop(tuple(v * supersample for v in crop))
        offset = (crop[0] * supersample, crop[1] * supersample)
        painter = _Painter(ImageDraw.Draw(region), big, theme, supersample, offset, region)
        _draw_dynamic(painter, scene, snapshot, trail)
        if supersample > 1:
            region = region.resize((crop[2] - crop[0], crop[3] - crop[1]), Image.Resampling.LANCZOS)
        inner = (paste[0] - crop[0], paste[1] - crop[1], paste[2] - crop[0], paste[3] - crop[1])
        image.paste(region.crop(inner), paste[:2])
    if hud:
        _draw_hud(image, scene, snapshot, theme)
    return image


def _draw_dynamic(
    painter: _Painter, scene: Scene, snapshot: Snapshot, trail: np.ndarray | None
) -> None:
    """Everything that moves, back to front."""
    painter.upcoming_targets(scene, snapshot)
    if trail is not None:
        painter.trail(np.asarray(trail, dtype=float).reshape(-1, 2))
    painter.props(scene, snapshot)
    painter.chain(scene, snapshot)
    _draw_sprites(painter, scene, snapshot)
    if snapshot.target is not None:
        painter.crosshair(np.asarray(snapshot.target, dtype=float))


@lru_cache(maxsize=2)
def _static_layers(
    scene: Scene, camera: Camera, theme: Theme, supersample: int
) -> tuple[Image.Image, Image.Image]:
    """Background, grid, goals and obstacles, supersampled and shrunk: the same for every frame
    of a run, so drawn once. Keyed by the scene's identity (``Scene`` compares by identity)."""
    big = camera.scaled(supersample)
    image = Image.new("RGB", big.size, theme.background)
    painter = _Painter(ImageDraw.Draw(image), big, theme, supersample)
    painter.grid()
    painter.goals(scene)
    painter.obstacles(scene)
    if supersample == 1:
        return image, image
    return image, image.resize(camera.size, Image.Resampling.LANCZOS)


def _dirty_boxes(
    box: tuple[float, float, float, float], size: tuple[int, int], supersample: int
) -> tuple[tuple[int, int, int, int], tuple[int, int, int, int]] | None:
    """Output-pixel boxes for a frame whose moving parts cover drawing-pixel ``box``: the one to
    paste (every pixel the moving parts can change) and the larger one to redraw and shrink, with
    room for the filter's reach, so no pasted pixel misses a neighbour a full-frame shrink uses.
    None when the moving parts are all out of the picture."""
    reach = LANCZOS_REACH if supersample > 1 else 0
    width, height = size

    def grow(b: tuple[int, int, int, int], by: int) -> tuple[int, int, int, int]:
        return (max(0, b[0] - by), max(0, b[1] - by), min(width, b[2] + by), min(height, b[3] + by))

    x0, y0, x1, y1 = box
    touched = (
        math.floor(x0 / supersample),
        math.floor(y0 / supersample),
        math.ceil(x1 / supersample),
        math.ceil(y1 / supersample),
    )
    paste = grow(touched, reach)
    if paste[0] >= paste[2] or paste[1] >= paste[3]:
        return None
    return paste, grow(paste, reach)


class _Extent:
    """Stands in for ``ImageDraw`` on a measuring pass: records the box the primitives touch."""

    def __init__(self) -> None:
        self.box: tuple[float, float, float, float] | None = None

    def _add(self, xy: object, pad: float) -> None:
        points = np.asarray(xy, dtype=float).reshape(-1, 2)
        low, high = points.min(axis=0) - pad, points.max(axis=0) + pad
        if self.box is not None:
            low = np.minimum(low, self.box[:2])
            high = np.maximum(high, self.box[2:])
        self.box = (float(low[0]), float(low[1]), float(high[0]), float(high[1]))

    # Pillow rounds coordinates and grows outlines and wide lines by up to their width: pad.
    def line(self, xy: object, fill: object = None, width: int = 1, **_: object) -> None:
        self._add(xy, width + 1)

    def polygon(
        self, xy: object, fill: object = None, outline: object = None, width: int = 1
    ) -> None:
        self._add(xy, width + 1)

    def ellipse(
        self, xy: object, fill: object = None, outline: object = None, width: int = 1
    ) -> None:
        self._add(xy, 1)


def _blend(base: RGB, color: RGB, alpha: float) -> RGB:
    """``color`` at opacity ``alpha`` over ``base``."""
    return tuple(round(b + (c - b) * alpha) for b, c in zip(base, color, strict=True))  # type: ignore[return-value]


class _Painter:
    """Primitives in world coordinates on one (supersampled) image."""

    def __init__(
        self,
        draw: ImageDraw.ImageDraw | _Extent,
        camera: Camera,
        theme: Theme,
        ss: int,
        offset: tuple[int, int] = (0, 0),
        image: Image.Image | None = None,
    ) -> None:
        self.draw = draw
        # The image ``draw`` draws on, for pasting sprites; None on the measuring pass.
        self.image = image
        self.camera = camera
        self.theme = theme
        self.ss = ss  # drawing pixels per output pixel
        # Drawing px of the image's top-left corner when drawing on a crop of the frame.
        self.offset = np.array(offset, dtype=float)
        # The whole frame in this image's drawing px: what is drawn beyond it is never seen.
        self.frame = (-self.offset, np.array(camera.size, dtype=float) - self.offset)

    def px(self, points: object) -> np.ndarray:
        points = np.asarray(points, dtype=float).reshape(-1, 2)
        return to_draw_coords(self.camera, points) - self.offset

    def circle(
        self,
        center: np.ndarray,
        radius: float,
        fill: RGB | None,
        outline: RGB | None = None,
        width: float = 0.0,
    ) -> None:
        """A circle; ``radius`` and ``width`` in drawing pixels, ``center`` in drawing coords."""
        x, y = center
        box = (x - radius, y - radius, x + radius, y + radius)
        self.draw.ellipse(
            box, fill=fill, outline=outline, width=max(1, round(width)) if outline else 0
        )

    def capsule(self, a: np.ndarray, b: np.ndarray, radius: float, fill: RGB) -> None:
        """A bar with round ends from ``a`` to ``b`` (drawing coords), ``radius`` drawing px."""
        draw_capsule(self.draw, a, b, radius, fill)

    def grid(self) -> None:
        step = _nice_step(GRID_STEP * self.ss / self.camera.scale)
        width, height = self.camera.size
        (x0, y1), (x1, y0) = self.camera.pixel_to_world([[0.0, 0.0], [width, height]])
        line = max(1, round(self.ss))
        for gx in np.arange(math.ceil(x0 / step) * step, x1, step):
            x = self.px([[gx, 0.0]])[0, 0]
            self.draw.line([(x, 0), (x, height)], fill=self.theme.grid, width=line)
        for gy in np.arange(math.ceil(y0 / step) * step, y1, step):
            y = self.px([[0.0, gy]])[0, 1]
            self.draw.line([(0, y), (width, y)], fill=self.theme.grid, width=line)

    def goals(self, scene: Scene) -> None:
        fill = _blend(self.theme.background, self.theme.goal, GOAL_FILL_ALPHA)
        for xmin, ymin, xmax, ymax in np.asarray(scene.goals, dtype=float).reshape(-1, 4):
            (left, top), (right, bottom) = self.px([[xmin, ymax], [xmax, ymin]])
            self.draw.rounded_rectangle(
                (left, top, right, bottom),
                radius=5 * self.ss,
                fill=fill,
                outline=self.theme.goal,
                width=round(2 * self.ss),
            )

    def obstacles(self, scene: Scene) -> None:
        theme, ss = self.theme, self.ss
        segments = np.asarray(scene.segments, dtype=float).reshape(-1, 5)
        for ax, ay, bx, by, radius in segments:
            a, b = self.px([[ax, ay], [bx, by]])
            r = max(radius * self.camera.scale, MIN_OBSTACLE_WIDTH * ss / 2)
            self.capsule(a, b, r + OBSTACLE_OUTLINE * ss, theme.obstacle_outline)
            self.capsule(a, b, r, theme.obstacle)
        for x, y, radius in np.asarray(scene.circles, dtype=float).reshape(-1, 3):
            r = radius * self.camera.scale
            self.circle(
                self.px([[x, y]])[0],
                r,
                theme.obstacle,
                theme.obstacle_outline,
                OBSTACLE_OUTLINE * ss,
            )

    def upcoming_targets(self, scene: Scene, snapshot: Snapshot) -> None:
        """Targets still to come, faded, joined by a dashed path."""
        upcoming = _upcoming(scene, snapshot)
        if not len(upcoming):
            return
        color, ss = self.theme.target_upcoming, self.ss
        path = upcoming if snapshot.target is None else np.vstack([snapshot.target, upcoming])
        points = self.px(path)
        for a, b in zip(points[:-1], points[1:], strict=True):
            _dashed(self.draw, a, b, color, self.frame, width=max(1, round(1.2 * ss)), dash=5 * ss)
        for p in self.px(upcoming):
            self.circle(p, UPCOMING_RADIUS * ss, self.theme.background, color, 2 * ss)

    def trail(self, trail: np.ndarray) -> None:
        if len(trail) < 2:
            return
        points = self.px(trail)
        count = len(points) - 1
        lo, hi = TRAIL_WIDTH
        for i in range(count):
            age = (i + 1) / count  # 1 for the newest segment
            color = _blend(self.theme.background, self.theme.trail, 0.15 + 0.85 * age**1.5)
            radius = (lo + (hi - lo) * age) * self.ss / 2
            self.capsule(points[i], points[i + 1], radius, color)

    def props(self, scene: Scene, snapshot: Snapshot) -> None:
        poses = np.asarray(snapshot.props, dtype=float).reshape(-1, 3)
        if len(poses) != len(scene.props):
            raise ValueError(
                f"snapshot has {len(poses)} prop poses but the scene has {len(scene.props)} props"
            )
        theme, scale, ss = self.theme, self.camera.scale, self.ss
        skinned = _skinned(scene.prop_sprites, len(poses), "prop")
        for shape, (x, y, angle), skin in zip(scene.props, poses, skinned, strict=True):
            if skin:
                continue
            center = self.px([[x, y]])[0]
            if shape.kind == "ball":
                r = shape.size[0] * scale
                self.circle(center, r, theme.prop, theme.prop_outline, 1.5 * ss)
                # A spoke, so a rolling ball visibly rolls.
                edge = self.px(
                    [[x + shape.size[0] * math.cos(angle), y + shape.size[0] * math.sin(angle)]]
                )[0]
                self.draw.line(
                    [tuple(center), tuple(edge)],
                    fill=theme.prop_outline,
                    width=max(1, round(1.5 * ss)),
                )
            elif shape.kind == "box":
                hw, hh = shape.size[0] / 2, shape.size[1] / 2
                c, s = math.cos(angle), math.sin(angle)
                corners = [
                    (x + c * u - s * v, y + s * u + c * v)
                    for u, v in ((-hw, -hh), (hw, -hh), (hw, hh), (-hw, hh))
                ]
                self.draw.polygon(
                    [tuple(p) for p in self.px(corners)],
                    fill=theme.prop,
                    outline=theme.prop_outline,
                    width=max(1, round(1.5 * ss)),
                )
            else:
                raise ValueError(f"unknown prop kind {shape.kind!r}; expected 'ball' or 'box'")

    def chain(self, scene: Scene, snapshot: Snapshot) -> None:
        theme, ss = self.theme, self.ss
        points = self.px(snapshot.joints)
        n = len(points) - 1
        widths = np.asarray(scene.link_widths, dtype=float).reshape(-1)
        if len(widths) != n:
            raise ValueError(f"scene has {len(widths)} link widths for a chain of {n} links")
        radii = np.maximum(widths * self.camera.scale, MIN_LINK_WIDTH * ss) / 2
        limited = np.asarray(snapshot.torque_limited, dtype=bool).reshape(-1)
        if len(limited) not in (0, n):
            raise ValueError(f"torque_limited has {len(limited)} entries for {n} links")

        skinned = _skinned(scene.link_sprites, n, "link")
        self.mount(points[0], radii[0])
        # All outlines first, so where links overlap at a joint the fills merge seamlessly.
        for i in np.flatnonzero(~skinned):
            self.capsule(points[i], points[i + 1], radii[i] + LINK_OUTLINE * ss, theme.link_outline)
        for i in np.flatnonzero(~skinned):
            fill = theme.torque_limited if len(limited) and limited[i] else theme.link
            self.capsule(points[i], points[i + 1], radii[i], fill)
        for i in range(1, n):
            r = max(0.38 * min(radii[i - 1], radii[i]), 1.5 * ss)
            self.circle(points[i], r, theme.joint, theme.link_outline, 1.0 * ss)
        # The base pivot sits on top of link 0, like a bolt.
        self.circle(points[0], max(0.55 * radii[0], 2 * ss), theme.base, theme.joint, 1.2 * ss)
        self.circle(
            points[-1], max(0.6 * radii[-1], 2.5 * ss), theme.effector, theme.link_outline, 1.2 * ss
        )

    def sprite(self, sprite: Sprite, point: np.ndarray, angle: float) -> None:
        """``sprite`` with its pivot on world ``point``, turned by ``angle`` (world radians)."""
        # Sprites are placed in pixel-corner coordinates, half a pixel off Pillow's primitives.
        anchor = tuple(self.px(point)[0] + 0.5)
        if self.image is None:  # the measuring pass: only the box it covers counts
            self.draw.polygon(sprite_corners(sprite, anchor, angle, self.camera.scale))
        else:
            draw_sprite(self.image, sprite, anchor, angle, self.camera.scale)

    def mount(self, base: np.ndarray, link_radius: float) -> None:
        """A pedestal under the base with a hatched ground line, like an engineering drawing."""
        ss = self.ss
        r = max(link_radius * 1.6, 7 * ss)
        x, y = base
        top, bottom = y + 0.2 * r, y + 1.9 * r
        self.draw.polygon(
            [(x - 0.9 * r, top), (x + 0.9 * r, top), (x + 1.5 * r, bottom), (x - 1.5 * r, bottom)],
            fill=self.theme.base,
        )
        self.circle(base, r, self.theme.base)
        ground = max(1, round(1.5 * ss))
        self.draw.line(
            [(x - 2.2 * r, bottom), (x + 2.2 * r, bottom)], fill=self.theme.base, width=ground
        )
        for k in range(9):
            hx = x - 2.0 * r + k * 0.5 * r
            self.draw.line(
                [(hx, bottom), (hx - 0.45 * r, bottom + 0.45 * r)],
                fill=self.theme.base,
                width=max(1, round(ss)),
            )

    def crosshair(self, target: np.ndarray) -> None:
        color, ss = self.theme.target, self.ss
        c = self.px(target)[0]
        r = TARGET_RADIUS * ss
        self.circle(c, r, None, color, 2.0 * ss)
        width = max(1, round(2.0 * ss))
        for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            self.draw.line(
                [
                    (c[0] + dx * 0.45 * r, c[1] + dy * 0.45 * r),
                    (c[0] + dx * 1.6 * r, c[1] + dy * 1.6 * r),
                ],
                fill=color,
                width=width,
            )
        self.circle(c, 1.6 * ss, color)


def _draw_sprites(painter: _Painter, scene: Scene, snapshot: Snapshot) -> None:
    """Prop and link images, over the shapes of the rest (links base first, so each link's
    image lies on its parent's)."""
    poses = np.asarray(snapshot.props, dtype=float).reshape(-1, 3)
    for sprite, (x, y, angle) in zip(scene.prop_sprites, poses, strict=False):
        if sprite is not None:
            painter.sprite(sprite, np.array([x, y]), angle)
    joints = np.asarray(snapshot.joints, dtype=float)
    for i, sprite in enumerate(scene.link_sprites):
        if sprite is not None:
            (ax, ay), (bx, by) = joints[i], joints[i + 1]
            painter.sprite(sprite, joints[i], math.atan2(by - ay, bx - ax))


def _skinned(sprites: tuple[Sprite | None, ...], count: int, what: str) -> np.ndarray:
    """Which of ``count`` links or props have a sprite, (count,) bool."""
    if len(sprites) not in (0, count):
        raise ValueError(f"scene has {len(sprites)} {what} sprites for {count} {what}s")
    return np.array([s is not None for s in sprites] or [False] * count, dtype=bool)


def _upcoming(scene: Scene, snapshot: Snapshot) -> np.ndarray:
    """The scene's targets after the current one, (k, 2).

    ``scene.targets`` lists the reach steps' targets only, so a step index does not say where
    in the list the run is: the current target is found in the list instead. When it is not
    there (a follow step), the list is taken as one target per step if the counts agree, and
    nothing is marked otherwise rather than marking a target already done.
    """
    targets = np.asarray(scene.targets, dtype=float).reshape(-1, 2)
    if snapshot.step_index >= scene.step_count or not len(targets):
        return targets[:0]
    if snapshot.target is not None:
        hits = np.flatnonzero(np.all(np.isclose(targets, snapshot.target), axis=1))
        if len(hits):
            return targets[hits[0] + 1 :]
    if len(targets) == scene.step_count:
        return targets[snapshot.step_index + 1 :]
    return targets[:0]


def draw_capsule(
    draw: ImageDraw.ImageDraw, a: np.ndarray, b: np.ndarray, radius: float, fill: tuple[int, ...]
) -> None:
    """A bar of half-width ``radius`` with round ends, all in drawing coordinates: a link, a
    wall, a pymunk fat segment."""
    ax, ay = float(a[0]), float(a[1])
    bx, by = float(b[0]), float(b[1])
    length = math.hypot(bx - ax, by - ay)
    if length > 1e-9:
        nx, ny = -(by - ay) / length * radius, (bx - ax) / length * radius
        draw.polygon(
            [(ax + nx, ay + ny), (bx + nx, by + ny), (bx - nx, by - ny), (ax - nx, ay - ny)],
            fill=fill,
        )
    for x, y in ((ax, ay), (bx, by)):
        draw.ellipse((x - radius, y - radius, x + radius, y + radius), fill=fill)


def _dashed(
    draw: ImageDraw.ImageDraw | _Extent,
    a: np.ndarray,
    b: np.ndarray,
    color: RGB,
    frame: tuple[np.ndarray, np.ndarray],
    width: int,
    dash: float,
) -> None:
    length = float(np.hypot(*(b - a)))
    if not (math.isfinite(length) and length >= 1e-9):
        return
    direction = (b - a) / length
    # Only the part inside the image is dashed (a far target would ask for millions of dashes);
    # it starts on a whole period so the dashes sit where an unclipped path puts them.
    visible = _clip(a, direction, length, frame, margin=width + dash)
    if visible is None:
        return
    first = math.floor(visible[0] / (2 * dash)) * 2 * dash
    for start in np.arange(first, visible[1], 2 * dash):
        p, q = a + direction * start, a + direction * min(start + dash, length)
        draw.line([tuple(p), tuple(q)], fill=color, width=width)


def _clip(
    a: np.ndarray,
    direction: np.ndarray,
    length: float,
    frame: tuple[np.ndarray, np.ndarray],
    margin: float,
) -> tuple[float, float] | None:
    """The distances along ``a + t * direction``, ``0 <= t <= length``, inside the ``frame``
    (top-left and bottom-right corners) grown by ``margin`` px on every side (Liang-Barsky), or
    None when the segment misses it.

    >>> corners = (np.array([0.0, 0.0]), np.array([20.0, 10.0]))
    >>> _clip(np.array([-10.0, 5.0]), np.array([1.0, 0.0]), 100.0, corners, 0.0)
    (10.0, 30.0)
    """
    lo, hi = 0.0, length
    for axis in (0, 1):
        low, high = frame[0][axis] - margin, frame[1][axis] + margin
        if abs(direction[axis]) < 1e-12:
            if not low <= a[axis] <= high:
                return None
            continue
        t1, t2 = sorted(((low - a[axis]) / direction[axis], (high - a[axis]) / direction[axis]))
        lo, hi = max(lo, t1), min(hi, t2)
    return (float(lo), float(hi)) if lo < hi else None


def _nice_step(raw: float) -> float:
    """The smallest 1, 2 or 5 x 10^k at least ``raw``."""
    exponent = math.floor(math.log10(raw))
    for mantissa in (1.0, 2.0, 5.0, 10.0):
        step = mantissa * 10.0**exponent
        if step >= raw:
            return step
    return 10.0 ** (exponent + 1)


# -- HUD -------------------------------------------------------------------------------------------


@lru_cache(maxsize=8)
def _font(size: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    return ImageFont.load_default(size=size)


def _hud_lines(scene: Scene, snapshot: Snapshot, theme: Theme) -> list[list[tuple[str, RGB]]]:
    """The HUD's text as lines of (text, colour) runs."""
    status_colors = {"success": theme.success, "failure": theme.failure, "blocked": theme.failure}
    stats: list[tuple[str, RGB]] = [(f"t {snapshot.time:.2f} s", theme.hud_text)]
    if scene.step_count:
        if snapshot.step_index >= scene.step_count:
            stats.append(("   steps done", theme.hud_text))
        else:
            stats.append((f"   step {snapshot.step_index + 1}/{scene.step_count}", theme.hud_text))
    error = "-" if not math.isfinite(snapshot.error) else f"{snapshot.error:.1f}"
    stats.append((f"   error {error} px", theme.hud_text))
    status: list[tuple[str, RGB]] = [
        (snapshot.solver_status, status_colors.get(snapshot.solver_status, theme.hud_muted))
    ]
    limited = int(np.count_nonzero(snapshot.torque_limited))
    if limited:
        status.append((f"   {limited} at torque limit", theme.torque_limited))
    return [[(scene.level_name, theme.hud_text)], stats, status]


def _draw_hud(image: Image.Image, scene: Scene, snapshot: Snapshot, theme: Theme) -> None:
    """A translucent panel in the top-left corner with the run's vital numbers."""
    height = image.size[1]
    pad = max(3, round(height * 0.018))
    sizes = [max(9, round(height * 0.032))] + [max(8, round(height * 0.026))] * 2
    lines = _hud_lines(scene, snapshot, theme)
    draw = ImageDraw.Draw(image)
    widths, heights = [], []
    for line, size in zip(lines, sizes, strict=True):
        text = "".join(run for run, _ in line)
        widths.append(draw.textbbox((0, 0), text, font=_font(size), anchor="la")[2])
        heights.append(round(size * 1.3))
    box = (pad, pad, pad + max(widths) + 2 * pad, pad + sum(heights) + pad)
    mask = Image.new("L", image.size, 0)
    ImageDraw.Draw(mask).rounded_rectangle(box, radius=pad, fill=round(255 * HUD_PANEL_ALPHA))
    image.paste(theme.hud_panel, (0, 0), mask)
    y = pad + pad // 2
    for line, size, line_height in zip(lines, sizes, heights, strict=True):
        x, font = 2 * pad, _font(size)
        for text, color in line:
            draw.text((x, y), text, fill=color, font=font, anchor="la")
            x += draw.textlength(text, font=font)
        y += line_height
