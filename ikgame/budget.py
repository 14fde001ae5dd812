"""What a run will cost before it starts: an estimate of its time from the level's sizes.

A level inside every per-field limit can still ask for days of work (200 links, 1000 solver
iterations, 300,000 ticks). :func:`estimate_run` turns the sizes that drive the cost into
seconds, with per-unit costs measured on a 2-core machine; the command line refuses a run whose
estimate is above its budget (``ikgame run --budget MINUTES``, or ``--no-budget``).

The estimate is an upper bound on the work, not a promise about the clock: it assumes the run
lasts the level's whole ``duration`` (a script that ends early stops sooner) and one process
drawing frames.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Final

if TYPE_CHECKING:
    from ikgame.level.model import Level

__all__ = ["RunEstimate", "estimate_run", "DEFAULT_BUDGET_MINUTES"]

DEFAULT_BUDGET_MINUTES: Final = 30.0
"""Estimated minutes a run may take before the command line asks for ``--budget``."""

TICK_US: Final = 150.0
"""Fixed cost of a tick, microseconds: script, controller and world bookkeeping."""
LINK_US: Final = 6.0
"""Cost of one link in the physics step, per tick, microseconds."""
LINK_ITERATION_US: Final = 2.2
"""Cost of one solver iteration over one link, per tick, microseconds."""
OBSTACLE_US: Final = 0.6
"""Cost of one static obstacle, per tick, microseconds (the collision broad phase)."""
PROP_US: Final = 6.0
"""Cost of one dynamic prop, per tick, microseconds."""
PIXEL_NS: Final = 130.0
"""Cost of one pixel of one frame, nanoseconds: drawing, PNG encoding and the GIF."""


@dataclass(frozen=True)
class RunEstimate:
    """The estimated cost of a run.

    Attributes:
        ticks: physics ticks at most (duration x tick_rate).
        link_iterations: ticks x links x solver iterations, the solver's work.
        frames: frames drawn (0 without frames).
        pixels: frames x pixels per frame.
        simulate_s: estimated simulation time, s.
        render_s: estimated drawing and encoding time, s.
    """

    ticks: int
    link_iterations: int
    frames: int
    pixels: int
    simulate_s: float
    render_s: float

    @property
    def seconds(self) -> float:
        """The whole estimate, s."""
        return self.simulate_s + self.render_s

    def describe(self) -> str:
        """One line for a person: the estimate and what drives it.

        >>> RunEstimate(1000, 30000, 0, 0, 0.5, 0.0).describe()
        'about 0.5 s (1000 ticks, 30000 link-iterations, no frames)'
        """
        frames = (
            f"{self.frames} frames of {self.pixels // max(1, self.frames)} px"
            if self.frames
            else "no frames"
        )
        return (
            f"about {_duration(self.seconds)} ({self.ticks} ticks, "
            f"{self.link_iterations} link-iterations, {frames})"
        )


def estimate_run(level: Level, *, frame_size: tuple[int, int] | None = (960, 540)) -> RunEstimate:
    """Estimate a run of ``level``; ``frame_size`` None when no frames are drawn.

    >>> from ikgame.level import DEFAULT_LEVEL, load_level
    >>> estimate_run(load_level(DEFAULT_LEVEL), frame_size=None).ticks
    4800
    """
    ticks = round(level.level.duration * level.world.tick_rate)
    links = len(level.chain.expanded_links)
    iterations = level.chain.iterations
    per_tick_us = (
        TICK_US
        + links * (LINK_US + LINK_ITERATION_US * iterations)
        + len(level.obstacles) * OBSTACLE_US
        + len(level.props) * PROP_US
    )
    frames = 0 if frame_size is None else max(1, round(level.level.duration * level.world.fps))
    pixels = 0 if frame_size is None else frames * frame_size[0] * frame_size[1]
    return RunEstimate(
        ticks=ticks,
        link_iterations=ticks * links * iterations,
        frames=frames,
        pixels=pixels,
        simulate_s=ticks * per_tick_us * 1e-6,
        render_s=pixels * PIXEL_NS * 1e-9,
    )


def _duration(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.2g} s" if seconds < 10 else f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"
