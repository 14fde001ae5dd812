"""Draw a :class:`~ikgame.snapshot.Snapshot` with Pillow.

The scene is drawn at ``supersample`` times the output size and shrunk by averaging each
``supersample`` x ``supersample`` block (``Image.reduce``): Pillow's primitives are not
anti-aliased, and the share of a pixel's sub-pixels an edge covers is exactly the anti-aliased
coverage. A block average is ten times cheaper than a Lanczos shrink of the same sub-pixels and
reaches no neighbouring pixel, so a frame can be shrunk piecewise. The static scene (background,
grid, goals, obstacles) is drawn and shrunk once per run; each frame redraws only the rectangle
its moving parts span, and shrinks and pastes only the tiles they touch: a trail or a dashed path
that crosses the frame touches a diagonal band of tiles, not the rectangle around it. The HUD is
drawn after the shrink so its text stays crisp.
A tree is drawn link by link like a chain, with a joint where each link meets its parent; each
of its end effectors has its own colour (:meth:`~ikgame.render.theme.Theme.effector_styles`) for
its target marker, trail, tip and upcoming targets, and the HUD lists every effector's error.
Links and props that carry a sprite are drawn as their images instead of their shapes
(:func:`_draw_sprites`, with :mod:`ikgame.render.sprites`), over the shapes, under the crosshair.
Translucent layers (goals, trail, faded targets) are blended with the background colour by hand
instead of alpha compositing a full-size layer, which would cost as much as the rest of a frame.

Sizes below are in output pixels unless a name says otherwise.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from functools import lru_cache

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from ikgame.render.camera import Camera
from ikgame.render.sprites import draw_sprite, sprite_corners
from ikgame.render.theme import RGB, EffectorStyle, Theme
from ikgame.snapshot import Scene, Snapshot, Sprite, link_segments

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
HUD_EFFECTORS_PER_LINE = 4  # a tree's per-effector errors, this many to a HUD line
MAX_SUPERSAMPLE = 8  # 8x of a 4K frame is already 2 GB of pixels
DIRTY_TILE = 32  # output px: the side of the tiles a frame's moving parts mark for redrawing
STATIC_STRIP = 64  # output px: rows of the static layer converted to RGB and shrunk at a time


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

    ``trail`` is the end effectors' recent path, oldest first, drawn as a fading line per
    effector: (m, 2) for a single effector, or (m, k, 2) with a column per effector (points that
    are not finite are skipped). Same inputs give the same pixels, byte for byte.

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
    link_segments(scene, snapshot)  # shape checks, before any drawing

    big = camera.scaled(supersample)
    static_big, static = _static_layers(scene, camera, theme, supersample)
    # Record first: only what the moving parts touch is drawn and shrunk, which is most of the
    # saving, since shrinking costs more than all the drawing.
    recording = _Recording()
    _draw_dynamic(_Painter(recording, big, theme, supersample), scene, snapshot, trail)
    image = static.copy()
    rects = _dirty_rects(recording.boxes, camera.size, supersample)
    if rects:
        ss = supersample
        left, top = min(r[0] for r in rects), min(r[1] for r in rects)
        right, bottom = max(r[2] for r in rects), max(r[3] for r in rects)
        region = static_big.crop((left * ss, top * ss, right * ss, bottom * ss)).convert("RGB")
        recording.replay(region, (left * ss, top * ss))
        for x0, y0, x1, y1 in rects:
            tile = region.crop(
                ((x0 - left) * ss, (y0 - top) * ss, (x1 - left) * ss, (y1 - top) * ss)
            )
            image.paste(tile.reduce(ss) if ss > 1 else tile, (x0, y0))
    if hud:
        _draw_hud(image, scene, snapshot, theme)
    return image


def _draw_dynamic(
    painter: _Painter, scene: Scene, snapshot: Snapshot, trail: np.ndarray | None
) -> None:
    """Everything that moves, back to front."""
    styles = painter.theme.effector_styles(len(scene.effectors))
    targets = snapshot.target_points
    if len(targets) != len(styles):
        raise ValueError(
            f"snapshot has {len(targets)} target rows for {len(styles)} effectors (a tree's "
            "Snapshot.targets has one per effector, NaN where there is none)"
        )
    painter.upcoming_targets(scene, snapshot, styles)
    if trail is not None:
        paths = np.asarray(trail, dtype=float)
        paths = paths.reshape(-1, 1, 2) if paths.ndim < 3 else paths
        if paths.shape[1:] != (len(styles), 2):
            raise ValueError(f"trail has shape {paths.shape} for {len(styles)} effectors")
        for j, style in enumerate(styles):
            path = paths[:, j]
            painter.trail(path[np.all(np.isfinite(path), axis=1)], style.trail)
    painter.props(scene, snapshot)
    painter.skeleton(scene, snapshot, styles)
    _draw_sprites(painter, scene, snapshot)
    for target, style in zip(targets, styles, strict=True):
        if np.all(np.isfinite(target)):
            painter.crosshair(target, style.target)


@lru_cache(maxsize=2)
def _static_layers(
    scene: Scene, camera: Camera, theme: Theme, supersample: int
) -> tuple[Image.Image, Image.Image]:
    """Background, grid, goals and obstacles, supersampled and shrunk: the same for every frame
    of a run, so drawn once. Keyed by the scene's identity (``Scene`` compares by identity).

    The supersampled layer is a palette image: its few flat fills are exact palette entries
    (Pillow's primitives do not blend), a byte per pixel where RGB takes four, which at 3x of
    960x540 is 5 MB instead of 19 MB in every process that draws. Each frame converts only the
    region it redraws; the shrunk layer is made from strips, so the RGB layer never exists whole.
    """
    big = camera.scaled(supersample)
    image = Image.new("P", big.size, theme.background)
    painter = _Painter(ImageDraw.Draw(image), big, theme, supersample)
    painter.grid()
    painter.goals(scene)
    painter.obstacles(scene)
    if supersample == 1:
        return image, image.convert("RGB")
    width, height = camera.size
    small = Image.new("RGB", camera.size)
    for top in range(0, height, STATIC_STRIP):
        bottom = min(height, top + STATIC_STRIP)
        rows = image.crop((0, top * supersample, width * supersample, bottom * supersample))
        small.paste(rows.convert("RGB").reduce(supersample), (0, top))
    return image, small


def _dirty_rects(
    boxes: list[tuple[float, float, float, float]], size: tuple[int, int], supersample: int
) -> list[tuple[int, int, int, int]]:
    """Output-pixel rectangles covering every ``DIRTY_TILE`` tile that one of the drawing-pixel
    ``boxes`` touches, inside a frame of ``size``: each row's runs of touched tiles, merged with
    the same runs of the rows below. Empty when the moving parts are all out of the picture.

    >>> _dirty_rects([(0.0, 0.0, 30.0, 30.0), (100.0, 150.0, 110.0, 160.0)], (64, 64), 3)
    [(0, 0, 32, 32), (32, 32, 64, 64)]
    """
    width, height = size
    tile = DIRTY_TILE * supersample  # in drawing px
    columns, rows = math.ceil(width / DIRTY_TILE), math.ceil(height / DIRTY_TILE)
    touched = np.zeros((rows, columns), dtype=bool)
    if boxes:
        spans = np.asarray(boxes, dtype=float) / tile
        # Clipped to the frame at both ends: a box outside it gives an empty slice (a negative
        # bound would count from the far end instead).
        limit = [columns, rows]
        low = np.clip(np.floor(spans[:, :2]), 0, limit).astype(int)
        high = np.clip(np.ceil(spans[:, 2:]), 0, limit).astype(int)
        for c0, r0, c1, r1 in np.hstack([low, high]).tolist():
            touched[r0:r1, c0:c1] = True
    rects: list[tuple[int, int, int, int]] = []
    open_runs: dict[tuple[int, int], int] = {}  # a run of columns -> the row its rectangle began
    for row in range(rows + 1):
        runs = set() if row == rows else set(_runs(touched[row]))
        for run in [r for r in open_runs if r not in runs]:
            rects.append((run[0], open_runs.pop(run), run[1], row))
        for run in runs:
            open_runs.setdefault(run, row)
    return sorted(
        (
            c0 * DIRTY_TILE,
            r0 * DIRTY_TILE,
            min(width, c1 * DIRTY_TILE),
            min(height, r1 * DIRTY_TILE),
        )
        for c0, r0, c1, r1 in rects
    )


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """The ``(start, stop)`` of each run of True in a 1-d boolean array."""
    edges = np.flatnonzero(np.diff(np.concatenate(([False], flags, [False])).astype(np.int8)))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))


class _Recording:
    """Stands in for ``ImageDraw`` on the first pass: keeps each primitive and the box it
    touches, so that the frame is then drawn by replaying them onto the region that changes,
    without running the painter a second time."""

    def __init__(self) -> None:
        self.boxes: list[tuple[float, float, float, float]] = []
        self.calls: list[tuple[str, list[tuple[float, float]], dict[str, object]]] = []

    def _add(self, name: str, xy: Sequence[object], pad: float, options: dict[str, object]) -> None:
        # Plain floats, not NumPy: a frame records hundreds of small primitives.
        if isinstance(xy[0], int | float):
            points = list(zip(xy[0::2], xy[1::2], strict=True))
        else:
            points = [(p[0], p[1]) for p in xy]  # type: ignore[index]
        xs, ys = [p[0] for p in points], [p[1] for p in points]
        self.boxes.append((min(xs) - pad, min(ys) - pad, max(xs) + pad, max(ys) + pad))  # type: ignore[type-var, operator]
        self.calls.append((name, points, options))  # type: ignore[arg-type]

    # Pillow rounds coordinates and grows outlines and wide lines by up to their width: pad.
    def line(self, xy: Sequence[object], fill: object = None, width: int = 1) -> None:
        self._add("line", xy, width + 1, {"fill": fill, "width": width})

    def polygon(
        self, xy: Sequence[object], fill: object = None, outline: object = None, width: int = 1
    ) -> None:
        self._add("polygon", xy, width + 1, {"fill": fill, "outline": outline, "width": width})

    def ellipse(
        self, xy: Sequence[object], fill: object = None, outline: object = None, width: int = 1
    ) -> None:
        self._add("ellipse", xy, 1, {"fill": fill, "outline": outline, "width": width})

    def sprite(
        self, sprite: Sprite, anchor: tuple[float, float], angle: float, scale: float
    ) -> None:
        """A sprite placed as :func:`~ikgame.render.sprites.draw_sprite` places it."""
        corners = sprite_corners(sprite, anchor, angle, scale).tolist()
        self._add(
            "sprite", [anchor, *corners], 2, {"sprite": sprite, "angle": angle, "scale": scale}
        )

    def replay(self, image: Image.Image, offset: tuple[int, int]) -> None:
        """Draw the recorded primitives on ``image``, whose top-left corner is drawing pixel
        ``offset`` of the frame."""
        ox, oy = offset
        draw = ImageDraw.Draw(image)
        for name, points, options in self.calls:
            shifted = [(x - ox, y - oy) for x, y in points]
            if name == "sprite":
                draw_sprite(
                    image, options["sprite"], shifted[0], options["angle"], options["scale"]
                )  # type: ignore[arg-type]
            else:
                getattr(draw, name)(shifted, **options)


def _blend(base: RGB, color: RGB, alpha: float) -> RGB:
    """``color`` at opacity ``alpha`` over ``base``."""
    return tuple(round(b + (c - b) * alpha) for b, c in zip(base, color, strict=True))  # type: ignore[return-value]


class _Painter:
    """Primitives in world coordinates on one (supersampled) image."""

    def __init__(
        self,
        draw: ImageDraw.ImageDraw | _Recording,
        camera: Camera,
        theme: Theme,
        ss: int,
    ) -> None:
        self.draw = draw
        self.camera = camera
        self.theme = theme
        self.ss = ss  # drawing pixels per output pixel
        # The whole frame in drawing px: what is drawn beyond it is never seen.
        self.frame = (np.zeros(2), np.array(camera.size, dtype=float))

    def px(self, points: object) -> np.ndarray:
        points = np.asarray(points, dtype=float).reshape(-1, 2)
        return to_draw_coords(self.camera, points)

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

    def upcoming_targets(
        self, scene: Scene, snapshot: Snapshot, styles: Sequence[EffectorStyle]
    ) -> None:
        """Each effector's targets still to come, faded, joined by a dashed path."""
        ss = self.ss
        currents = snapshot.target_points
        for j, style in enumerate(styles[: len(scene.target_lists)]):
            upcoming = _upcoming(scene, snapshot, j)
            if not len(upcoming):
                continue
            color, current = style.upcoming, currents[j]
            known = np.all(np.isfinite(current))
            path = np.vstack([current, upcoming]) if known else upcoming
            points = self.px(path)
            for a, b in zip(points[:-1], points[1:], strict=True):
                _dashed(
                    self.draw, a, b, color, self.frame, width=max(1, round(1.2 * ss)), dash=5 * ss
                )
            for p in self.px(upcoming):
                self.circle(p, UPCOMING_RADIUS * ss, self.theme.background, color, 2 * ss)

    def trail(self, trail: np.ndarray, trail_color: RGB) -> None:
        """A fading line along ``trail`` (k, 2), oldest first, toward ``trail_color``."""
        if len(trail) < 2:
            return
        points = self.px(trail)
        count = len(points) - 1
        lo, hi = TRAIL_WIDTH
        for i in range(count):
            age = (i + 1) / count  # 1 for the newest segment
            color = _blend(self.theme.background, trail_color, 0.15 + 0.85 * age**1.5)
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

    def skeleton(self, scene: Scene, snapshot: Snapshot, styles: Sequence[EffectorStyle]) -> None:
        """The links (a chain or a tree), their joints, the base and the effectors' tips."""
        theme, ss = self.theme, self.ss
        starts, ends = (self.px(points) for points in link_segments(scene, snapshot))
        n = len(starts)
        widths = np.asarray(scene.link_widths, dtype=float).reshape(-1)
        radii = np.maximum(widths * self.camera.scale, MIN_LINK_WIDTH * ss) / 2
        limited = np.asarray(snapshot.torque_limited, dtype=bool).reshape(-1)
        if len(limited) not in (0, n):
            raise ValueError(f"torque_limited has {len(limited)} entries for {n} links")
        parents = scene.link_parents
        roots = np.flatnonzero(parents < 0)

        skinned = _skinned(scene.link_sprites, n, "link")
        # One pedestal when every root hangs from one point; roots spread over a body hang from
        # a body drawn as a bar between the two roots farthest apart.
        if np.all(starts[roots] == starts[roots[0]]):
            self.mount(starts[roots[0]], radii[roots[0]])
        else:
            hips = starts[roots]
            apart = np.hypot(*(hips[:, None, :] - hips[None, :, :]).transpose(2, 0, 1))
            a, b = np.unravel_index(np.argmax(apart), apart.shape)
            body = 1.6 * float(radii[roots].max())
            self.capsule(hips[a], hips[b], body + LINK_OUTLINE * ss, theme.link_outline)
            self.capsule(hips[a], hips[b], body, theme.base)
        # All outlines first, so where links overlap at a joint the fills merge seamlessly.
        for i in np.flatnonzero(~skinned):
            self.capsule(starts[i], ends[i], radii[i] + LINK_OUTLINE * ss, theme.link_outline)
        for i in np.flatnonzero(~skinned):
            fill = theme.torque_limited if len(limited) and limited[i] else theme.link
            self.capsule(starts[i], ends[i], radii[i], fill)
        for i in np.flatnonzero(parents >= 0):
            r = max(0.38 * min(radii[parents[i]], radii[i]), 1.5 * ss)
            self.circle(starts[i], r, theme.joint, theme.link_outline, 1.0 * ss)
        # The base pivot sits on top of each root link, like a bolt.
        for i in roots:
            self.circle(starts[i], max(0.55 * radii[i], 2 * ss), theme.base, theme.joint, 1.2 * ss)
        for i, style in zip(scene.effectors, styles, strict=True):
            self.circle(
                ends[i], max(0.6 * radii[i], 2.5 * ss), style.tip, theme.link_outline, 1.2 * ss
            )

    def sprite(self, sprite: Sprite, point: np.ndarray, angle: float) -> None:
        """``sprite`` with its pivot on world ``point``, turned by ``angle`` (world radians)."""
        # Sprites are placed in pixel-corner coordinates, half a pixel off Pillow's primitives.
        x, y = self.px(point)[0] + 0.5
        self.draw.sprite(sprite, (float(x), float(y)), angle, self.camera.scale)

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

    def crosshair(self, target: np.ndarray, color: RGB) -> None:
        ss = self.ss
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
    starts, ends = link_segments(scene, snapshot)
    for i, sprite in enumerate(scene.link_sprites):
        if sprite is not None:
            (ax, ay), (bx, by) = starts[i], ends[i]
            painter.sprite(sprite, starts[i], math.atan2(by - ay, bx - ax))


def _skinned(sprites: tuple[Sprite | None, ...], count: int, what: str) -> np.ndarray:
    """Which of ``count`` links or props have a sprite, (count,) bool."""
    if len(sprites) not in (0, count):
        raise ValueError(f"scene has {len(sprites)} {what} sprites for {count} {what}s")
    return np.array([s is not None for s in sprites] or [False] * count, dtype=bool)


def _upcoming(scene: Scene, snapshot: Snapshot, effector: int = 0) -> np.ndarray:
    """The targets of effector number ``effector`` still to come after its current one, (t, 2).

    The lists hold the reach steps' targets only, so a step index does not say where in a list
    the run is: the current target is found in the list instead. When it is not there (a follow
    step), a chain's list is taken as one target per step if the counts agree, and nothing is
    marked otherwise rather than marking a target already done. A tree's effector that has no
    target yet has its whole list still to come.
    """
    targets = scene.target_lists[effector]
    if snapshot.step_index >= scene.step_count or not len(targets):
        return targets[:0]
    current = snapshot.target_points[effector]
    aimed = bool(np.all(np.isfinite(current)))
    if aimed:
        hits = np.flatnonzero(np.all(np.isclose(targets, current), axis=1))
        if len(hits):
            return targets[hits[0] + 1 :]
    if scene.is_tree:
        return targets[:0] if aimed else targets
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
    draw: ImageDraw.ImageDraw | _Recording,
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
    return [
        [(scene.level_name, theme.hud_text)],
        stats,
        *_effector_lines(scene, snapshot, theme),
        status,
    ]


def _effector_lines(scene: Scene, snapshot: Snapshot, theme: Theme) -> list[list[tuple[str, RGB]]]:
    """Each effector's name, in its colour, and its error, px, a few to a line; none for a
    lone effector, whose error the line above already shows."""
    names = scene.effector_names
    if len(names) < 2:
        return []
    errors = snapshot.effector_errors
    if len(errors) != len(names):
        raise ValueError(f"snapshot has {len(errors)} errors for {len(names)} effectors")
    runs = []
    for name, error, style in zip(names, errors, theme.effector_styles(len(names)), strict=True):
        shown = f"{error:.1f}" if math.isfinite(error) else "-"
        runs.append([(name, style.target), (f" {shown}", theme.hud_text)])
    step = HUD_EFFECTORS_PER_LINE
    lines = []
    for start in range(0, len(runs), step):
        line: list[tuple[str, RGB]] = []
        for k, run in enumerate(runs[start : start + step]):
            line += ([("   ", theme.hud_text)] if k else []) + run
        lines.append(line)
    lines[-1].append((" px", theme.hud_text))
    return lines


def _draw_hud(image: Image.Image, scene: Scene, snapshot: Snapshot, theme: Theme) -> None:
    """A translucent panel in the top-left corner with the run's vital numbers."""
    height = image.size[1]
    pad = max(3, round(height * 0.018))
    lines = _hud_lines(scene, snapshot, theme)
    sizes = [max(9, round(height * 0.032))] + [max(8, round(height * 0.026))] * (len(lines) - 1)
    draw = ImageDraw.Draw(image)
    widths, heights = [], []
    for line, size in zip(lines, sizes, strict=True):
        text = "".join(run for run, _ in line)
        widths.append(draw.textbbox((0, 0), text, font=_font(size), anchor="la")[2])
        heights.append(round(size * 1.3))
    right, bottom = pad + max(widths) + 2 * pad, pad + sum(heights) + pad
    # A mask of the panel's size, not the frame's: the paste then touches only the panel.
    mask = Image.new("L", (right + 1, bottom + 1), 0)
    ImageDraw.Draw(mask).rounded_rectangle(
        (pad, pad, right, bottom), radius=pad, fill=round(255 * HUD_PANEL_ALPHA)
    )
    image.paste(theme.hud_panel, (0, 0, right + 1, bottom + 1), mask)
    y = pad + pad // 2
    for line, size, line_height in zip(lines, sizes, heights, strict=True):
        x, font = 2 * pad, _font(size)
        for text, color in line:
            draw.text((x, y), text, fill=color, font=font, anchor="la")
            x += draw.textlength(text, font=font)
        y += line_height
