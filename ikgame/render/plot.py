"""The solver comparison as a picture: end-effector error against time per solver (left) and each
solver's end-effector path (right).

Plain data in, a Pillow image out. :class:`ComparisonPlot` holds names, numbers and arrays only,
so this module knows nothing of the simulation that measured them: ``ikgame.compare`` builds one
with ``Comparison.plot_data()`` and tests build them by hand. :func:`render_comparison` draws it.

Units: time s, lengths and errors px (world units, y up), sizes of the picture in pixels.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
from PIL import Image, ImageDraw, ImageFont

__all__ = [
    "ERROR_FLOOR",
    "SOLVER_COLOURS",
    "SUPERSAMPLE",
    "ComparisonPlot",
    "SolverTrace",
    "render_comparison",
]

SOLVER_COLOURS: Final[Mapping[str, tuple[int, int, int]]] = {
    "ccd": (213, 94, 0),
    "jacobian_transpose": (0, 114, 178),
    "dls": (0, 158, 115),
    "fabrik": (204, 121, 167),
}
"""Line colour per solver (Okabe-Ito, readable with colour-blindness), fixed so that one solver
has the same colour in every figure."""

_EXTRA_COLOURS: Final = ((230, 159, 0), (86, 180, 233), (120, 120, 120), (0, 0, 0))
"""For solvers registered later than this module was written."""

SUPERSAMPLE: Final = 3
"""The plot is drawn this many times larger and shrunk: Pillow's lines are not anti-aliased."""

ERROR_FLOOR: Final = 0.01
"""px: the log error axis starts no lower than this (an error of 0 would be at minus infinity)."""


def _array(name: str, value: object, shape: str) -> np.ndarray:
    """``value`` as a float array of ``shape`` ("k" or "k,2"); ValueError naming the field."""
    array = np.asarray(value, dtype=float)
    if shape == "k,2" and array.size == 0:
        array = array.reshape(0, 2)
    if array.ndim != shape.count(",") + 1 or (shape == "k,2" and array.shape[1] != 2):
        raise ValueError(f"{name} must be ({shape}), got shape {array.shape}")
    return array


@dataclass(frozen=True, eq=False)
class SolverTrace:
    """One solver's run, as the plot draws it. Sequences are accepted and stored as arrays.

    Attributes:
        solver: the solver's name; it picks the colour (:data:`SOLVER_COLOURS`).
        status: ``passed``, ``failed`` or ``diverged``, shown next to the name.
        sim_time: simulated time the run took, s; the longest run sets the time axis.
        path_length: distance the end effector travelled, px, shown over its path (a tree's:
            every effector's, added up).
        times: (ticks,) simulated time at the end of each tick, s.
        errors: (ticks,) end-effector distance to the target after each tick, px; NaN (no
            target) breaks the line.
        path: (k, 2) end-effector positions, px (a tree's first effector).
        other_paths: a tree's other effectors' positions, (k, 2) px each, drawn like ``path``.
        target_trails: the route of each moving target, (m, 2) px each, drawn as a pale band.
    """

    solver: str
    status: str
    sim_time: float
    path_length: float
    times: np.ndarray
    errors: np.ndarray
    path: np.ndarray
    other_paths: tuple[np.ndarray, ...] = ()
    target_trails: tuple[np.ndarray, ...] = ()

    def __post_init__(self) -> None:
        times = _array("times", self.times, "k")
        errors = _array("errors", self.errors, "k")
        if times.shape != errors.shape:
            raise ValueError(
                f"times and errors must have one value per tick, got {times.size} and {errors.size}"
            )
        path = _array("path", self.path, "k,2")
        others = tuple(_array("each of other_paths", p, "k,2") for p in self.other_paths)
        if not all(len(p) for p in (path, *others)):
            raise ValueError("every path must have at least one point")
        trails = tuple(_array("each target trail", t, "k,2") for t in self.target_trails)
        object.__setattr__(self, "times", times)
        object.__setattr__(self, "errors", errors)
        object.__setattr__(self, "path", path)
        object.__setattr__(self, "other_paths", others)
        object.__setattr__(self, "target_trails", trails)

    @property
    def paths(self) -> tuple[np.ndarray, ...]:
        """Every effector's path, the first effector's first."""
        return (self.path, *self.other_paths)


@dataclass(frozen=True, eq=False)
class ComparisonPlot:
    """Everything :func:`render_comparison` draws. Sequences are accepted and stored as arrays.

    Attributes:
        level: the level's name, in the title.
        traces: one :class:`SolverTrace` per solver, in legend order (the first is drawn on top).
        base: where the chain is mounted, px.
        reach: the chain's length, px: the circle of reach around the base.
        start_pose: (n + 1, 2) joint positions then the end effector before the first tick, px.
        reach_points: (k, 2) the reach targets in the order the script ran them, px.
        tolerance: the reach tolerance, px, marked on the error axis (None: not marked).
    """

    level: str
    traces: tuple[SolverTrace, ...]
    base: tuple[float, float]
    reach: float
    start_pose: np.ndarray
    reach_points: np.ndarray
    tolerance: float | None = None

    def __post_init__(self) -> None:
        if not self.traces:
            raise ValueError("a comparison plot needs at least one solver trace")
        object.__setattr__(self, "traces", tuple(self.traces))
        object.__setattr__(self, "start_pose", _array("start_pose", self.start_pose, "k,2"))
        object.__setattr__(self, "reach_points", _array("reach_points", self.reach_points, "k,2"))


# Sizes in output pixels; _Canvas multiplies by SUPERSAMPLE.

_INK: Final = (40, 40, 40)
_MUTED: Final = (110, 110, 110)
_GRID: Final = (228, 228, 228)
_FAINT: Final = (200, 200, 200)
_BACKGROUND: Final = (255, 255, 255)
_MIN_SIZE: Final = (480, 240)
_MAX_SIZE: Final = (4000, 3000)


class _Canvas:
    """An ImageDraw that takes output-pixel coordinates and draws at SUPERSAMPLE times them."""

    def __init__(self, size: tuple[int, int], background: tuple[int, int, int]) -> None:
        self.image = Image.new("RGB", (size[0] * SUPERSAMPLE, size[1] * SUPERSAMPLE), background)
        self.draw = ImageDraw.Draw(self.image)

    def line(self, points: Sequence[tuple[float, float]], colour, width: float = 1.0) -> None:
        scaled = [(x * SUPERSAMPLE, y * SUPERSAMPLE) for x, y in points]
        self.draw.line(scaled, fill=colour, width=max(1, round(width * SUPERSAMPLE)), joint="curve")

    def dashed(self, a: tuple[float, float], b: tuple[float, float], colour, dash: float = 6.0):
        length = math.dist(a, b)
        count = max(1, int(length / dash))
        for i in range(0, count, 2):
            t0, t1 = i / count, min(i + 1, count) / count
            self.line([_lerp(a, b, t0), _lerp(a, b, t1)], colour)

    def circle(self, centre, radius: float, *, fill=None, outline=None, width: float = 1.0):
        x, y, r = (v * SUPERSAMPLE for v in (*centre, radius))
        self.draw.ellipse(
            (x - r, y - r, x + r, y + r),
            fill=fill,
            outline=outline,
            width=max(1, round(width * SUPERSAMPLE)),
        )

    def rect(self, box, *, fill=None, outline=None, width: float = 1.0) -> None:
        self.draw.rectangle(
            [v * SUPERSAMPLE for v in box],
            fill=fill,
            outline=outline,
            width=max(1, round(width * SUPERSAMPLE)),
        )

    def text(self, xy, text: str, colour=_INK, size: float = 13, anchor: str = "la") -> None:
        self.draw.text(
            (xy[0] * SUPERSAMPLE, xy[1] * SUPERSAMPLE),
            text,
            fill=colour,
            font=_font(round(size * SUPERSAMPLE)),
            anchor=anchor,
        )

    def text_width(self, text: str, size: float = 13) -> float:
        return self.draw.textlength(text, font=_font(round(size * SUPERSAMPLE))) / SUPERSAMPLE

    def finish(self) -> Image.Image:
        width, height = self.image.size
        return self.image.resize(
            (width // SUPERSAMPLE, height // SUPERSAMPLE), Image.Resampling.LANCZOS
        )


def _font(size: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    if size not in _FONTS:
        _FONTS[size] = ImageFont.load_default(size=size)
    return _FONTS[size]


_FONTS: dict[int, ImageFont.FreeTypeFont | ImageFont.ImageFont] = {}


def _lerp(a, b, t: float) -> tuple[float, float]:
    return (a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t)


def _colour(plot: ComparisonPlot, solver: str) -> tuple[int, int, int]:
    if solver in SOLVER_COLOURS:
        return SOLVER_COLOURS[solver]
    others = [t.solver for t in plot.traces if t.solver not in SOLVER_COLOURS]
    return _EXTRA_COLOURS[others.index(solver) % len(_EXTRA_COLOURS)]


def render_comparison(plot: ComparisonPlot, size: tuple[int, int] = (1200, 560)) -> Image.Image:
    """The comparison as a picture: error against time per solver (left), paths (right).

    The left panel plots the end-effector error (px, log scale: errors span from hundreds of px
    down to fractions of one) against simulated time, one coloured line per solver, with the
    reach tolerance dashed. The right panel draws each solver's end-effector path (a tree's: one
    per effector) in its own small map, all at one scale, with the start pose, the base and the
    numbered targets.

    >>> trace = SolverTrace("ccd", "passed", sim_time=1.0, path_length=90.0,
    ...     times=[0.5, 1.0], errors=[40.0, 2.0], path=[(120, 0), (90, 40), (60, 60)])
    >>> plot = ComparisonPlot("Demo", (trace,), base=(0, 0), reach=120.0,
    ...     start_pose=[(0, 0), (60, 0), (120, 0)], reach_points=[(60, 60)], tolerance=6.0)
    >>> render_comparison(plot, size=(600, 300)).size
    (600, 300)
    """
    width, height = _check_size(size)
    canvas = _Canvas((width, height), _BACKGROUND)
    canvas.text((16, 12), f"{plot.level}: solver comparison", size=17)
    split = round(width * 0.5)
    _legend(canvas, plot, (16, 42), split - 24)
    _error_panel(canvas, plot, (66, 94, split - 24, height - 48))
    _path_panels(canvas, plot, (split + 8, 12, width - 12, height - 12))
    return canvas.finish()


def _check_size(size: object) -> tuple[int, int]:
    try:
        width, height = size  # type: ignore[misc]
    except (TypeError, ValueError):
        raise ValueError(f"size must be (width, height) in px, got {size!r}") from None
    for value in (width, height):
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"size must be two ints, got {size!r}")
    if not (_MIN_SIZE[0] <= width <= _MAX_SIZE[0] and _MIN_SIZE[1] <= height <= _MAX_SIZE[1]):
        raise ValueError(
            f"size must be from {_MIN_SIZE[0]}x{_MIN_SIZE[1]} to {_MAX_SIZE[0]}x{_MAX_SIZE[1]} "
            f"px, got {width}x{height}"
        )
    return width, height


def _error_panel(canvas: _Canvas, plot: ComparisonPlot, box) -> None:
    left, top, right, bottom = box
    finite = np.concatenate([t.errors[np.isfinite(t.errors)] for t in plot.traces])
    positive = finite[finite > 0]
    low = max(ERROR_FLOOR, float(positive.min()) if positive.size else 1.0)
    high = float(finite.max()) if finite.size else 10.0
    if plot.tolerance is not None:
        high = max(high, plot.tolerance)
    lo_exp, hi_exp = math.floor(math.log10(low)), math.ceil(math.log10(high))
    hi_exp = max(hi_exp, lo_exp + 1)
    t_max = max(t.sim_time for t in plot.traces) or 1.0

    def px(t: float, e: float) -> tuple[float, float]:
        frac = (math.log10(max(e, 10.0**lo_exp)) - lo_exp) / (hi_exp - lo_exp)
        return (left + (right - left) * t / t_max, bottom - (bottom - top) * frac)

    for exp in range(lo_exp, hi_exp + 1):
        y = px(0.0, 10.0**exp)[1]
        canvas.line([(left, y), (right, y)], _GRID)
        canvas.text((left - 7, y), _decade_label(exp), _MUTED, 12, "rm")
        for minor in range(2, 10) if exp < hi_exp else ():
            ym = px(0.0, minor * 10.0**exp)[1]
            canvas.line([(left - 3, ym), (left, ym)], _FAINT)
    step = _nice_step(t_max / 6)
    for i in range(int(t_max / step + 1e-9) + 1):
        x = px(i * step, 1.0)[0]
        canvas.line([(x, top), (x, bottom)], _GRID)
        canvas.line([(x, bottom), (x, bottom + 4)], _INK)
        canvas.text((x, bottom + 7), f"{i * step:g}", _MUTED, 12, "ma")
    canvas.line([(left, top), (left, bottom), (right, bottom)], _INK)
    title = "end-effector error (px, log scale)"
    if plot.tolerance is not None:
        title += ", dashed: reach tolerance"
    canvas.text((left - 50, top - 22), title, _INK, 13)
    canvas.text(((left + right) / 2, bottom + 25), "simulated time (s)", _INK, 13, "ma")
    if plot.tolerance is not None:
        # Marked on the axis, not in the plot, where a label would hide the lines it labels.
        y = px(0.0, plot.tolerance)[1]
        canvas.dashed((left, y), (right, y), _MUTED)
        canvas.text((left - 7, y), f"{plot.tolerance:g}", _MUTED, 11, "rm")
    # The first solver is drawn last, on top: it is usually the reference.
    for trace in reversed(plot.traces):
        for segment in _finite_segments(trace.times, trace.errors):
            canvas.line([px(t, e) for t, e in segment], _colour(plot, trace.solver), 1.6)


def _legend(canvas: _Canvas, plot: ComparisonPlot, top_left, right: float) -> None:
    """One entry per solver (line, name, status), flowing left to right, wrapping at ``right``."""
    x, y = top_left
    for trace in plot.traces:
        text = f"{trace.solver} ({trace.status}, {trace.sim_time:.2f} s)"
        entry = 30 + canvas.text_width(text, 12) + 18
        if x > top_left[0] and x + entry > right:
            x, y = top_left[0], y + 18
        canvas.line([(x, y), (x + 24, y)], _colour(plot, trace.solver), 3.0)
        canvas.text((x + 30, y), text, _INK, 12, "lm")
        x += entry


def _finite_segments(times: np.ndarray, values: np.ndarray) -> list[list[tuple[float, float]]]:
    """Runs of consecutive finite samples: a tick without a target breaks the line."""
    segments, current = [], []
    for t, v in zip(times.tolist(), values.tolist(), strict=True):
        if math.isfinite(v):
            current.append((t, v))
        elif current:
            segments.append(current)
            current = []
    if current:
        segments.append(current)
    return [s if len(s) > 1 else s * 2 for s in segments]


def _decade_label(exp: int) -> str:
    return f"{10.0**exp:g}" if -3 <= exp <= 4 else f"1e{exp}"


def _nice_step(raw: float) -> float:
    """The smallest of 1, 2, 5 x 10^k at least ``raw``."""
    base = 10.0 ** math.floor(math.log10(raw))
    return next(m * base for m in (1, 2, 5, 10) if m * base >= raw - 1e-12)


def _path_panels(canvas: _Canvas, plot: ComparisonPlot, box) -> None:
    left, top, right, bottom = box
    count = len(plot.traces)
    cols = 1 if count == 1 else 2
    rows = math.ceil(count / cols)
    gap = 10
    cell_w = (right - left - gap * (cols - 1)) / cols
    cell_h = (bottom - top - gap * (rows - 1)) / rows
    points = [plot.start_pose, plot.reach_points, np.array([plot.base])]
    points += [path for trace in plot.traces for path in trace.paths]
    every = np.concatenate([p.reshape(-1, 2) for p in points])
    every = every[np.all(np.isfinite(every), axis=1)]
    lo, hi = every.min(axis=0), every.max(axis=0)
    span = np.maximum(hi - lo, 1.0)
    header, margin = 22, 20  # px: the cell's title row; room for target numbers at the edges
    scale = min((cell_w - 2 * margin) / span[0], (cell_h - header - 2 * margin) / span[1])
    for i, trace in enumerate(plot.traces):
        x0 = left + (i % cols) * (cell_w + gap)
        y0 = top + (i // cols) * (cell_h + gap)
        centre = np.array([x0 + cell_w / 2, y0 + header + (cell_h - header) / 2])
        mid = (lo + hi) / 2

        def to_px(p, centre=centre, mid=mid) -> list[tuple[float, float]]:
            p = np.asarray(p, dtype=float).reshape(-1, 2)
            x = centre[0] + (p[:, 0] - mid[0]) * scale
            y = centre[1] - (p[:, 1] - mid[1]) * scale
            return list(zip(x.tolist(), y.tolist(), strict=True))

        _path_cell(canvas, plot, trace, (x0, y0, x0 + cell_w, y0 + cell_h), to_px, scale)


def _path_cell(canvas: _Canvas, plot: ComparisonPlot, trace: SolverTrace, box, to_px, scale):
    x0, y0, x1, y1 = box
    colour = _colour(plot, trace.solver)
    canvas.rect(box, outline=_FAINT)
    canvas.text((x0 + 8, y0 + 6), trace.solver, colour, 14)
    room = x1 - x0 - 24 - canvas.text_width(trace.solver, 14)
    for info in (f"path {trace.path_length:.0f} px, {trace.status}", f"{trace.path_length:.0f} px"):
        if canvas.text_width(info, 12) <= room:
            canvas.text((x1 - 8, y0 + 7), info, _MUTED, 12, "ra")
            break
    # Content is clipped to the cell by drawing it on a sub-canvas of the cell's size.
    cell = _Canvas((round(x1 - x0) - 2, round(y1 - y0) - 24), _BACKGROUND)

    def local(points) -> list[tuple[float, float]]:
        return [(x - x0 - 1, y - y0 - 23) for x, y in to_px(points)]

    base = local(plot.base)[0]
    cell.circle(base, plot.reach * scale, outline=_GRID)
    cell.line(local(plot.start_pose), _FAINT, 4.0)
    # A wide pale band under the effector's line: the route the target took.
    for trail in trace.target_trails:
        cell.line(local(trail), _GRID, 7.0)
    for path in trace.paths:
        cell.line(local(path), colour, 1.5)
        cell.circle(local(path[-1])[0], 3.0, fill=colour)
    cell.rect((base[0] - 4, base[1] - 4, base[0] + 4, base[1] + 4), fill=_INK)
    for number, point in enumerate(local(plot.reach_points), start=1):
        cell.circle(point, 6.0, outline=_INK, width=1.5)
        cell.text((point[0] + 8, point[1] - 8), str(number), _INK, 12, "lb")
    canvas.image.paste(cell.image, (round((x0 + 1) * SUPERSAMPLE), round((y0 + 23) * SUPERSAMPLE)))
