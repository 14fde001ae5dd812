"""The level format as a validated, frozen pydantic model.

Level files use degrees and seconds; :class:`Level` keeps the file's values as written (so the
JSON Schema and error messages speak the file's units) and offers radian views where the
simulation needs them. Every range here is a guard against typos and hostile files alike.
"""

from __future__ import annotations

import math
from typing import Annotated, Final, Literal

from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag, model_validator

__all__ = [
    "MAX_LINKS",
    "MAX_DURATION",
    "MAX_STEPS",
    "Level",
    "LevelInfo",
    "WorldConfig",
    "ChainConfig",
    "LinkConfig",
    "SegmentObstacle",
    "CircleObstacle",
    "ReachStep",
    "WaitStep",
    "Step",
    "SOLVER_NAMES",
]

MAX_LINKS: Final = 200
"""Links in one chain, after ``repeat`` is expanded."""
MAX_DURATION: Final = 600.0
"""Simulated seconds in one level."""
MAX_STEPS: Final = 500
"""Script steps in one level."""
MAX_COORD: Final = 1.0e5
"""Largest coordinate or length, px: beyond it the camera and physics lose all meaning."""

SOLVER_NAMES: Final = ("ccd", "jacobian_transpose", "dls", "fabrik")

Coord = Annotated[float, Field(ge=-MAX_COORD, le=MAX_COORD, allow_inf_nan=False)]
Vec2 = tuple[Coord, Coord]
Length = Annotated[float, Field(gt=0, le=MAX_COORD, allow_inf_nan=False)]
Seconds = Annotated[float, Field(gt=0, le=MAX_DURATION, allow_inf_nan=False)]
Degrees = Annotated[float, Field(ge=-180.0, le=180.0, allow_inf_nan=False)]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class LevelInfo(_Model):
    """``[level]``: name, description and how long the level may run."""

    name: str = Field(min_length=1, max_length=80, description="Display name.")
    description: str = Field("", max_length=2000, description="What the level teaches.")
    duration: Seconds = Field(description="Simulated time at most, s.")
    expect: Literal["passed", "failed"] = Field(
        "passed",
        description="The status the level is designed to end with ('failed' for a level that "
        "shows the failure state on purpose).",
    )


class WorldConfig(_Model):
    """``[world]``: gravity, damping and the fixed clocks of the run."""

    gravity: Vec2 = Field((0.0, -900.0), description="Gravity, px/s^2 (y up).")
    damping: float = Field(
        0.9,
        gt=0,
        le=1,
        allow_inf_nan=False,
        description="Fraction of velocity bodies keep after one second (1 = no damping).",
    )
    tick_rate: int = Field(240, ge=30, le=2000, description="Physics ticks per second.")
    fps: int = Field(30, ge=1, le=120, description="Recorded frames per second.")
    bounds: tuple[Coord, Coord, Coord, Coord] | None = Field(
        None, description="Camera bounds (xmin, ymin, xmax, ymax), px; fitted when absent."
    )

    @model_validator(mode="after")
    def _bounds_ordered(self) -> WorldConfig:
        if self.bounds is not None:
            xmin, ymin, xmax, ymax = self.bounds
            if xmin >= xmax or ymin >= ymax:
                raise ValueError(
                    "bounds must be (xmin, ymin, xmax, ymax) with xmin < xmax, ymin < ymax"
                )
        return self


class LinkConfig(_Model):
    """``[[chain.links]]``: one link (or ``repeat`` identical links) and its joint."""

    length: Length = Field(description="Link length, px.")
    mass: float = Field(1.0, gt=0, le=1e6, allow_inf_nan=False, description="Link mass.")
    width: float = Field(
        12.0, gt=0, le=1000, allow_inf_nan=False, description="Link thickness, px."
    )
    limits: tuple[Degrees, Degrees] | None = Field(
        None, description="Joint limits relative to the parent link, degrees [min, max]."
    )
    max_torque: float = Field(
        5.0e7, gt=0, le=1e15, allow_inf_nan=False, description="Motor torque limit (mass px^2/s^2)."
    )
    max_speed: float = Field(
        360.0, gt=0, le=36000, allow_inf_nan=False, description="Motor speed limit, deg/s."
    )
    repeat: int = Field(1, ge=1, le=MAX_LINKS, description="Use this link this many times.")

    @model_validator(mode="after")
    def _limits_ordered(self) -> LinkConfig:
        if self.limits is not None and self.limits[0] >= self.limits[1]:
            raise ValueError(f"limits must be [min, max] with min < max, got {list(self.limits)}")
        return self

    @property
    def limits_rad(self) -> tuple[float, float] | None:
        """Joint limits in radians, or None."""
        if self.limits is None:
            return None
        return (math.radians(self.limits[0]), math.radians(self.limits[1]))


class ChainConfig(_Model):
    """``[chain]``: where the chain is mounted, how it is controlled, and its links."""

    base: Vec2 = Field((0.0, 0.0), description="Base position, px.")
    angle: Degrees = Field(90.0, description="Direction of the base mount, degrees (90 = up).")
    solver: Literal["ccd", "jacobian_transpose", "dls", "fabrik"] = Field(
        "ccd", description="IK solver."
    )
    iterations: int = Field(10, ge=1, le=1000, description="Solver iterations per tick.")
    arrival: float = Field(
        0.5, ge=0, le=1000, allow_inf_nan=False, description="Solver arrival distance, px."
    )
    gain: float = Field(
        12.0,
        gt=0,
        le=1000,
        allow_inf_nan=False,
        description="Joint servo gain, 1/s: motor rate = gain x angle error.",
    )
    links: list[LinkConfig] = Field(min_length=1, description="The links, base first.")

    @model_validator(mode="after")
    def _link_count(self) -> ChainConfig:
        total = sum(link.repeat for link in self.links)
        if total > MAX_LINKS:
            raise ValueError(f"a chain has at most {MAX_LINKS} links, this one has {total}")
        return self

    @property
    def expanded_links(self) -> tuple[LinkConfig, ...]:
        """One entry per physical link, ``repeat`` expanded."""
        return tuple(link for link in self.links for _ in range(link.repeat))


class SegmentObstacle(_Model):
    """``[[obstacles]]`` with ``kind = "segment"``: a static thick line."""

    kind: Literal["segment"]
    a: Vec2 = Field(description="One end, px.")
    b: Vec2 = Field(description="Other end, px.")
    radius: float = Field(
        4.0, ge=0, le=1000, allow_inf_nan=False, description="Half thickness, px."
    )
    friction: float = Field(0.8, ge=0, le=10, allow_inf_nan=False, description="Friction.")


class CircleObstacle(_Model):
    """``[[obstacles]]`` with ``kind = "circle"``: a static disc."""

    kind: Literal["circle"]
    center: Vec2 = Field(description="Centre, px.")
    radius: Length = Field(description="Radius, px.")
    friction: float = Field(0.8, ge=0, le=10, allow_inf_nan=False, description="Friction.")


Obstacle = Annotated[SegmentObstacle | CircleObstacle, Field(discriminator="kind")]


class ReachStep(_Model):
    """``[[script]]`` with ``reach``: move the end effector to a point and hold it there."""

    reach: Vec2 = Field(description="Target point, px.")
    tolerance: float = Field(6.0, gt=0, le=1000, allow_inf_nan=False, description="px.")
    hold: float = Field(
        0.5, ge=0, le=MAX_DURATION, allow_inf_nan=False, description="Time within tolerance, s."
    )
    timeout: Seconds = Field(4.0, description="Time before the step fails, s.")


class WaitStep(_Model):
    """``[[script]]`` with ``wait``: keep the current target for a while."""

    wait: Seconds = Field(description="How long, s.")


_STEP_KINDS: Final = ("reach", "wait")


def _step_kind(value: object) -> str | None:
    fields = value if isinstance(value, dict) else vars(value) if hasattr(value, "__dict__") else {}
    kinds = [kind for kind in _STEP_KINDS if kind in fields]
    return kinds[0] if len(kinds) == 1 else None


Step = Annotated[
    Annotated[ReachStep, Tag("reach")] | Annotated[WaitStep, Tag("wait")],
    Discriminator(
        _step_kind,
        custom_error_type="step_kind",
        custom_error_message="a script step needs exactly one of the keys: "
        + ", ".join(_STEP_KINDS),
    ),
]


class Level(_Model):
    """A whole level file. Load one with :func:`ikgame.load_level`.

    >>> Level.model_validate({"level": {"name": "x", "duration": 1.0},
    ...     "chain": {"links": [{"length": 50.0, "repeat": 2}]},
    ...     "script": [{"reach": [50.0, 50.0]}]}).chain.expanded_links[1].length
    50.0
    """

    level: LevelInfo
    world: WorldConfig = WorldConfig()
    chain: ChainConfig
    obstacles: list[Obstacle] = Field(default_factory=list, max_length=500)
    script: list[Step] = Field(min_length=1, max_length=MAX_STEPS)
