"""Level tooling as pure functions: validate files, list the shipped levels, the JSON Schema,
and the field reference of docs/levels.md.

The command line wires these up (``ikgame validate``, ``ikgame list``, ``ikgame schema``); tests
keep ``assets/level.schema.json`` equal to :func:`schema_text` and the reference section of
``docs/levels.md`` equal to :func:`reference_markdown`, so neither can drift from the model.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Final

from ikgame.level import model
from ikgame.level.library import shipped_levels
from ikgame.level.loader import (
    MAX_ASSET_BYTES,
    MAX_FILE_BYTES,
    MAX_SPRITE_BYTES,
    MAX_SPRITE_PIXELS,
    MAX_SPRITE_SIDE,
    MAX_SPRITE_TOTAL_PIXELS,
    LevelError,
    Problem,
    load_level,
)
from ikgame.level.model import Level, step_count

__all__ = [
    "validate_files",
    "level_rows",
    "level_schema",
    "schema_text",
    "reference_markdown",
]

SCHEMA_DIALECT: Final = "https://json-schema.org/draft/2020-12/schema"

_SECTIONS: Final = (
    ("The file", "Level", "The top-level tables and arrays of tables of a level file."),
    ("`[level]`", "LevelInfo", None),
    ("`[world]`", "WorldConfig", None),
    ("`[chain]`", "ChainConfig", None),
    ("`[[chain.links]]`", "LinkConfig", None),
    ("`[[chain.bones]]`", "BoneConfig", None),
    ('`[[obstacles]]` with `kind = "segment"`', "SegmentObstacle", None),
    ('`[[obstacles]]` with `kind = "circle"`', "CircleObstacle", None),
    ('`[[props]]` with `kind = "ball"`', "BallProp", None),
    ('`[[props]]` with `kind = "box"`', "BoxProp", None),
    ("`[[goals]]`", "Goal", None),
    ("`[[script]]` reach", "ReachStep", None),
    ('`[[script]]` follow = "line"', "FollowLine", None),
    ('`[[script]]` follow = "circle"', "FollowCircle", None),
    ('`[[script]]` follow = "lissajous"', "FollowLissajous", None),
    ('`[[script]]` follow = "polyline"', "FollowPolyline", None),
    ("`[[script]]` wait", "WaitStep", None),
    ("`[[script]]` set", "SetStep", None),
    ("The `set` table of a set step", "SetChanges", None),
    ("`[[script]]` sequence", "SequenceStep", None),
    ("`[gait]`", "GaitConfig", None),
)
"""Reference sections in reading order: heading, model name, and a description overriding the
model's docstring (whose doctest has no place in a reference)."""


def validate_files(
    paths: Iterable[str | Path], check: Callable[[Level, Path], object] | None = None
) -> list[Problem]:
    """Every problem in every level file (a folder stands for its ``*.toml`` files); empty when
    all are valid. ``check(level, path)`` may look further at each valid level (the files it
    names) and raise :class:`~ikgame.level.loader.LevelError`.

    >>> from ikgame.level.library import LEVELS_DIR
    >>> validate_files([LEVELS_DIR])
    []
    >>> [str(p) for p in validate_files(["no/such.toml"])]
    ['no/such.toml: no such level file']
    """
    problems: list[Problem] = []
    for path in paths:
        path = Path(path)
        files = sorted(path.glob("*.toml")) if path.is_dir() else [path]
        if not files:
            problems.append(Problem(str(path), None, "", "a folder without level files (*.toml)"))
        for file in files:
            try:
                level = load_level(file)
                if check is not None:
                    check(level, file)
            except LevelError as exc:
                problems.extend(exc.problems)
    return problems


def level_rows(paths: Iterable[str | Path] | None = None) -> list[dict[str, object]]:
    """One row per level (default: the shipped levels, in learning order) for ``ikgame list``.

    Keys: ``file`` (the file name), ``name``, ``description``, ``links`` (after ``repeat``),
    ``steps`` (each sequence point counted), ``solver``, ``expect``. Raises
    :class:`~ikgame.level.loader.LevelError` for an invalid file.

    >>> row = level_rows()[0]
    >>> row["file"], row["links"], row["expect"]
    ('01_first_reach.toml', 3, 'passed')
    """
    rows = []
    for path in shipped_levels() if paths is None else [Path(p) for p in paths]:
        level = load_level(path)
        rows.append(
            {
                "file": path.name,
                "name": level.level.name,
                "description": level.level.description,
                "links": len(level.chain.expanded_links),
                "steps": step_count(level.script),
                "solver": level.chain.solver,
                "expect": level.level.expect,
            }
        )
    return rows


def level_schema() -> dict[str, object]:
    """The JSON Schema (2020-12) of a level file, from the model, with the file's key names.

    >>> schema = level_schema()
    >>> schema["title"], schema["properties"]["world"]["$ref"]
    ('ikgame level', '#/$defs/WorldConfig')
    """
    schema = Level.model_json_schema(by_alias=True)
    schema.pop("title", None)
    schema.pop("description", None)
    return {
        "$schema": SCHEMA_DIALECT,
        "title": "ikgame level",
        "description": "A level of ikgame, a 2D physics sandbox for procedural animation: a "
        "motorised chain, its world, and the script it plays. Units: px, s, degrees. "
        "Reference: docs/levels.md.",
        **schema,
    }


def schema_text() -> str:
    """:func:`level_schema` as the exact text of ``assets/level.schema.json`` (2-space indent,
    trailing newline), so that writing it twice gives the same bytes.

    >>> schema_text().endswith("}\\n")
    True
    """
    return json.dumps(level_schema(), indent=2, ensure_ascii=False) + "\n"


def reference_markdown() -> str:
    """The field reference of docs/levels.md (Markdown): every table of the format, every key
    with its type, default, allowed range and meaning, then the size limits.

    >>> "| `tick_rate` | integer | `240` | 30 ≤ v ≤ 2000 |" in reference_markdown()
    True
    """
    schema = level_schema()
    defs = schema["$defs"]
    out = []
    for heading, name, description in _SECTIONS:
        table = schema if name == "Level" else defs[name]
        out += [f"### {heading}", "", description or _sentence(table["description"]), ""]
        out += ["| Key | Type | Default | Range | Meaning |", "|---|---|---|---|---|"]
        required = set(table.get("required", ()))
        for key, prop in table["properties"].items():
            kind, allowed = _type_and_range(prop)
            default = "required" if key in required else _default(prop.get("default"))
            meaning = prop.get("description", "")
            out.append(f"| `{key}` | {kind} | {default} | {allowed} | {meaning} |")
        out.append("")
    out += ["### Limits", "", "| Limit | Value |", "|---|---|"]
    for label, value in _limits():
        out.append(f"| {label} | {value} |")
    return "\n".join(out) + "\n"


def _limits() -> list[tuple[str, str]]:
    return [
        ("Level file size", f"{MAX_FILE_BYTES:,} bytes"),
        ("Size of a theme file", f"{MAX_ASSET_BYTES:,} bytes"),
        ("Size of a sprite image file", f"{MAX_SPRITE_BYTES:,} bytes"),
        (
            "Pixels of a sprite image",
            f"{MAX_SPRITE_PIXELS:,}, at most {MAX_SPRITE_SIDE} px a side",
        ),
        ("Pixels of all a level's sprite images together", f"{MAX_SPRITE_TOTAL_PIXELS:,}"),
        ("Links in the chain or tree (after `repeat`)", str(model.MAX_LINKS)),
        ("Duration", f"{model.MAX_DURATION:g} s"),
        ("Recorded frames (`duration` x `fps`)", f"{model.MAX_FRAMES:,}"),
        ("Physics ticks (`duration` x `tick_rate`)", f"{model.MAX_TICKS:,}"),
        ("Script steps (each `sequence` point counts)", str(model.MAX_STEPS)),
        ("Points in a `polyline` or a `sequence`", f"{model.MAX_POINTS:,}"),
        ("Obstacles", str(model.MAX_OBSTACLES)),
        ("Props", str(model.MAX_PROPS)),
        ("Goals", str(model.MAX_GOALS)),
        ("Any coordinate or length", f"{model.MAX_COORD:g} px"),
    ]


def _type_and_range(prop: dict) -> tuple[str, str]:
    """A property's type and allowed values in words."""
    if "oneOf" in prop:
        kinds, ranges = zip(*(_type_and_range(option) for option in prop["oneOf"]), strict=True)
        return " or ".join(kinds), "; ".join(r for r in ranges if r)
    options = [p for p in prop.get("anyOf", [prop]) if p.get("type") != "null"]
    (prop,) = options
    if "const" in prop:
        return f'`"{prop["const"]}"`', ""
    if "enum" in prop:
        return "string", "one of " + ", ".join(f'`"{v}"`' for v in prop["enum"])
    if "$ref" in prop:
        return "table", ""
    kind = prop.get("type")
    if kind in ("number", "integer"):
        return kind, _bounds(prop)
    if kind == "boolean":
        return "boolean", ""
    if kind == "string":
        low, high = prop.get("minLength", 0), prop.get("maxLength")
        letters = ", letters, digits, _ and -" if prop.get("pattern") == model.KEY_PATTERN else ""
        return "string", f"{low}..{high} characters{letters}"
    if kind == "object":
        (value,) = prop["patternProperties"].values()
        element, _ = _type_and_range(value)
        low, high = prop.get("minProperties", 0), prop.get("maxProperties")
        return f"table of name = {element}", f"{low}..{high} entries"
    if kind == "array" and "prefixItems" in prop:
        items = prop["prefixItems"]
        bounds = {_bounds(item) for item in items}
        each = f"each {bounds.pop()}" if len(bounds) == 1 else ""
        return f"{len(items)} numbers", each
    if kind == "array":
        element, _ = _type_and_range(prop["items"]) if "type" in prop["items"] else ("table", "")
        if "oneOf" in prop["items"]:
            element = "table"
        low, high = prop.get("minItems", 0), prop.get("maxItems")
        return f"list of {element}", f"{low}..{high} items"
    raise ValueError(f"no reference wording for the schema {prop}")


def _sentence(description: str) -> str:
    """A model's docstring without the table name it starts with (the heading has it)."""
    description = " ".join(description.split())
    if description.startswith("["):
        rest = description.split(": ", 1)[1]
        description = rest[0].upper() + rest[1:]
    return description


def _bounds(prop: dict) -> str:
    low = (
        f"{_number(prop['minimum'])} ≤ "
        if "minimum" in prop
        else f"{_number(prop['exclusiveMinimum'])} < "
        if "exclusiveMinimum" in prop
        else ""
    )
    high = (
        f" ≤ {_number(prop['maximum'])}"
        if "maximum" in prop
        else f" < {_number(prop['exclusiveMaximum'])}"
        if "exclusiveMaximum" in prop
        else ""
    )
    return f"{low}v{high}" if low or high else "any"


def _number(value: float) -> str:
    return f"{value:g}"


def _default(value: object) -> str:
    if value is None:
        return "none"
    if isinstance(value, dict):
        return "see its table"
    if isinstance(value, list) and not value:
        return "none"
    return f"`{json.dumps(value)}`"
