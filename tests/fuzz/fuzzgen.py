"""Level files for fuzzing: generated from the level model's JSON Schema, and mutated as raw text.

:func:`generated_level` walks the schema the model publishes (so new fields are fuzzed without a
change here), samples every number across its whole range (log-uniform where the range spans
magnitudes, the edges now and then), then caps the sizes that drive a run's cost, so a case runs
in well under a second. :func:`mutated_text` breaks a level's text the ways a careless or hostile
user would: truncation, stray bytes, huge numbers, deep nesting, long keys, markup in strings.
Everything is driven by one ``random.Random``: a seed is a case.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import random
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ikgame.cli import main
from ikgame.level.library import LEVELS_DIR
from ikgame.level.tools import level_schema

_SCHEMA = level_schema()
_DEFS = _SCHEMA["$defs"]
MAX_ITEMS = 4  # items of any array: enough to mix kinds, few enough to run fast
MAX_LINKS = 12
MAX_DURATION = 2.0  # s
MAX_TICK_RATE = 480
MAX_ITERATIONS = 20
_SPRITES = ("sprites/ball.png", "sprites/claw.png")
"""Sprites shipped in assets/, which any level may name."""
_TEXTS = ("x", "ball", "A level", ":100: [bold]red[/] :1234:", "ünï cödé", "b[/]", "p")


def generated_level(rng: random.Random) -> dict[str, Any]:
    """A level as a dict, mostly valid: drawn from the schema, then made cheap to run and
    consistent where the schema cannot say it (goals name existing props)."""
    level = _value(rng, _SCHEMA)
    level.setdefault("world", {})
    _make_chain(rng, level)
    _make_cheap(rng, level)
    props = level.get("props", [])
    for i, prop in enumerate(props):
        if rng.random() < 0.9:
            prop["name"] = f"p{i}"
    names = [p["name"] for p in props]
    goals = [g for g in level.get("goals", []) if names]
    for goal in goals:
        goal["prop"] = rng.choice(names)
    level["goals"] = goals
    for step in level["script"]:
        if "set" in step:
            if not {"gravity", "solver", "gain", "base", "angle"} & set(step["set"]):
                step["set"]["gain"] = 5.0
            if not {"base", "angle"} & set(step["set"]):
                step["set"].pop("over", None)
    # The orderings and names the schema cannot express: a careless user gets these wrong now
    # and then, the mutations cover that.
    level["level"]["theme"] = rng.choice(["dark", "light", None])
    if level["level"]["theme"] is None:
        del level["level"]["theme"]
    # A sprite names a file: a shipped one from assets/ now and then, else none.
    for body in [*level["chain"]["links"], *props]:
        if "sprite" in body and rng.random() < 0.3:
            body["sprite"] = rng.choice(_SPRITES)
        elif not ("sprite" in body and rng.random() < 0.1):  # a few name a missing file
            for key in ("sprite", "sprite_pivot", "sprite_scale"):
                body.pop(key, None)
    if rng.random() < 0.5:  # a chain of one material, as most levels have
        for link in level["chain"]["links"]:
            link["mass"] = level["chain"]["links"][0].get("mass", 1.0)
    for link in level["chain"]["links"]:
        if "limits" in link:
            low, high = sorted(link["limits"])
            link["limits"] = [low, high] if low < high else [-90.0, 90.0]
    for region in [level["world"].get("bounds"), *(g["region"] for g in goals)]:
        if region is not None:
            region[:] = _ordered(region)
    if all("set" in step for step in level["script"]) or "set" in level["script"][-1]:
        level["script"].append({"wait": 0.5})
    return level


def _make_chain(rng: random.Random, level: dict[str, Any]) -> None:
    """Make the level a chain of links whose script aims its tip at points, as a chain level
    is written; tests/level covers trees, effector names and gaits, which runs do not play."""
    chain = level["chain"]
    chain.pop("bones", None)
    if not chain.get("links"):
        chain["links"] = [_value(rng, _DEFS["LinkConfig"])]
    level.pop("gait", None)
    for step in level["script"]:
        if isinstance(step.get("reach"), dict):
            step["reach"] = [round(rng.uniform(-200.0, 200.0), 3) for _ in range(2)]
        step.pop("effector", None)


def _ordered(region: list[float]) -> list[float]:
    xmin, xmax = sorted(region[0::2])
    ymin, ymax = sorted(region[1::2])
    return [xmin, ymin, xmax + (xmin == xmax), ymax + (ymin == ymax)]


def _make_cheap(rng: random.Random, level: dict[str, Any]) -> None:
    info, world, chain = level["level"], level["world"], level["chain"]
    info["duration"] = min(info["duration"], rng.choice([MAX_DURATION, 0.5, 0.05]))
    world["tick_rate"] = min(world.get("tick_rate", 240), MAX_TICK_RATE)
    world["fps"] = min(world.get("fps", 30), world["tick_rate"])
    info["duration"] = max(info["duration"], 1.0 / world["tick_rate"])
    chain["iterations"] = min(chain.get("iterations", 10), MAX_ITERATIONS)
    budget = MAX_LINKS
    for link in chain["links"]:
        link["repeat"] = max(1, min(link.get("repeat", 1), budget))
        budget -= link["repeat"]
    chain["links"] = [link for link in chain["links"] if link["repeat"] >= 1][:MAX_LINKS]
    for step in level["script"]:
        for key in ("sequence", "points"):
            if key in step:
                step[key] = step[key][:MAX_ITEMS]


def _value(rng: random.Random, node: dict[str, Any]) -> Any:
    if "$ref" in node:
        return _value(rng, _DEFS[node["$ref"].rsplit("/", 1)[1]])
    if "anyOf" in node:
        options = [o for o in node["anyOf"] if o.get("type") != "null"]
        return _value(rng, rng.choice(options))
    if "oneOf" in node and "type" not in node:
        return _value(rng, rng.choice(node["oneOf"]))
    if "const" in node:
        return node["const"]
    if "enum" in node:
        return rng.choice(node["enum"])
    kind = node.get("type")
    if kind == "object":
        out = {}
        # A table that needs one of several keys says which in its alternatives.
        required = {
            *node.get("required", ()),
            *rng.choice(node.get("oneOf", [{}])).get("required", ()),
        }
        for key, sub in node.get("properties", {}).items():
            if key in required or rng.random() < 0.5:
                value = _value(rng, sub)
                if value is not None:
                    out[key] = value
        return out
    if kind == "array":
        if "prefixItems" in node:
            return [_value(rng, sub) for sub in node["prefixItems"]]
        low = node.get("minItems", 0)
        count = rng.randint(low, max(low, min(node.get("maxItems", MAX_ITEMS), MAX_ITEMS)))
        return [_value(rng, node["items"]) for _ in range(count)]
    if kind == "integer":
        low, high = node.get("minimum", 0), node.get("maximum", 1000)
        return rng.choice([low, high, rng.randint(low, high)])
    if kind == "number":
        return _number(rng, node)
    if kind == "string":
        text = rng.choice(_TEXTS)
        return text[: node.get("maxLength", 80)] or "x"
    if kind == "boolean":
        return rng.random() < 0.5
    return None


def _number(rng: random.Random, node: dict[str, Any]) -> float:
    low = node.get("minimum", node.get("exclusiveMinimum", -1e6))
    high = node.get("maximum", 1e6)
    exclusive = "exclusiveMinimum" in node
    pick = rng.random()
    if pick < 0.1:
        return float(high)
    if pick < 0.2:
        return math.nextafter(float(low), math.inf) if exclusive else float(low)
    if low >= 0 and high > 0:
        floor = max(low, high * 1e-9) if low > 0 or exclusive else high * 1e-9
        if low == 0 and not exclusive and rng.random() < 0.1:
            return 0.0
        return (
            round(math.exp(rng.uniform(math.log(max(floor, 1e-300)), math.log(high))), 6) or floor
        )
    # Coordinates: mostly near the chain, now and then anywhere in range.
    scale = rng.choice([200.0, 200.0, 1000.0, high])
    return round(rng.uniform(max(low, -scale), min(high, scale)), 3)


def level_toml(level: dict[str, Any]) -> str:
    """A level dict as TOML text, written the way a person would: tables, arrays of tables."""
    lines: list[str] = []
    for table in ("level", "world", "chain"):
        if table not in level:
            continue
        body = level[table]
        lines.append(f"[{table}]")
        lines += [f"{k} = {_toml(v)}" for k, v in body.items() if k != "links"]
        for link in body.get("links", []) if table == "chain" else []:
            lines.append("[[chain.links]]")
            lines += [f"{k} = {_toml(v)}" for k, v in link.items()]
    for array in ("obstacles", "props", "goals", "script"):
        for item in level.get(array, []):
            lines.append(f"[[{array}]]")
            lines += [f"{_key(k)} = {_toml(v)}" for k, v in item.items()]
    return "\n".join(lines) + "\n"


def _key(key: str) -> str:
    return key if key.replace("_", "").isalnum() else f'"{key}"'


def _toml(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_key(k)} = {_toml(v)}" for k, v in value.items()) + "}"
    raise TypeError(value)


_HUGE = ("1" * 5000, "1." + "1" * 5000, "1e400", "-1e400", "9" * 30, "5e-324", "1e-200", "nan")


def mutated_text(rng: random.Random, text: str) -> str | bytes:
    """``text`` broken in one or two ways; bytes when the break is not valid UTF-8."""
    out: str | bytes = text
    for _ in range(rng.choice((1, 1, 2))):
        out = rng.choice(_MUTATIONS)(rng, out if isinstance(out, str) else out.decode("latin-1"))
    return out


def _truncate(rng: random.Random, text: str) -> str:
    return text[: rng.randint(0, len(text))]


def _stray_bytes(rng: random.Random, text: str) -> bytes:
    at = rng.randint(0, len(text))
    junk = bytes(rng.choice([0x00, 0x07, 0x1B, 0x80, 0xC3, 0xFF, 0x5B, 0x22]) for _ in range(3))
    return text[:at].encode() + junk + text[at:].encode()


def _huge_number(rng: random.Random, text: str) -> str:
    spots = [i for i, c in enumerate(text) if c.isdigit() and (i == 0 or not text[i - 1].isalnum())]
    if not spots:
        return text + f"\nx = {rng.choice(_HUGE)}\n"
    at = rng.choice(spots)
    end = at
    while end < len(text) and (text[end].isdigit() or text[end] in ".e-+_"):
        end += 1
    return text[:at] + rng.choice(_HUGE) + text[end:]


def _deep_nesting(rng: random.Random, text: str) -> str:
    depth = rng.choice((5, 20, 1000, 100_000))
    return text + f"\n[extra]\nx = {'[' * depth}1{']' * depth}\n"


def _long_key(rng: random.Random, text: str) -> str:
    parts = rng.choice((3, 9, 100_000))
    key = rng.choice(("a", "level", "chain")) + ".a" * parts if rng.random() < 0.5 else "k" * parts
    header = rng.random() < 0.5
    return text + (f"\n[{key}]\n" if header else f"\n{key} = 1\n")


def _swap_value(rng: random.Random, text: str) -> str:
    lines = text.splitlines()
    values = [i for i, line in enumerate(lines) if " = " in line]
    if not values:
        return text
    i = rng.choice(values)
    key = lines[i].split(" = ", 1)[0]
    new = rng.choice(('":100: [red]x[/]"', "true", "[]", "{}", "-1", "0", '"', "[1, 2, 3]"))
    lines[i] = f"{key} = {new}"
    return "\n".join(lines) + "\n"


def _drop_line(rng: random.Random, text: str) -> str:
    lines = text.splitlines()
    if lines:
        del lines[rng.randrange(len(lines))]
    return "\n".join(lines) + "\n"


def _duplicate_line(rng: random.Random, text: str) -> str:
    lines = text.splitlines()
    if lines:
        i = rng.randrange(len(lines))
        lines.insert(i, lines[i])
    return "\n".join(lines) + "\n"


_MUTATIONS = (
    _truncate,
    _stray_bytes,
    _huge_number,
    _deep_nesting,
    _long_key,
    _swap_value,
    _drop_line,
    _duplicate_line,
)


# -- running a case ------------------------------------------------------------------------------


@dataclass(frozen=True)
class Outcome:
    """What ``ikgame run`` did with one case."""

    code: int
    errors: tuple[str, ...]  # stderr lines
    status: str | None  # from results.json, when written
    wrote: bool  # whether the out folder exists afterwards
    divergence: str = ""


def case_text(seed: int) -> tuple[str, str | bytes]:
    """The case of ``seed``: ``("generated", text)`` or ``("mutated", text or bytes)``."""
    rng = random.Random(seed)
    if rng.random() < 0.6:
        return "generated", level_toml(generated_level(rng))
    if rng.random() < 0.15:
        source = rng.choice(sorted(LEVELS_DIR.glob("*.toml"))).read_text(encoding="utf-8")
    else:
        source = level_toml(generated_level(rng))
    return "mutated", mutated_text(rng, source)


def run_case(data: str | bytes, folder: Path, *, frames: bool = False) -> Outcome:
    """Write ``data`` as a level in ``folder`` and ``ikgame run`` it in this process."""
    level = folder / "case.toml"
    level.write_bytes(data if isinstance(data, bytes) else data.encode("utf-8"))
    out = folder / "out"
    options = ["--size", "32x18", "--no-gif", "--workers", "1"] if frames else ["--no-frames"]
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(["run", str(level), "--out", str(out), "--quiet", *options])
    status = divergence = None
    if (out / "results.json").is_file():
        results = json.loads((out / "results.json").read_text(encoding="utf-8"))
        status, divergence = results["status"], results.get("divergence", "")
    return Outcome(code, tuple(err.getvalue().splitlines()), status, out.exists(), divergence or "")


def unlocated(outcome: Outcome, file: str) -> list[str]:
    """Error lines that give no line number yet are not about the file as a whole (a missing
    table, unreadable bytes, a file-level limit)."""
    lines = []
    for line in outcome.errors:
        rest = line.removeprefix("error: ").removeprefix(file)
        if rest.startswith(":") and rest[1:].split(":", 1)[0].isdigit():
            continue
        field, _, message = rest.removeprefix(": ").partition(": ")
        if message == "Field required" and "." not in field and "[" not in field:
            continue  # a missing top-level table: there is no line to point at
        if not message:  # "file: what" with no field: about the whole file
            continue
        lines.append(line)
    return lines
