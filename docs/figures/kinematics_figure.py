"""Draw docs/figures/kinematics.png: a 3-link chain before and after ``solve_ccd``.

The figure illustrates the conventions in ``docs/kinematics.md``: the world frame (x right, y up,
pixels), the base and its direction ``base_angle``, joints numbered from the base, local joint
angles measured from the parent link's direction, and the end effector at the tip of the last
link. The pose comes from ``ikgame.kinematics`` itself, so the picture cannot drift from the code.

Run from the repository root::

    python docs/figures/kinematics_figure.py

Everything is drawn at ``SUPERSAMPLE`` times the final size and downscaled, which is what
anti-aliases Pillow's otherwise jagged lines and circles.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from ikgame.kinematics import Skeleton, forward_kinematics, solve_ccd

WIDTH, HEIGHT = 720, 440  # final image size, px
SUPERSAMPLE = 4  # drawing scale before the downscale that anti-aliases
MARGIN = 50  # free border around the fitted scene, final px
PALETTE_COLOURS = 48  # the figure is flat colour: a small palette keeps the PNG small

LENGTHS = (120.0, 90.0, 60.0)  # link lengths, world px
START_ANGLES = (-1.1, 1.0, 0.8)  # the pose before solving, radians
TARGET = (60.0, 175.0)  # world px
TOLERANCE = 0.5  # arrival distance, world px

# Colours from assets/themes/light.json, so the figure looks like the renderer's output.
BACKGROUND = "#f6f2e9"
GRID = "#e9e3d5"
INK = "#2d3142"
MUTED = "#7a7f8e"
GHOST = "#c9c4b8"
LINK = "#3a78d4"
LINK_OUTLINE = "#1c355e"
JOINT = "#fbf8f1"
EFFECTOR = "#ffb703"
TARGET_COLOUR = "#d62839"
ANGLE = "#9b5de5"

OUTPUT = Path(__file__).with_name("kinematics.png")


class Canvas:
    """World-to-pixel transform and the few primitives the figure needs, at supersampled scale."""

    def __init__(self, points: np.ndarray) -> None:
        lo = points.min(axis=0)
        hi = points.max(axis=0)
        span = np.maximum(hi - lo, 1.0)
        self.scale = min((WIDTH - 2 * MARGIN) / span[0], (HEIGHT - 2 * MARGIN - 20) / span[1])
        # Centre the scene; the extra 20 px at the top leave room for the title.
        self.centre = (lo + hi) / 2
        self.image = Image.new("RGB", (WIDTH * SUPERSAMPLE, HEIGHT * SUPERSAMPLE), BACKGROUND)
        self.draw = ImageDraw.Draw(self.image)
        self.font = ImageFont.load_default(size=13 * SUPERSAMPLE)
        self.small = ImageFont.load_default(size=11 * SUPERSAMPLE)

    def px(self, point) -> tuple[float, float]:
        """World (y up) to supersampled image pixels (y down): the only place y flips."""
        x = (point[0] - self.centre[0]) * self.scale + WIDTH / 2
        y = HEIGHT / 2 + 10 - (point[1] - self.centre[1]) * self.scale
        return x * SUPERSAMPLE, y * SUPERSAMPLE

    def world(self, x: float, y: float) -> np.ndarray:
        """Final image pixels back to world coordinates (the inverse of :meth:`px`)."""
        return self.centre + np.array((x - WIDTH / 2, HEIGHT / 2 + 10 - y)) / self.scale

    def line(self, a, b, colour: str, width: float) -> None:
        self.draw.line([self.px(a), self.px(b)], fill=colour, width=round(width * SUPERSAMPLE))

    def dashed(self, a, b, colour: str, width: float, dash: float = 6.0) -> None:
        a, b = np.asarray(a, float), np.asarray(b, float)
        length = float(np.hypot(*(b - a))) * self.scale
        steps = max(1, int(length // dash))
        for k in range(0, steps, 2):
            self.line(
                a + (b - a) * k / steps, a + (b - a) * min(k + 1, steps) / steps, colour, width
            )

    def dot(self, centre, radius: float, fill: str, outline: str, width: float = 1.5) -> None:
        x, y = self.px(centre)
        r = radius * SUPERSAMPLE
        self.draw.ellipse(
            (x - r, y - r, x + r, y + r),
            fill=fill,
            outline=outline,
            width=round(width * SUPERSAMPLE),
        )

    def arc(self, centre, radius: float, start: float, end: float, colour: str) -> None:
        """Counter-clockwise world arc from angle ``start`` to ``end`` (radians), radius in px."""
        x, y = self.px(centre)
        r = radius * SUPERSAMPLE
        lo, hi = min(start, end), max(start, end)
        # Pillow measures degrees clockwise in image space, so world angles change sign.
        self.draw.arc(
            (x - r, y - r, x + r, y + r),
            start=-math.degrees(hi),
            end=-math.degrees(lo),
            fill=colour,
            width=round(1.5 * SUPERSAMPLE),
        )

    def text(
        self, at, offset, label: str, colour: str = INK, small: bool = False, anchor: str = "mm"
    ) -> None:
        """``label`` at world point ``at`` moved by ``offset`` final px (y down)."""
        x, y = self.px(at)
        position = (x + offset[0] * SUPERSAMPLE, y + offset[1] * SUPERSAMPLE)
        font = self.small if small else self.font
        self.draw.text(position, label, fill=colour, font=font, anchor=anchor)

    def finish(self) -> Image.Image:
        image = self.image.resize((WIDTH, HEIGHT), Image.Resampling.LANCZOS)
        return image.quantize(PALETTE_COLOURS, method=Image.Quantize.MEDIANCUT, dither=0)


def _draw_grid(canvas: Canvas, step: float = 50.0) -> None:
    corner_lo = canvas.centre - np.array((WIDTH, HEIGHT)) / 2 / canvas.scale
    corner_hi = canvas.centre + np.array((WIDTH, HEIGHT)) / 2 / canvas.scale
    for x in np.arange(math.floor(corner_lo[0] / step) * step, corner_hi[0], step):
        canvas.line((x, corner_lo[1] - step), (x, corner_hi[1] + step), GRID, 1)
    for y in np.arange(math.floor(corner_lo[1] / step) * step, corner_hi[1] + step, step):
        canvas.line((corner_lo[0] - step, y), (corner_hi[0] + step, y), GRID, 1)


def _draw_axes(canvas: Canvas, origin: np.ndarray) -> None:
    size = 32 / canvas.scale
    for direction, label, offset in (((1, 0), "x", (8, 0)), ((0, 1), "y (up)", (22, 2))):
        tip = origin + size * np.asarray(direction, float)
        canvas.line(origin, tip, INK, 1.5)
        side = np.array((-direction[1], direction[0]), float) * 4 / canvas.scale
        back = tip - 7 / canvas.scale * np.asarray(direction, float)
        canvas.draw.polygon(
            [canvas.px(tip), canvas.px(back + side), canvas.px(back - side)], fill=INK
        )
        canvas.text(tip, offset, label, small=True)


def _draw_chain(canvas: Canvas, points: np.ndarray, colour: str, outline: str) -> None:
    for a, b in zip(points[:-1], points[1:], strict=True):
        canvas.line(a, b, outline, 9)
        canvas.line(a, b, colour, 6)
    for joint in points[1:-1]:
        canvas.dot(joint, 4.5, JOINT, outline)


def main(output: Path = OUTPUT) -> Path:
    """Solve the figure's reach with ``solve_ccd``, draw both poses, write ``output``."""
    skeleton = Skeleton.chain(LENGTHS)
    before = np.array(START_ANGLES)
    target = np.array(TARGET)
    solution = solve_ccd(skeleton, before, target, max_iterations=50, tolerance=TOLERANCE)
    points_before, _ = forward_kinematics(skeleton, before)
    points_after, world_after = forward_kinematics(skeleton, solution.angles)

    canvas = Canvas(np.vstack((points_before, points_after, target)))
    _draw_grid(canvas)
    _draw_axes(canvas, canvas.world(28, HEIGHT - 24))
    base = skeleton.base

    # The base direction: angles[0] is measured from it (base_angle = 0 here, so along +x).
    ray_end = base + 70 * np.array((math.cos(skeleton.base_angle), math.sin(skeleton.base_angle)))
    canvas.dashed(base, ray_end, MUTED, 1.2)
    canvas.text(base, (22, 13), "base direction (base_angle = 0)", MUTED, small=True, anchor="lm")

    _draw_chain(canvas, points_before, GHOST, MUTED)
    canvas.text(points_before[-1], (10, 0), "before", MUTED, anchor="lm")

    # Each joint's local angle: from the parent link's direction (dashed) to its own link.
    parent_world = np.concatenate(([skeleton.base_angle], world_after[:-1]))
    for i, (joint, start, angle) in enumerate(
        zip(points_after[:-1], parent_world, solution.angles, strict=True)
    ):
        radius = 34.0 if i else 70.0
        if i:
            extension = joint + 45 * np.array((math.cos(start), math.sin(start)))
            canvas.dashed(joint, extension, ANGLE, 1.2, dash=4.0)
        canvas.arc(joint, radius, start, start + angle, ANGLE)
        # Labels sit just right of each joint, where this pose leaves the page empty.
        label_at = joint + (radius + 8) / canvas.scale * np.array((math.cos(0.2), math.sin(0.2)))
        label = f"angles[{i}] = {angle:+.2f} rad"
        canvas.text(label_at, (0, 0), label, ANGLE, small=True, anchor="lm")

    _draw_chain(canvas, points_after, LINK, LINK_OUTLINE)
    bx, by = canvas.px(base)
    half = 7 * SUPERSAMPLE
    canvas.draw.rectangle((bx - half, by - half, bx + half, by + half), fill=INK)
    canvas.text(base, (-14, 0), "base = joint 0", INK, anchor="rm")
    for i, joint in enumerate(points_after[1:-1], start=1):
        canvas.text(joint, (-38, -4), f"joint {i}", INK)
    canvas.dot(points_after[-1], 6, EFFECTOR, LINK_OUTLINE)
    canvas.text(points_after[-1], (-14, -12), "end effector", INK, anchor="rm")

    cross = 9 / canvas.scale
    canvas.line(target - (cross, 0), target + (cross, 0), TARGET_COLOUR, 2)
    canvas.line(target - (0, cross), target + (0, cross), TARGET_COLOUR, 2)
    canvas.dot(target, 2, TARGET_COLOUR, TARGET_COLOUR, 1)
    label = f"target ({TARGET[0]:g}, {TARGET[1]:g})"
    canvas.text(target, (14, -12), label, TARGET_COLOUR, anchor="lm")

    title = (
        f"solve_ccd: {solution.status.value} in {solution.iterations} iterations, "
        f"error {solution.error:.2f} px (tolerance {TOLERANCE} px)"
    )
    canvas.draw.text(
        (WIDTH * SUPERSAMPLE / 2, 16 * SUPERSAMPLE), title, fill=INK, font=canvas.font, anchor="mm"
    )

    output.parent.mkdir(parents=True, exist_ok=True)
    canvas.finish().save(output, optimize=True)
    return output


if __name__ == "__main__":
    written = main(Path(sys.argv[1]) if len(sys.argv) > 1 else OUTPUT)
    print(f"wrote {written} ({written.stat().st_size} bytes)")
