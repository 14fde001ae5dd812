"""Load a level file: TOML -> validated :class:`~ikgame.level.model.Level`.

Every problem is reported with the file, the line where it can be found, the field's path and
what was expected, so a level designer never has to read a traceback.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Final

from pydantic import ValidationError

from ikgame.level.model import Level

__all__ = ["LevelError", "Problem", "load_level", "parse_level"]

MAX_FILE_BYTES: Final = 1_000_000
"""A level is a few kilobytes; anything this large is a mistake or an attack."""

_TAGGED: Final = ("script", "obstacles")
"""Lists of tagged unions: pydantic names the member's tag after the index."""
_HEADER = re.compile(r"^\s*(\[\[?)\s*([A-Za-z0-9_.\-\" ]+?)\s*\]\]?\s*(#.*)?$")


@dataclass(frozen=True)
class Problem:
    """One thing wrong with a level file.

    >>> str(Problem("a.toml", 3, "chain.gain", "must be > 0"))
    'a.toml:3: chain.gain: must be > 0'
    """

    file: str
    line: int | None
    field: str
    message: str

    def __str__(self) -> str:
        where = self.file if self.line is None else f"{self.file}:{self.line}"
        return (
            f"{where}: {self.field}: {self.message}" if self.field else f"{where}: {self.message}"
        )


class LevelError(ValueError):
    """A level file that cannot be used; ``problems`` lists every reason.

    >>> str(LevelError([Problem("a.toml", None, "", "not found")]))
    'a.toml: not found'
    """

    def __init__(self, problems: list[Problem]) -> None:
        self.problems = problems
        super().__init__("\n".join(str(p) for p in problems))


def load_level(path: str | Path) -> Level:
    """Read and validate a level file; raise :class:`LevelError` naming every problem.

    >>> load_level("levels/01_first_reach.toml").level.name  # doctest: +SKIP
    'First reach'
    """
    path = Path(path)
    name = str(path)
    try:
        if path.stat().st_size > MAX_FILE_BYTES:
            raise LevelError([Problem(name, None, "", f"larger than {MAX_FILE_BYTES} bytes")])
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise LevelError([Problem(name, None, "", "no such level file")]) from None
    except IsADirectoryError:
        raise LevelError([Problem(name, None, "", "is a folder, not a level file")]) from None
    except UnicodeDecodeError as exc:
        raise LevelError([Problem(name, None, "", f"not UTF-8 text ({exc.reason})")]) from None
    except OSError as exc:
        raise LevelError([Problem(name, None, "", f"cannot be read ({exc.strerror})")]) from None
    return parse_level(text, name)


def parse_level(text: str, file: str = "<level>") -> Level:
    """Validate level TOML text; ``file`` names it in error messages.

    >>> parse_level('[level]\\nname = 1', 'x.toml')
    Traceback (most recent call last):
    ...
    ikgame.level.loader.LevelError: x.toml:2: level.name: Input should be a valid string (got 1)
    x.toml:1: level.duration: Field required
    x.toml: chain: Field required
    x.toml: script: Field required
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        line = getattr(exc, "lineno", None)
        message = getattr(exc, "msg", str(exc))
        raise LevelError([Problem(file, line, "", f"invalid TOML: {message}")]) from None
    try:
        return Level.model_validate(data)
    except ValidationError as exc:
        tables = _tables(text)
        problems = []
        for err in exc.errors(include_url=False):
            loc = _without_tags(err["loc"])
            problems.append(
                Problem(file, _locate(text, tables, loc), _field_path(loc), _message(err))
            )
        raise LevelError(problems) from None


def _without_tags(loc: tuple[object, ...]) -> tuple[object, ...]:
    """Drop the union tags pydantic puts in a path: ``script[0].reach.hold`` is ``script[0].hold``."""
    if len(loc) > 3 and loc[0] in _TAGGED and isinstance(loc[1], int):
        return loc[:2] + loc[3:]
    return loc


def _field_path(loc: tuple[object, ...]) -> str:
    """``('chain', 'links', 1, 'length')`` -> ``chain.links[1].length``."""
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else str(part)
    return out


def _message(err: dict) -> str:
    message = err["msg"].removeprefix("Value error, ")
    if err["type"] == "extra_forbidden":
        return "unknown key (check the spelling; see docs/levels.md)"
    if err["type"] == "missing":
        return message
    value = err.get("input")
    if isinstance(value, dict | list) or value is None:
        return message
    return f"{message} (got {value!r})"


def _tables(text: str) -> dict[tuple[object, ...], int]:
    """Map each table header's path (with array-of-table indices) to its line number."""
    tables: dict[tuple[object, ...], int] = {(): 1}
    counts: dict[tuple[str, ...], int] = {}
    for number, line in enumerate(text.splitlines(), start=1):
        match = _HEADER.match(line)
        if not match:
            continue
        keys = tuple(k.strip().strip('"') for k in match.group(2).split("."))
        path: list[object] = []
        for depth, key in enumerate(keys):
            path.append(key)
            prefix = keys[: depth + 1]
            if prefix in counts and depth < len(keys) - 1:
                path.append(counts[prefix] - 1)
        if match.group(1) == "[[":
            counts[keys] = counts.get(keys, 0) + 1
            path.append(counts[keys] - 1)
        tables[tuple(path)] = number
    return tables


def _locate(
    text: str, tables: dict[tuple[object, ...], int], loc: tuple[object, ...]
) -> int | None:
    """The line of ``loc`` in ``text``: its key inside the deepest table that contains it."""
    for cut in range(len(loc), -1, -1):
        prefix = tuple(loc[:cut])
        if prefix not in tables:
            continue
        start = tables[prefix]
        if cut == len(loc) or not isinstance(loc[cut], str):
            return start if prefix else None
        key = re.compile(rf"^\s*\"?{re.escape(str(loc[cut]))}\"?\s*=")
        lines = text.splitlines()
        for number in range(start if prefix else 1, len(lines) + 1):
            line = lines[number - 1]
            if number > start and _HEADER.match(line):
                break
            if key.match(line):
                return number
        return start if prefix else None
    return None
