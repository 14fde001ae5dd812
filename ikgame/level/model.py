"""The level format as a validated, frozen pydantic model.

Level files use degrees and seconds; :class:`Level` keeps the file's values as written (so the
JSON Schema and error messages speak the file's units) and offers radian views where the
simulation needs them. Every range here is a guard against typos and hostile files alike: a level
is data, and the limits below bound the memory, time and disk a level can ask for.

Checks that span several fields raise a ``ValidationError`` located at the field to blame (see
:func:`_invalid`), so the loader can point at the right line of the file.
"""

from __future__ import annotations

import math
import re
import weakref
from dataclasses import dataclass, fields
from typing import Annotated, Any, Final, Literal

from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    Tag,
    ValidationError,
    field_validator,
    model_validator,
)
from pydantic_core import InitErrorDetails, PydanticCustomError

from ikgame.level.names import SOLVER_NAMES, SolverName

__all__ = [
    "MAX_LINKS",
    "MAX_DURATION",
    "MAX_STEPS",
    "MAX_POINTS",
    "MAX_OBSTACLES",
    "MAX_PROPS",
    "MAX_GOALS",
    "MAX_FRAMES",
    "MAX_TICKS",
    "MAX_COORD",
    "SOLVER_NAMES",
    "FOLLOW_SHAPES",
    "Level",
    "LevelInfo",
    "WorldConfig",
    "ChainConfig",
    "LinkConfig",
    "BoneConfig",
    "Link",
    "GaitConfig",
    "CHAIN_EFFECTOR",
    "KEY_PATTERN",
    "SegmentObstacle",
    "CircleObstacle",
    "BallProp",
    "BoxProp",
    "Goal",
    "ReachStep",
    "FollowLine",
    "FollowCircle",
    "FollowLissajous",
    "FollowPolyline",
    "WaitStep",
    "SetChanges",
    "SetStep",
    "SequenceStep",
    "Step",
    "step_count",
    "follow_duration",
    "check_relative_file",
]

MAX_LINKS: Final = 200
"""Links in one chain or tree, after ``repeat`` is expanded."""
MAX_DURATION: Final = 600.0
"""Simulated seconds in one level."""
MAX_STEPS: Final = 500
"""Script steps in one level, after each ``sequence`` is expanded into its reach steps."""
MAX_POINTS: Final = 1000
"""Points in one ``polyline`` path or one ``sequence``."""
MAX_OBSTACLES: Final = 500
"""Static obstacles in one level."""
MAX_PROPS: Final = 100
"""Dynamic props in one level."""
MAX_GOALS: Final = 100
"""Goals in one level."""
MAX_FRAMES: Final = 18_000
"""Recorded frames (``duration`` x ``fps``): 10 minutes at 30 fps; bounds memory and disk."""
MAX_TICKS: Final = 300_000
"""Physics ticks (``duration`` x ``tick_rate``): bounds the time a run can take."""
MAX_COORD: Final = 1.0e5
"""Largest coordinate or length, px: beyond it the camera and physics lose all meaning."""
MIN_SIZE: Final = 0.1
"""Smallest length, width or radius, px: a tenth of a rendered pixel. Smaller bodies have moments
of inertia that underflow (pymunk refuses a zero moment) and Jacobians too small to invert."""
MIN_MASS: Final = 1.0e-3
"""Smallest mass: with :data:`MIN_SIZE` it keeps every moment of inertia a normal float."""
MAX_MASS_RATIO: Final = 1000.0
"""Largest mass ratio of two joined links: pymunk's iterative joint solver spreads an impulse in
proportion to the inverse masses, and past about 10^4 the light link is thrown about."""
MIN_SECONDS: Final = 1.0e-3
"""Shortest time a level may name, s: two ticks at the fastest tick rate. Shorter periods make
rates such as 2 pi / period overflow."""
MIN_TICKS_PER_TURN: Final = 8
"""A circling or oscillating target needs this many physics ticks per turn to be a path at all
rather than a few points jumping about; a base move needs as many ticks to accelerate the chain
rather than teleport its pivot (which the joint solver answers with unbounded impulses)."""

CHAIN_EFFECTOR: Final = "tip"
"""The name of a chain's one effector, the tip of its last link."""

# Printable text only: a level's names end up in terminals and pictures.
_NAME_PATTERN: Final = r"^[^\x00-\x1f\x7f]*$"
# Bone names are TOML bare keys, so that ``reach = { left = [x, y] }`` needs no quotes.
KEY_PATTERN: Final = r"^[A-Za-z0-9_-]+$"
_TEXT_PATTERN: Final = r"^[^\x00-\x09\x0b-\x1f\x7f]*$"
_THEME_NAME: Final = re.compile(r"^[A-Za-z0-9_-]+$")

Coord = Annotated[float, Field(ge=-MAX_COORD, le=MAX_COORD, allow_inf_nan=False)]
Fraction = Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)]
SpriteScale = Annotated[float, Field(ge=1e-3, le=1000, allow_inf_nan=False)]
Vec2 = tuple[Coord, Coord]
Region = tuple[Coord, Coord, Coord, Coord]
Length = Annotated[float, Field(ge=MIN_SIZE, le=MAX_COORD, allow_inf_nan=False)]
Seconds = Annotated[float, Field(ge=MIN_SECONDS, le=MAX_DURATION, allow_inf_nan=False)]
Degrees = Annotated[float, Field(ge=-180.0, le=180.0, allow_inf_nan=False)]
Mass = Annotated[float, Field(ge=MIN_MASS, le=1e6, allow_inf_nan=False)]
Friction = Annotated[float, Field(ge=0, le=10, allow_inf_nan=False)]
Tolerance = Annotated[float, Field(gt=0, le=1000, allow_inf_nan=False)]
Gain = Annotated[float, Field(gt=0, le=1000, allow_inf_nan=False)]
Name = Annotated[str, Field(min_length=1, max_length=40, pattern=_NAME_PATTERN)]
BoneName = Annotated[str, Field(min_length=1, max_length=40, pattern=KEY_PATTERN)]


def _invalid(loc: tuple[str | int, ...], message: str, value: object) -> ValidationError:
    """A validation error located at ``loc`` (relative to the model being validated).

    Raised from a model validator, pydantic prefixes the model's own location, so a check that
    spans fields can still blame the one field a designer has to change.
    """
    return ValidationError.from_exception_data(
        "Level",
        [
            InitErrorDetails(
                type=PydanticCustomError("level_rule", "{message}", {"message": message}),
                loc=loc,
                input=value,
            )
        ],
    )


class _Model(BaseModel):
    # Validators are built when a model is first used, not at import: a run validates one
    # Level, whose build covers every nested model, so building each of them on its own too
    # would only cost start-up.
    model_config = ConfigDict(extra="forbid", frozen=True, defer_build=True)


class LevelInfo(_Model):
    """[level]: name, description, how long the level may run and how it should end."""

    name: str = Field(
        min_length=1, max_length=80, pattern=_NAME_PATTERN, description="Display name."
    )
    description: str = Field(
        "", max_length=2000, pattern=_TEXT_PATTERN, description="What the level teaches."
    )
    duration: Seconds = Field(description="Simulated time at most, s.")
    expect: Literal["passed", "failed"] = Field(
        "passed",
        description="The status the level is designed to end with ('failed' for a level that "
        "shows the failure state on purpose).",
    )
    theme: str | None = Field(
        None,
        min_length=1,
        max_length=200,
        description="Colour theme: a shipped theme's name ('dark', 'light') or a .json file "
        "inside the level's folder or assets/.",
    )

    @field_validator("theme")
    @classmethod
    def _theme_inside(cls, value: str | None) -> str | None:
        if value is not None and not _THEME_NAME.match(value):
            if not value.endswith(".json"):
                raise ValueError("must be a shipped theme's name or a .json file")
            check_relative_file(value, ".json")
        return value


def check_relative_file(name: str, suffix: str) -> None:
    """Raise ``ValueError`` unless ``name`` is a relative path that cannot leave its folder and
    ends with ``suffix``.

    Whether the file exists, and where its symlinks lead, is checked when the level is loaded
    from a file (:func:`ikgame.level.loader.resolve_level_file`).

    >>> check_relative_file("../secret.json", ".json")
    Traceback (most recent call last):
    ...
    ValueError: must stay inside the level's folder or assets/: '..' is not allowed
    """
    if "\\" in name or "\x00" in name:
        raise ValueError("must be a relative path with '/' separators")
    if name.startswith("/") or re.match(r"^[A-Za-z]:", name):
        raise ValueError(
            "must be a path relative to the level's folder or assets/, not an absolute path"
        )
    if ".." in name.split("/"):
        raise ValueError("must stay inside the level's folder or assets/: '..' is not allowed")
    if not name.endswith(suffix):
        raise ValueError(f"must be a {suffix} file")


def _check_sprite_fields(model: LinkConfig | _Prop) -> None:
    """``sprite_pivot`` and ``sprite_scale`` mean nothing without a ``sprite``: say so."""
    if model.sprite is None:
        for name in ("sprite_pivot", "sprite_scale"):
            if name in model.model_fields_set:
                raise _invalid((name,), "only applies with sprite", getattr(model, name))


def _png_inside(value: str) -> str:
    check_relative_file(value, ".png")
    return value


SpritePath = Annotated[str, Field(min_length=1, max_length=200), AfterValidator(_png_inside)]


# The sprite fields of links and props differ only in words and the pivot's default.
def _sprite_field(replaces: str, orientation: str) -> Any:
    return Field(
        None,
        description=f"A PNG image drawn in place of {replaces} (a file in the level's folder or "
        f"assets/); {orientation}.",
    )


def _pivot_field(default: tuple[float, float], onto: str) -> Any:
    return Field(
        default,
        description=f"The image point that sits on {onto}, as fractions of the image's width "
        "and height from its top-left corner.",
    )


def _scale_field(spans: str) -> Any:
    return Field(
        None, description=f"World px per image px; default: the image's width spans {spans}."
    )


class WorldConfig(_Model):
    """[world]: gravity, damping and the fixed clocks of the run."""

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
    bounds: Region | None = Field(
        None, description="Camera bounds (xmin, ymin, xmax, ymax), px; fitted when absent."
    )

    @model_validator(mode="after")
    def _bounds_ordered(self) -> WorldConfig:
        if self.bounds is not None:
            _check_region(self.bounds, "bounds")
        if self.fps > self.tick_rate:
            # A frame is taken at a tick: more frames than ticks would repeat frames and play
            # the run back faster than it ran.
            raise _invalid(
                ("fps",),
                f"{self.fps} fps is more frames than the {self.tick_rate} ticks/s of "
                f"world.tick_rate; at most {self.tick_rate} (or raise world.tick_rate)",
                self.fps,
            )
        return self


def _check_region(region: tuple[float, float, float, float], field: str) -> None:
    xmin, ymin, xmax, ymax = region
    if xmin >= xmax or ymin >= ymax:
        raise _invalid(
            (field,),
            f"must be (xmin, ymin, xmax, ymax) with xmin < xmax and ymin < ymax, "
            f"got {list(region)}",
            list(region),
        )


def _radians(limits: tuple[float, float] | None) -> tuple[float, float] | None:
    """Joint limits in radians, or None."""
    return None if limits is None else (math.radians(limits[0]), math.radians(limits[1]))


class LinkConfig(_Model):
    """[[chain.links]]: one link (or `repeat` identical links) and its joint."""

    length: Length = Field(description="Link length, px.")
    mass: Mass = Field(1.0, description="Link mass.")
    width: float = Field(
        12.0, ge=MIN_SIZE, le=1000, allow_inf_nan=False, description="Link thickness, px."
    )
    limits: tuple[Degrees, Degrees] | None = Field(
        None, description="Joint limits relative to the parent link, degrees [min, max]."
    )
    max_torque: float = Field(
        5.0e7, gt=0, le=1e15, allow_inf_nan=False, description="Motor torque limit (mass px^2/s^2)."
    )
    max_speed: float = Field(
        360.0, ge=0.01, le=36000, allow_inf_nan=False, description="Motor speed limit, deg/s."
    )
    repeat: int = Field(1, ge=1, le=MAX_LINKS, description="Use this link this many times.")
    sprite: SpritePath | None = _sprite_field(
        "the link's capsule", "the image's +x axis points along the link"
    )
    sprite_pivot: tuple[Fraction, Fraction] = _pivot_field((0.0, 0.5), "the link's joint")
    sprite_scale: SpriteScale | None = _scale_field("the link's length")

    @model_validator(mode="after")
    def _limits_ordered(self) -> LinkConfig:
        if self.limits is not None and self.limits[0] >= self.limits[1]:
            raise _invalid(
                ("limits",),
                f"must be [min, max] with min < max, got {list(self.limits)}",
                list(self.limits),
            )
        _check_sprite_fields(self)
        return self

    @property
    def limits_rad(self) -> tuple[float, float] | None:
        """Joint limits in radians, or None."""
        return _radians(self.limits)


class _BoneFields(_Model):
    """What a bone adds to a link: its place in the tree and its effector (listed first)."""

    name: BoneName = Field(
        description="Unique name: children name it as their "
        "`parent`, the script names its tip as an effector."
    )
    parent: BoneName | None = Field(
        None,
        description="The bone this one hangs from (listed before it); none: a root, hanging "
        "from the base.",
    )
    at: Vec2 = Field(
        (0.0, 0.0),
        description="Roots only: where the root's joint sits on the base, px in the base's "
        "frame (x along chain.angle, y to its left); every root gives it when there are several.",
    )
    angle: Degrees = Field(
        0.0,
        description="Start angle relative to the parent bone (a root: to chain.angle), degrees, "
        "within the limits (the default 0 is clipped into them).",
    )
    effector: bool | None = Field(
        None,
        description="Whether the bone's tip is an effector the script can name; default: true "
        "for a bone without children.",
    )
    weight: float = Field(
        1.0,
        gt=0,
        le=1000,
        allow_inf_nan=False,
        description="The effector's weight when its target and the others' cannot all be "
        "reached (effectors only).",
    )


class BoneConfig(LinkConfig, _BoneFields):
    """[[chain.bones]]: one named bone of a tree (or `repeat` identical bones in a row) and its
    joint; every key of a link, and where the bone hangs."""

    repeat: int = Field(
        1,
        ge=1,
        le=MAX_LINKS,
        description="Use this bone this many times in a row; its children and its effector "
        "sit at the last one's tip.",
    )

    @model_validator(mode="after")
    def _angle_within_limits(self) -> BoneConfig:
        if "angle" in self.model_fields_set and self.limits is not None:
            low, high = self.limits
            if not low <= self.angle <= high:
                raise _invalid(
                    ("angle",),
                    f"{self.angle:g} is outside the bone's limits {list(self.limits)}",
                    self.angle,
                )
        return self


@dataclass(frozen=True)
class Link:
    """One physical link as the world builds it: an entry of ``[[chain.links]]`` or
    ``[[chain.bones]]`` with its ``repeat`` expanded (:attr:`ChainConfig.expanded_links`).

    ``name``: ``link1``, ``link2`` ... in a chain; a bone's name in a tree (the first links of a
    repeated bone are ``name.1``, ``name.2`` ..., its last is ``name``). ``parent_index``: the
    index of the link it hangs from, -1 for a root (on the base). ``source``: the index of its
    entry in ``chain.links`` or ``chain.bones``. ``at`` (px, base frame; roots only, else zero),
    ``angle`` (start angle relative to the parent, degrees, unclipped), ``effector`` (its tip is
    an effector), ``weight`` (that effector's weight); the rest as in :class:`LinkConfig`.

    >>> link = ChainConfig(links=[{"length": 40.0, "limits": (-90.0, 90.0)}]).expanded_links[0]
    >>> link.name, link.parent_index, link.effector, link.limits_rad[1] == math.pi / 2
    ('link1', -1, True, True)
    """

    name: str
    parent_index: int
    source: int
    length: float
    mass: float
    width: float
    limits: tuple[float, float] | None
    max_torque: float
    max_speed: float
    sprite: str | None
    sprite_pivot: tuple[float, float]
    sprite_scale: float | None
    at: tuple[float, float] = (0.0, 0.0)
    angle: float = 0.0
    effector: bool = False
    weight: float = 1.0

    @property
    def limits_rad(self) -> tuple[float, float] | None:
        """Joint limits in radians, or None."""
        return _radians(self.limits)


_LINK_FIELDS: Final = tuple(f.name for f in fields(Link) if f.name in LinkConfig.model_fields)


def _link(entry: LinkConfig, name: str, parent: int, source: int, **tree: Any) -> Link:
    return Link(
        name=name,
        parent_index=parent,
        source=source,
        **{key: getattr(entry, key) for key in _LINK_FIELDS},
        **tree,
    )


def _listing(names: list[str] | tuple[str, ...], most: int = 10) -> str:
    """Names for a message: ``'a', 'b'``, the first ``most`` of a long list, 'none' for none."""
    shown = ", ".join(repr(n) for n in names[:most])
    return (shown + ", ..." if len(names) > most else shown) or "none"


class ChainConfig(_Model):
    """[chain]: where the chain or tree is mounted, how it is controlled, and its links or
    bones."""

    # The schema says what the validator checks: exactly one of links and bones.
    model_config = ConfigDict(
        json_schema_extra={"oneOf": [{"required": ["links"]}, {"required": ["bones"]}]}
    )

    base: Vec2 = Field((0.0, 0.0), description="Base position, px.")
    angle: Degrees = Field(90.0, description="Direction of the base mount, degrees (90 = up).")
    solver: SolverName = Field("ccd", description="IK solver.")
    iterations: int = Field(10, ge=1, le=1000, description="Solver iterations per solve.")
    arrival: float = Field(
        0.5, ge=0, le=1000, allow_inf_nan=False, description="Solver arrival distance, px."
    )
    gain: Gain = Field(12.0, description="Joint servo gain, 1/s: motor rate = gain x angle error.")
    links: list[LinkConfig] | None = Field(
        None,
        min_length=1,
        max_length=MAX_LINKS,
        description="The links of a chain, base first (give links or bones).",
    )
    bones: list[BoneConfig] | None = Field(
        None,
        min_length=1,
        max_length=MAX_LINKS,
        description="The bones of a tree, each parent before its children (give links or bones).",
    )
    branches_collide: bool = Field(
        False,
        description="Bones of different branches collide with each other (a bone never collides "
        "with its ancestors, descendants or siblings); trees only.",
    )

    @model_validator(mode="after")
    def _links_or_bones(self) -> ChainConfig:
        if self.links is None and self.bones is None:
            raise _invalid(
                ("links",),
                "give the chain its [[chain.links]] (a chain) or its [[chain.bones]] (a tree)",
                None,
            )
        if self.links is not None and self.bones is not None:
            raise _invalid(
                ("bones",),
                "give [[chain.links]] (a chain) or [[chain.bones]] (a tree), not both",
                None,
            )
        field, noun = self.entry_field, "tree" if self.bones else "chain"
        total = sum(entry.repeat for entry in self.entries)
        if total > MAX_LINKS:
            raise _invalid(
                (field,), f"a {noun} has at most {MAX_LINKS} links, this one has {total}", total
            )
        if self.bones is None and self.branches_collide:
            raise _invalid(
                ("branches_collide",), "a chain of links has no branches: give bones", True
            )
        if self.bones is not None:
            _check_bones(self.bones)
        links = self.expanded_links
        far: list[float] = []  # px from the base to each link's tip, along the links
        for link in links:
            if link.parent_index < 0:
                far.append(math.hypot(*link.at) + link.length)
                continue
            far.append(far[link.parent_index] + link.length)
            before = links[link.parent_index]
            ratio = max(before.mass, link.mass) / min(before.mass, link.mass)
            if ratio > MAX_MASS_RATIO:
                whose = (
                    "the link before it" if self.bones is None else f"its parent {before.name!r}"
                )
                raise _invalid(
                    (field, link.source, "mass"),
                    f"{link.mass:g} is {ratio:.3g} times {'more' if link.mass > before.mass else 'less'} "
                    f"than the mass of {whose} ({before.mass:g}); joined links may "
                    f"differ at most {MAX_MASS_RATIO:g} times, beyond that the physics cannot "
                    "hold the joint between them and blows up",
                    link.mass,
                )
        reach = max(far)
        if reach > MAX_COORD:
            # Every coordinate is within MAX_COORD; a longer chain would reach where the
            # physics counts a body as blown up.
            what = (
                f"the links add up to {reach:g} px"
                if self.bones is None
                else f"the longest way from the base to a tip is {reach:g} px"
            )
            raise _invalid((field,), f"{what}; at most {MAX_COORD:g} (shorten the {field})", reach)
        return self

    @property
    def entry_field(self) -> Literal["links", "bones"]:
        """The key the file lists its parts under: ``"links"`` (a chain) or ``"bones"``."""
        return "links" if self.bones is None else "bones"

    @property
    def entries(self) -> list[LinkConfig]:
        """The entries as the file lists them (``chain.links`` or ``chain.bones``)."""
        return self.links if self.bones is None else self.bones

    @property
    def expanded_links(self) -> tuple[Link, ...]:
        """One entry per physical link, ``repeat`` expanded, each parent before its children.

        >>> chain = ChainConfig(bones=[{"name": "hip", "length": 30.0},
        ...     {"name": "leg", "parent": "hip", "length": 20.0, "repeat": 2}])
        >>> [(link.name, link.parent_index, link.effector) for link in chain.expanded_links]
        [('hip', -1, False), ('leg.1', 0, False), ('leg', 1, True)]
        """
        links = _EXPANDED.get(id(self))
        if links is None:
            links = _EXPANDED[id(self)] = self._expand()
            weakref.finalize(self, _EXPANDED.pop, id(self), None)
        return links

    def _expand(self) -> tuple[Link, ...]:
        if self.bones is None:
            count = sum(entry.repeat for entry in self.links)
            links: list[Link] = []
            for source, entry in enumerate(self.links):
                for _ in range(entry.repeat):
                    k = len(links)
                    links.append(
                        _link(entry, f"link{k + 1}", k - 1, source, effector=k == count - 1)
                    )
            return tuple(links)
        parents = {bone.parent for bone in self.bones}
        tips: dict[str, int] = {}
        links = []
        for source, bone in enumerate(self.bones):
            parent = -1 if bone.parent is None else tips[bone.parent]
            effector = bone.name not in parents if bone.effector is None else bone.effector
            for k in range(1, bone.repeat + 1):
                last = k == bone.repeat
                links.append(
                    _link(
                        bone,
                        bone.name if last else f"{bone.name}.{k}",
                        parent,
                        source,
                        at=bone.at if parent < 0 else (0.0, 0.0),
                        angle=bone.angle,
                        effector=effector and last,
                        weight=bone.weight,
                    )
                )
                parent = len(links) - 1
            tips[bone.name] = parent
        return tuple(links)

    @property
    def effector_names(self) -> tuple[str, ...]:
        """The effectors' names in link order: ``("tip",)`` for a chain, bone names in a tree.

        >>> ChainConfig(links=[{"length": 10.0, "repeat": 3}]).effector_names
        ('tip',)
        """
        if self.bones is None:
            return (CHAIN_EFFECTOR,)
        return tuple(link.name for link in self.expanded_links if link.effector)

    @property
    def effector_links(self) -> tuple[int, ...]:
        """The index of each effector's link, in the order of :attr:`effector_names`.

        >>> ChainConfig(links=[{"length": 10.0, "repeat": 3}]).effector_links
        (2,)
        """
        return tuple(i for i, link in enumerate(self.expanded_links) if link.effector)

    def start_segments(self) -> tuple[tuple[tuple[float, float], tuple[float, float]], ...]:
        """Where each link lies when the run starts, as (joint, tip) in world px: every joint at
        its start angle (0, or a bone's ``angle``) clipped into its limits.

        >>> ChainConfig(angle=0.0, links=[{"length": 10.0, "repeat": 2}]).start_segments()[1]
        ((10.0, 0.0), (20.0, 0.0))
        """
        base = math.radians(self.angle)
        cos, sin = math.cos(base), math.sin(base)
        angles: list[float] = []
        out: list[tuple[tuple[float, float], tuple[float, float]]] = []
        for link in self.expanded_links:
            start = link.angle
            if link.limits is not None:
                start = min(max(start, link.limits[0]), link.limits[1])
            if link.parent_index < 0:
                x, y = link.at
                joint = (self.base[0] + x * cos - y * sin, self.base[1] + x * sin + y * cos)
                angle = base + math.radians(start)
            else:
                joint = out[link.parent_index][1]
                angle = angles[link.parent_index] + math.radians(start)
            angles.append(angle)
            out.append(
                (
                    joint,
                    (
                        joint[0] + link.length * math.cos(angle),
                        joint[1] + link.length * math.sin(angle),
                    ),
                )
            )
        return tuple(out)


_EXPANDED: Final[dict[int, tuple[Link, ...]]] = {}
"""Each live chain's expanded links, by the chain's id: a chain is frozen, so they never change
(``model_copy`` makes a new object), and the world and controller may ask for them often. Not in
the instance's ``__dict__``, which ``model_copy`` would carry over to a changed copy."""


def _check_bones(bones: list[BoneConfig]) -> None:
    """The tree's shape: unique names, each parent listed before its children, several roots
    each placed with ``at``, ``weight`` on effectors only, and at least one effector."""
    first: dict[str, BoneConfig] = {}
    for bone in bones:
        first.setdefault(bone.name, bone)
    seen: dict[str, int] = {}
    for i, bone in enumerate(bones):
        if bone.name in seen:
            raise _invalid(
                ("bones", i, "name"),
                f"another bone is already named {bone.name!r} (chain.bones[{seen[bone.name]}])",
                bone.name,
            )
        if bone.parent is not None and bone.parent not in seen:
            raise _invalid(("bones", i, "parent"), _parent_problem(bones, i, first), bone.parent)
        if bone.parent is not None and "at" in bone.model_fields_set:
            raise _invalid(
                ("bones", i, "at"),
                "only applies to a root (a bone without parent): a child's joint is at its "
                "parent's tip",
                list(bone.at),
            )
        seen[bone.name] = i
    roots = [i for i, bone in enumerate(bones) if bone.parent is None]
    # A second root is more often a child that lost its parent than the first root is.
    for i in roots[1:] + roots[:1] if len(roots) > 1 else ():
        if "at" not in bones[i].model_fields_set:
            other = bones[roots[1] if i == roots[0] else roots[0]].name
            raise _invalid(
                ("bones", i),
                f"bone {bones[i].name!r} has no parent, like {other!r}: a tree may have several "
                "roots (legs on a body), each placed on the base with `at`; give this bone "
                "`at = [x, y]`, or the `parent` it hangs from",
                None,
            )
    parents = {bone.parent for bone in bones}
    effectors = 0
    for i, bone in enumerate(bones):
        effector = bone.name not in parents if bone.effector is None else bone.effector
        if not effector and "weight" in bone.model_fields_set:
            raise _invalid(
                ("bones", i, "weight"),
                "only applies to an effector (a bone without children, or with effector = true)",
                bone.weight,
            )
        effectors += effector
    if not effectors:
        raise _invalid(
            ("bones",),
            "no bone is an effector (each bone without children says effector = false), so the "
            "script could move nothing",
            None,
        )


def _parent_problem(bones: list[BoneConfig], i: int, first: dict[str, BoneConfig]) -> str:
    """Why bone ``i``'s parent is not a bone listed before it."""
    bone = bones[i]
    if bone.parent == bone.name:
        return "a bone cannot hang from itself"
    if bone.parent not in first:
        return f"no bone is named {bone.parent!r} (bones: {_listing(list(first))})"
    path, name = [bone.name], bone.parent
    while name is not None and name in first and name not in path:
        path.append(name)
        name = first[name].parent
    if name == bone.name:
        cycle = " -> ".join([*path, bone.name])
        return f"the bones hang from each other in a cycle ({cycle}); every bone must lead back to the base"
    later = next(j for j, b in enumerate(bones) if b.name == bone.parent)
    return (
        f"{bone.parent!r} is listed after this bone (chain.bones[{later}]); list each parent "
        "before its children"
    )


class SegmentObstacle(_Model):
    """[[obstacles]] with kind = "segment": a static thick line."""

    kind: Literal["segment"] = Field(description="Which kind of obstacle.")
    a: Vec2 = Field(description="One end, px.")
    b: Vec2 = Field(description="Other end, px.")
    radius: float = Field(
        4.0, ge=0, le=1000, allow_inf_nan=False, description="Half thickness, px."
    )
    friction: Friction = Field(0.8, description="Friction.")


class CircleObstacle(_Model):
    """[[obstacles]] with kind = "circle": a static disc."""

    kind: Literal["circle"] = Field(description="Which kind of obstacle.")
    center: Vec2 = Field(description="Centre, px.")
    radius: Length = Field(description="Radius, px.")
    friction: Friction = Field(0.8, description="Friction.")


Obstacle = Annotated[SegmentObstacle | CircleObstacle, Field(discriminator="kind")]


class _Prop(_Model):
    kind: str
    name: Name = Field(description="Unique name; goals refer to the prop by it.")
    position: Vec2 = Field(description="Starting position of the centre, px.")
    angle: Degrees = Field(0.0, description="Starting angle, degrees.")
    mass: Mass = Field(1.0, description="Mass (a link of the same mass weighs the same).")
    friction: Friction = Field(0.7, description="Friction.")
    elasticity: float = Field(
        0.2,
        ge=0,
        le=1,
        allow_inf_nan=False,
        description="Bounce off obstacles, 0 (none) to 1 (full); two props bounce with the "
        "product of theirs; links never bounce.",
    )
    sprite: SpritePath | None = _sprite_field(
        "the prop's shape", "upright at angle 0, it turns with the prop"
    )
    sprite_pivot: tuple[Fraction, Fraction] = _pivot_field((0.5, 0.5), "the prop's centre")
    sprite_scale: SpriteScale | None = _scale_field("the ball's diameter or the box's width")

    @model_validator(mode="after")
    def _sprite_given(self) -> _Prop:
        _check_sprite_fields(self)
        return self


class BallProp(_Prop):
    """[[props]] with kind = "ball": a dynamic disc the chain can push."""

    kind: Literal["ball"] = Field(description="Which kind of prop.")
    radius: Annotated[float, Field(ge=MIN_SIZE, le=1000, allow_inf_nan=False)] = Field(
        description="Radius, px."
    )


class BoxProp(_Prop):
    """[[props]] with kind = "box": a dynamic rectangle the chain can push."""

    kind: Literal["box"] = Field(description="Which kind of prop.")
    size: tuple[
        Annotated[float, Field(ge=MIN_SIZE, le=2000, allow_inf_nan=False)],
        Annotated[float, Field(ge=MIN_SIZE, le=2000, allow_inf_nan=False)],
    ] = Field(description="Width and height, px.")


Prop = Annotated[BallProp | BoxProp, Field(discriminator="kind")]


class Goal(_Model):
    """[[goals]]: a region a prop must end inside; scored at the end of the run."""

    prop: Name = Field(description="The name of the prop that must end inside the region.")
    region: Region = Field(description="The region (xmin, ymin, xmax, ymax), px.")
    hold: float = Field(
        0.0,
        ge=0,
        le=MAX_DURATION,
        allow_inf_nan=False,
        description="Time the prop's centre must have stayed inside when the run ends, s.",
    )
    name: str = Field(
        "",
        max_length=40,
        pattern=_NAME_PATTERN,
        description="Display name; 'goal N' (N counting from 1) when empty.",
    )

    @model_validator(mode="after")
    def _region_ordered(self) -> Goal:
        _check_region(self.region, "region")
        return self


def _reach_kind(value: object) -> str:
    return "table" if isinstance(value, dict) else "point"


Reach = Annotated[
    Annotated[Vec2, Tag("point")]
    | Annotated[dict[BoneName, Vec2], Field(min_length=1, max_length=MAX_LINKS), Tag("table")],
    Discriminator(_reach_kind),
]


class ReachStep(_Model):
    """[[script]] with reach: move the end effector to a point (or several effectors, each to
    its point) and hold it there."""

    reach: Reach = Field(
        description="Target point [x, y], px; or a table of effector name = [x, y] that moves "
        "several effectors at once."
    )
    tolerance: Tolerance = Field(6.0, description="Distance that counts as reached, px.")
    hold: float = Field(
        0.5, ge=0, le=MAX_DURATION, allow_inf_nan=False, description="Time within tolerance, s."
    )
    timeout: Seconds = Field(4.0, description="Time before the step fails, s.")

    def targets(self, default: str | None) -> dict[str, tuple[float, float]]:
        """The point each effector aims at, px: the table as written, or the point for the
        ``default`` effector (None when there is no default: a chain of several effectors).

        >>> ReachStep(reach=(1, 2)).targets("tip")
        {'tip': (1.0, 2.0)}
        """
        if isinstance(self.reach, dict):
            return dict(self.reach)
        if default is None:
            raise ValueError(
                "a reach to a point moves the only effector, and this chain has several; "
                "name them: reach = { name = [x, y] }"
            )
        return {default: self.reach}

    @property
    def points(self) -> tuple[tuple[float, float], ...]:
        """Every target point of the step, px (one for a point, one per effector for a table).

        >>> ReachStep(reach={"a": (1, 2), "b": (3, 4)}).points
        ((1.0, 2.0), (3.0, 4.0))
        """
        return tuple(self.reach.values()) if isinstance(self.reach, dict) else (self.reach,)


def _effector_field(what: str) -> Any:
    return Field(
        None,
        description=f"The effector that {what}; default: the only one (name it when the chain "
        "has several).",
    )


class _Follow(_Model):
    follow: str
    duration: Seconds = Field(description="Time the target takes along the path, s.")
    easing: Literal["linear", "in", "out", "in-out"] = Field(
        "linear",
        description="How the path parameter runs: steadily, speeding up, slowing down, or both.",
    )
    tolerance: Tolerance = Field(15.0, description="Largest mean tracking error that passes, px.")
    lead_in: float = Field(
        1.0,
        ge=0,
        le=60,
        allow_inf_nan=False,
        description="Time aiming at the path's start before the target moves and scoring "
        "begins, s.",
    )
    effector: BoneName | None = _effector_field("follows the path")


class FollowLine(_Follow):
    """[[script]] with follow = "line": the target runs from one point to another."""

    follow: Literal["line"] = Field(description="The shape of the path.")
    from_: Vec2 = Field(alias="from", description="Start point, px.")
    to: Vec2 = Field(description="End point, px.")


class FollowCircle(_Follow):
    """[[script]] with follow = "circle": the target goes round a circle."""

    follow: Literal["circle"] = Field(description="The shape of the path.")
    center: Vec2 = Field(description="Centre, px.")
    radius: Length = Field(description="Radius, px.")
    period: Seconds = Field(description="Time for one turn, s.")
    direction: Literal["ccw", "cw"] = Field("ccw", description="Counter-clockwise or clockwise.")
    start: Degrees = Field(0.0, description="Angle of the start point, degrees (0 = +x).")


class FollowLissajous(_Follow):
    """[[script]] with follow = "lissajous": x = ax sin(2 pi fx s + phase), y = ay sin(2 pi fy s)
    about the centre (fx = 1, fy = 2 traces a figure-eight)."""

    follow: Literal["lissajous"] = Field(description="The shape of the path.")
    center: Vec2 = Field(description="Centre, px.")
    amplitude: tuple[
        Annotated[float, Field(ge=0, le=MAX_COORD, allow_inf_nan=False)],
        Annotated[float, Field(ge=0, le=MAX_COORD, allow_inf_nan=False)],
    ] = Field(description="Half width and half height [ax, ay], px.")
    frequency: tuple[
        Annotated[float, Field(ge=0, le=20, allow_inf_nan=False)],
        Annotated[float, Field(ge=0, le=20, allow_inf_nan=False)],
    ] = Field(description="Turns per second along x and y [fx, fy], Hz.")
    phase: float = Field(
        0.0, ge=-360, le=360, allow_inf_nan=False, description="Phase of x ahead of y, degrees."
    )


class FollowPolyline(_Follow):
    """[[script]] with follow = "polyline": the target runs along straight pieces at a speed."""

    follow: Literal["polyline"] = Field(description="The shape of the path.")
    points: list[Vec2] = Field(
        min_length=2, max_length=MAX_POINTS, description="Corner points, in order, px."
    )
    speed: float = Field(gt=0, le=1.0e4, allow_inf_nan=False, description="Target speed, px/s.")
    duration: Seconds | None = Field(
        None,
        description="Time along the path, s (the target waits at the last point once there); "
        "default: path length / speed.",
    )

    @model_validator(mode="after")
    def _has_length(self) -> FollowPolyline:
        length = self.length
        if length <= 0:
            raise _invalid(("points",), "the points must not all be the same", None)
        if self.duration is None and length / self.speed > MAX_DURATION:
            raise _invalid(
                ("speed",),
                f"the path takes {length / self.speed:g} s at this speed; at most {MAX_DURATION:g}",
                self.speed,
            )
        return self

    @property
    def length(self) -> float:
        """Length of the path, px."""
        return sum(math.dist(a, b) for a, b in zip(self.points, self.points[1:], strict=False))


FollowStep = Annotated[
    FollowLine | FollowCircle | FollowLissajous | FollowPolyline, Field(discriminator="follow")
]
FOLLOW_SHAPES: Final = {
    "line": FollowLine,
    "circle": FollowCircle,
    "lissajous": FollowLissajous,
    "polyline": FollowPolyline,
}
"""The model of each ``follow`` shape, by name."""


def follow_duration(step: FollowLine | FollowCircle | FollowLissajous | FollowPolyline) -> float:
    """Time the target moves along a follow step's path, s.

    >>> follow_duration(FollowPolyline(follow="polyline", points=[(0, 0), (30, 40)], speed=10))
    5.0
    """
    if step.duration is not None:
        return step.duration
    return step.length / step.speed


class WaitStep(_Model):
    """[[script]] with wait: keep the current target for a while."""

    wait: Seconds = Field(description="How long, s.")


class SetChanges(_Model):
    """The changes of a set step; give at least one of gravity, solver, gain, base, angle."""

    gravity: Vec2 | None = Field(None, description="New gravity, px/s^2.")
    solver: SolverName | None = Field(None, description="New IK solver.")
    gain: Gain | None = Field(None, description="New joint servo gain, 1/s.")
    base: Vec2 | None = Field(
        None, description="Where the chain's base moves to (smoothly, over `over` s), px."
    )
    angle: Degrees | None = Field(
        None,
        description="The base's new direction, degrees (as chain.angle: it turns smoothly, "
        "over `over` s, the shorter way round).",
    )
    over: Seconds = Field(
        1.0, description="Time the base takes to move or turn, s (with base or angle only)."
    )

    @model_validator(mode="after")
    def _something_changes(self) -> SetChanges:
        given = self.model_fields_set
        if not given & {"gravity", "solver", "gain", "base", "angle"}:
            raise ValueError("give at least one of gravity, solver, gain, base, angle")
        if "over" in given and self.base is None and self.angle is None:
            raise _invalid(("over",), "only applies with base or angle", self.over)
        return self

    @property
    def moves_base(self) -> bool:
        """Whether the base moves or turns (over ``over`` s)."""
        return self.base is not None or self.angle is not None


class SetStep(_Model):
    """[[script]] with set: change the world or the controller from this moment on; takes no
    time (the base then moves while the next steps run)."""

    set: SetChanges = Field(description="What changes.")


class SequenceStep(_Model):
    """[[script]] with sequence: reach several points in turn, each scored as a reach step."""

    sequence: list[Vec2] = Field(
        min_length=1, max_length=MAX_POINTS, description="Target points, in order, px."
    )
    tolerance: Tolerance = Field(6.0, description="Distance that counts as reached, px.")
    hold: float = Field(
        0.5, ge=0, le=MAX_DURATION, allow_inf_nan=False, description="Time within tolerance, s."
    )
    timeout: Seconds = Field(4.0, description="Time each point may take before it fails, s.")
    effector: BoneName | None = _effector_field("reaches the points")

    def reach_steps(self) -> tuple[ReachStep, ...]:
        """One reach step per point (a table naming the effector when the step names one).

        >>> SequenceStep(sequence=[(1, 2), (3, 4)]).reach_steps()[1].reach
        (3.0, 4.0)
        >>> SequenceStep(sequence=[(1, 2)], effector="left").reach_steps()[0].reach
        {'left': (1.0, 2.0)}
        """
        return tuple(
            ReachStep(
                reach=p if self.effector is None else {self.effector: p},
                tolerance=self.tolerance,
                hold=self.hold,
                timeout=self.timeout,
            )
            for p in self.sequence
        )


_STEP_KINDS: Final = ("reach", "follow", "wait", "set", "sequence")


def _step_kind(value: object) -> str | None:
    fields = value if isinstance(value, dict) else vars(value) if hasattr(value, "__dict__") else {}
    kinds = [kind for kind in _STEP_KINDS if kind in fields]
    return kinds[0] if len(kinds) == 1 else None


Step = Annotated[
    Annotated[ReachStep, Tag("reach")]
    | Annotated[FollowStep, Tag("follow")]
    | Annotated[WaitStep, Tag("wait")]
    | Annotated[SetStep, Tag("set")]
    | Annotated[SequenceStep, Tag("sequence")],
    Discriminator(
        _step_kind,
        custom_error_type="step_kind",
        custom_error_message="a script step needs exactly one of the keys: "
        + ", ".join(_STEP_KINDS),
    ),
]


def step_count(script: list[Step] | tuple[Step, ...]) -> int:
    """Steps the script runs, each point of a ``sequence`` counted as a step.

    >>> step_count([WaitStep(wait=1.0), SequenceStep(sequence=[(0, 1), (1, 0)])])
    3
    """
    return sum(len(s.sequence) if isinstance(s, SequenceStep) else 1 for s in script)


class GaitConfig(_Model):
    """[gait]: how a creature's legs step while the script carries its body (the chain's base)
    along with set steps; the gait places the legs' feet, the script moves the other effectors."""

    legs: list[BoneName] = Field(
        min_length=1,
        max_length=MAX_LINKS,
        description="The effectors that are feet, listed front to back.",
    )
    groups: list[Annotated[list[BoneName], Field(min_length=1, max_length=MAX_LINKS)]] | None = (
        Field(
            None,
            min_length=1,
            max_length=MAX_LINKS,
            description="Legs that step together, one group after the other, each leg in "
            "exactly one group; default: the legs alternate in the order listed (1st, 3rd, 5th "
            "... then 2nd, 4th ...): pairs for 4 legs, tripods for 6.",
        )
    )
    stride: Length = Field(
        60.0,
        description="Length of a step, px: a lifted foot lands stride / 2 ahead of its rest spot.",
    )
    step_height: float = Field(
        20.0,
        ge=0,
        le=MAX_COORD,
        allow_inf_nan=False,
        description="How high a stepping foot lifts, px.",
    )
    step_time: Seconds = Field(0.3, description="Time a foot spends in the air, s.")
    threshold: Length | None = Field(
        None,
        description="How far the body may carry a planted foot from its rest spot before it "
        "steps, px; default: stride / 2.",
    )

    @model_validator(mode="after")
    def _groups_share_out_the_legs(self) -> GaitConfig:
        for j, leg in enumerate(self.legs):
            if leg in self.legs[:j]:
                raise _invalid(("legs", j), f"{leg!r} is listed twice", leg)
        if self.groups is None:
            return self
        placed: dict[str, int] = {}
        for g, group in enumerate(self.groups):
            for j, leg in enumerate(group):
                if leg not in self.legs:
                    raise _invalid(
                        ("groups", g, j),
                        f"{leg!r} is not one of the gait's legs ({_listing(self.legs)})",
                        leg,
                    )
                if leg in placed:
                    raise _invalid(
                        ("groups", g, j),
                        f"{leg!r} is already in groups[{placed[leg]}]; each leg steps in one group",
                        leg,
                    )
                placed[leg] = g
        missing = [leg for leg in self.legs if leg not in placed]
        if missing:
            raise _invalid(
                ("groups",),
                f"{_listing(missing)} {'is' if len(missing) == 1 else 'are'} in no group; the "
                "groups share out every leg, each in exactly one",
                None,
            )
        return self

    @property
    def step_groups(self) -> tuple[tuple[str, ...], ...]:
        """The groups that step in turn: ``groups``, or the legs alternating as listed.

        >>> GaitConfig(legs=["a", "b", "c", "d", "e", "f"]).step_groups
        (('a', 'c', 'e'), ('b', 'd', 'f'))
        """
        if self.groups is not None:
            return tuple(tuple(group) for group in self.groups)
        if len(self.legs) == 1:
            return (tuple(self.legs),)
        return (tuple(self.legs[0::2]), tuple(self.legs[1::2]))

    @property
    def step_threshold(self) -> float:
        """``threshold``, or stride / 2 when not given, px.

        >>> GaitConfig(legs=["a"], stride=50.0).step_threshold
        25.0
        """
        return self.stride / 2.0 if self.threshold is None else self.threshold


def _check_start_clear(
    chain: ChainConfig, obstacles: list[SegmentObstacle | CircleObstacle]
) -> None:
    """Refuse a chain whose links start with their axis inside an obstacle: the links hang from
    a fixed base, so the physics would push them out against joints that cannot give, without
    bound."""
    links = chain.expanded_links
    for k, (joint, end) in enumerate(chain.start_segments()):
        for j, obstacle in enumerate(obstacles):
            if isinstance(obstacle, SegmentObstacle):
                gap = _segments_distance(joint, end, obstacle.a, obstacle.b)
            else:
                gap = _point_segment_distance(obstacle.center, joint, end)
            # A link's rounded edge may start in an obstacle (pymunk eases a shallow overlap
            # out); its axis may not.
            if gap < obstacle.radius:
                what = (
                    f"link {k + 1} of the chain"
                    if chain.bones is None
                    else f"bone {chain.bones[links[k].source].name!r}"
                )
                raise _invalid(
                    ("obstacles", j),
                    f"{what} starts inside this obstacle (its axis "
                    f"{obstacle.radius - gap:.3g} px deep); the chain hangs from a fixed base "
                    "and could not be pushed out: move the obstacle or change chain.base / "
                    "chain.angle",
                    None,
                )


def _point_segment_distance(
    p: tuple[float, float], a: tuple[float, float], b: tuple[float, float]
) -> float:
    """Distance from point ``p`` to the segment ``ab``, px.

    >>> _point_segment_distance((0.0, 5.0), (-1.0, 0.0), (1.0, 0.0))
    5.0
    """
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0 else ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2
    t = min(1.0, max(0.0, t))
    return math.hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy)


def _segments_distance(
    a: tuple[float, float],
    b: tuple[float, float],
    c: tuple[float, float],
    d: tuple[float, float],
) -> float:
    """Distance between the segments ``ab`` and ``cd``, px (0 when they cross).

    >>> _segments_distance((-1.0, 0.0), (1.0, 0.0), (0.0, -1.0), (0.0, 1.0))
    0.0
    """

    def side(p: tuple[float, float], q: tuple[float, float], r: tuple[float, float]) -> float:
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])

    if side(a, b, c) * side(a, b, d) < 0 and side(c, d, a) * side(c, d, b) < 0:
        return 0.0
    return min(
        _point_segment_distance(a, c, d),
        _point_segment_distance(b, c, d),
        _point_segment_distance(c, a, b),
        _point_segment_distance(d, a, b),
    )


def _check_script_timing(script: list[Step], tick_rate: int) -> None:
    """Refuse scripts whose ``set`` steps never apply and paths that turn faster than ticks."""
    timed = [i for i, step in enumerate(script) if not isinstance(step, SetStep)]
    if not timed:
        raise _invalid(
            ("script",),
            "the script has only set steps, which take no time, so the run would end before "
            "any change applied; add a reach, follow, wait or sequence step",
            None,
        )
    if timed[-1] < len(script) - 1:
        raise _invalid(
            ("script", timed[-1] + 1),
            "a set step at the end of the script never applies (the run ends with the last "
            "step that takes time); put it before a step, or add a wait after it",
            None,
        )
    for i, step in enumerate(script):
        if isinstance(step, SetStep) and step.set.moves_base:
            ticks = step.set.over * tick_rate
            if ticks < MIN_TICKS_PER_TURN:
                raise _invalid(
                    ("script", i, "set", "over"),
                    f"{step.set.over:g} s is {ticks:.3g} ticks at {tick_rate} ticks/s; a base "
                    f"move needs at least {MIN_TICKS_PER_TURN} ticks (over >= "
                    f"{MIN_TICKS_PER_TURN / tick_rate:.3g} s), or it yanks the chain apart",
                    step.set.over,
                )
            continue
        if isinstance(step, FollowCircle):
            turns, field, value = 1.0 / step.period, "period", step.period
        elif isinstance(step, FollowLissajous):
            turns, field, value = max(step.frequency), "frequency", list(step.frequency)
        else:
            continue
        if turns * MIN_TICKS_PER_TURN > tick_rate:
            raise _invalid(
                ("script", i, field),
                f"{turns:g} turns per second at {tick_rate} ticks/s leaves "
                f"{tick_rate / turns:.3g} ticks per turn; at least {MIN_TICKS_PER_TURN} "
                f"(at most {tick_rate / MIN_TICKS_PER_TURN:g} turns/s, or raise world.tick_rate)",
                value,
            )


def _check_gait(gait: GaitConfig, effectors: tuple[str, ...], tick_rate: int) -> None:
    for j, leg in enumerate(gait.legs):
        if leg not in effectors:
            raise _invalid(
                ("gait", "legs", j),
                f"no effector is named {leg!r} (effectors: {_listing(effectors)})",
                leg,
            )
    ticks = gait.step_time * tick_rate
    if ticks < MIN_TICKS_PER_TURN:
        raise _invalid(
            ("gait", "step_time"),
            f"{gait.step_time:g} s is {ticks:.3g} ticks at {tick_rate} ticks/s; a step needs at "
            f"least {MIN_TICKS_PER_TURN} ticks (step_time >= {MIN_TICKS_PER_TURN / tick_rate:.3g} "
            "s), or the foot jumps rather than steps",
            gait.step_time,
        )


def _check_script_effectors(level: Level) -> None:
    """Every effector the script names exists and is not a leg of the gait, and a step that
    names none has exactly one effector to move."""
    names, free = level.chain.effector_names, level.script_effectors

    def unknown(name: str) -> str | None:
        if name not in names:
            return f"no effector is named {name!r} (effectors: {_listing(names)})"
        if name not in free:
            return (
                f"{name!r} is a leg of the gait, which places its foot; the script moves the "
                f"other effectors ({_listing(free)})"
            )
        return None

    def unnamed(how: str) -> str | None:
        """Why a step that names no effector cannot run, or None when it can."""
        if len(free) == 1:
            return None
        if not free:
            return "every effector is a leg of the gait, so this step has none to move"
        return f"the chain has {len(free)} effectors ({_listing(free)}); say which: {how}"

    # A reach step's path starts with its union tag, "reach", as pydantic's own errors do.
    for i, step in enumerate(level.script):
        if isinstance(step, ReachStep) and isinstance(step.reach, dict):
            for name in step.reach:
                problem = unknown(name)
                if problem:
                    raise _invalid(("script", i, "reach", "reach", name), problem, name)
        elif isinstance(step, ReachStep):
            problem = unnamed("reach = { name = [x, y], ... }")
            if problem:
                raise _invalid(("script", i, "reach", "reach"), problem, list(step.reach))
        elif isinstance(step, _Follow | SequenceStep):
            problem = (
                unnamed('effector = "name"') if step.effector is None else unknown(step.effector)
            )
            if problem:
                raise _invalid(("script", i, "effector"), problem, step.effector)


def _empty() -> list[Any]:
    """A new empty list. (``default_factory=list`` would have pydantic read the signature of a
    builtin, which compiles tokenize's regular expressions: a few ms of every start-up.)"""
    return []


class Level(_Model):
    """A whole level file. Load one with :func:`ikgame.level.loader.load_level`.

    >>> Level.model_validate({"level": {"name": "x", "duration": 1.0},
    ...     "chain": {"links": [{"length": 50.0, "repeat": 2}]},
    ...     "script": [{"reach": [50.0, 50.0]}]}).chain.expanded_links[1].length
    50.0
    """

    level: LevelInfo = Field(description="Name, description, duration, expected status.")
    # model_construct: the defaults need no validation, so WorldConfig is not built on its own.
    world: WorldConfig = Field(
        WorldConfig.model_construct(), description="Gravity, damping, clocks, camera."
    )
    chain: ChainConfig = Field(description="The motorised chain and its controller.")
    obstacles: list[Obstacle] = Field(
        default_factory=_empty, max_length=MAX_OBSTACLES, description="Static obstacles."
    )
    props: list[Prop] = Field(
        default_factory=_empty,
        max_length=MAX_PROPS,
        description="Dynamic bodies the chain can push.",
    )
    goals: list[Goal] = Field(
        default_factory=_empty, max_length=MAX_GOALS, description="Regions props must end inside."
    )
    script: list[Step] = Field(
        min_length=1, max_length=MAX_STEPS, description="The steps, run in order."
    )
    gait: GaitConfig | None = Field(
        None, description="How the legs step while the body moves (creatures); none: no gait."
    )

    @model_validator(mode="after")
    def _consistent(self) -> Level:
        duration = self.level.duration
        frames = duration * self.world.fps
        if frames > MAX_FRAMES:
            raise _invalid(
                ("level", "duration"),
                f"{duration:g} s at {self.world.fps} fps records {frames:g} frames; at most "
                f"{MAX_FRAMES} (shorten the level or lower world.fps)",
                duration,
            )
        ticks = duration * self.world.tick_rate
        if ticks > MAX_TICKS:
            raise _invalid(
                ("level", "duration"),
                f"{duration:g} s at {self.world.tick_rate} ticks/s runs {ticks:g} ticks; at most "
                f"{MAX_TICKS} (shorten the level or lower world.tick_rate)",
                duration,
            )
        if round(ticks) < 1:
            raise _invalid(
                ("level", "duration"),
                f"{duration:g} s at {self.world.tick_rate} ticks/s is less than one tick; at "
                f"least {1 / self.world.tick_rate:.3g} s",
                duration,
            )
        _check_script_timing(self.script, self.world.tick_rate)
        _check_start_clear(self.chain, self.obstacles)
        steps = step_count(self.script)
        if steps > MAX_STEPS:
            raise _invalid(
                ("script",),
                f"the script runs {steps} steps (each sequence point counts); at most {MAX_STEPS}",
                None,
            )
        names: set[str] = set()
        for i, prop in enumerate(self.props):
            if prop.name in names:
                raise _invalid(
                    ("props", i, "name"), f"another prop is already named {prop.name!r}", prop.name
                )
            names.add(prop.name)
        for i, goal in enumerate(self.goals):
            if goal.prop not in names:
                known = ", ".join(repr(n) for n in sorted(names)) or "none"
                raise _invalid(
                    ("goals", i, "prop"),
                    f"no prop is named {goal.prop!r} (props: {known})",
                    goal.prop,
                )
        if self.gait is not None:
            _check_gait(self.gait, self.chain.effector_names, self.world.tick_rate)
        _check_script_effectors(self)
        return self

    @property
    def script_effectors(self) -> tuple[str, ...]:
        """The effectors the script moves, in link order: all but the gait's legs.

        >>> Level.model_validate({"level": {"name": "x", "duration": 1.0},
        ...     "chain": {"links": [{"length": 50.0}]},
        ...     "script": [{"wait": 1.0}]}).script_effectors
        ('tip',)
        """
        legs = () if self.gait is None else self.gait.legs
        return tuple(name for name in self.chain.effector_names if name not in legs)
