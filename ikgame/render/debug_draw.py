"""Draw any pymunk Space with Pillow, for debugging: pymunk's debug drawing with a Pillow backend.

pymunk ships backends for pygame and matplotlib; its Pillow one was moved out of the package.
This fills that gap the way pymunk's own backends are written: one small subclass of
``pymunk.SpaceDebugDrawOptions`` overriding only the five drawing primitives. The world-to-pixel
transform is the one :func:`~ikgame.render.pillow.render_snapshot` uses,
:func:`~ikgame.render.pillow.to_draw_coords`, so a debug drawing through a run's camera lines up
with that run's frames pixel for pixel.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pymunk
from PIL import Image, ImageDraw
from pymunk.space_debug_draw_options import SpaceDebugColor

from ikgame.render.camera import Camera
from ikgame.render.pillow import draw_capsule, to_draw_coords

__all__ = ["PillowDrawOptions"]


class PillowDrawOptions(pymunk.SpaceDebugDrawOptions):
    """Draw any pymunk Space onto a Pillow image: ``space.debug_draw(options)``.

    Only the five drawing primitives are overridden, each going through one world-to-pixel
    transform (:func:`~ikgame.render.pillow.to_draw_coords`), so shape colours, flags and
    ``shape.color`` work as in pymunk's own backends. Without a camera the world origin is the
    image's bottom-left corner, 1 world px per image px, y up.

    >>> image = Image.new("RGB", (64, 64), "white")
    >>> space = pymunk.Space()
    >>> space.add(pymunk.Segment(space.static_body, (8, 8), (56, 8), 2))
    >>> space.debug_draw(PillowDrawOptions(image))
    >>> image.getpixel((32, 55)) != (255, 255, 255)
    True
    """

    def __init__(self, image: Image.Image, camera: Camera | None = None) -> None:
        super().__init__()
        width, height = image.size
        if camera is None:
            camera = Camera((width, height), center=(width / 2, height / 2), scale=1.0)
        if camera.size != image.size:
            raise ValueError(f"camera size {camera.size} differs from image size {image.size}")
        self.image = image
        self.camera = camera
        # "RGBA" drawing blends colours with alpha < 255 into an RGB image instead of ignoring it.
        self._draw = ImageDraw.Draw(image, "RGBA")

    def _px(self, point: Sequence[float]) -> np.ndarray:
        return to_draw_coords(self.camera, [point])[0]

    def draw_circle(
        self,
        pos: pymunk.Vec2d,
        angle: float,
        radius: float,
        outline_color: SpaceDebugColor,
        fill_color: SpaceDebugColor,
    ) -> None:
        x, y = self._px(pos)
        r = max(radius * self.camera.scale, 0.5)
        self._draw.ellipse(
            (x - r, y - r, x + r, y + r), fill=fill_color.as_int(), outline=outline_color.as_int()
        )
        # A spoke from the centre shows the body's rotation.
        edge = self._px(pos + pymunk.Vec2d.from_polar(radius, angle))
        self._draw.line([(x, y), tuple(edge)], fill=outline_color.as_int(), width=1)

    def draw_segment(self, a: pymunk.Vec2d, b: pymunk.Vec2d, color: SpaceDebugColor) -> None:
        self._draw.line([tuple(self._px(a)), tuple(self._px(b))], fill=color.as_int(), width=1)

    def draw_fat_segment(
        self,
        a: pymunk.Vec2d,
        b: pymunk.Vec2d,
        radius: float,
        outline_color: SpaceDebugColor,
        fill_color: SpaceDebugColor,
    ) -> None:
        draw_capsule(
            self._draw,
            self._px(a),
            self._px(b),
            max(radius * self.camera.scale, 0.5),
            fill_color.as_int(),
        )

    def draw_polygon(
        self,
        verts: Sequence[pymunk.Vec2d],
        radius: float,
        outline_color: SpaceDebugColor,
        fill_color: SpaceDebugColor,
    ) -> None:
        points = [tuple(self._px(v)) for v in verts]
        self._draw.polygon(points, fill=fill_color.as_int(), outline=outline_color.as_int())
        if radius > 0:
            # A rounded polygon: its edges are fat segments, as in pymunk's own backends.
            r = radius * self.camera.scale
            for i in range(len(verts)):
                draw_capsule(
                    self._draw,
                    self._px(verts[i]),
                    self._px(verts[(i + 1) % len(verts)]),
                    r,
                    outline_color.as_int(),
                )

    def draw_dot(self, size: float, pos: pymunk.Vec2d, color: SpaceDebugColor) -> None:
        # pymunk gives dot sizes in screen pixels (constraint anchors), so no camera scale.
        x, y = self._px(pos)
        self._draw.ellipse((x - size, y - size, x + size, y + size), fill=color.as_int())
