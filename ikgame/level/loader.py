"""Load a level file: TOML -> validated :class:`~ikgame.level.model.Level`.

Every problem is reported with the file, the line where it can be found, the field's path and
what was expected, so a level designer never has to read a traceback.

TOML is data: nothing in a level runs code. The only files a level may name (its ``theme``, its
links' and props' ``sprite`` images) must resolve, symlinks followed, inside the level's own folder
or ``assets/`` (:func:`resolve_level_file`). Sprite images are checked here without being decoded
(this layer does not import Pillow): a PNG's structure, every chunk's checksum and its size in
pixels (:func:`sprite_file`); the renderer decodes them (:mod:`ikgame.skins`).
"""

from __future__ import annotations

import re
import struct
import tomllib
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Final

from pydantic import ValidationError

from ikgame.level.library import ASSETS_DIR, THEMES_DIR
from ikgame.level.model import FOLLOW_SHAPES, KEY_PATTERN, Level

__all__ = [
    "LevelError",
    "Problem",
    "load_level",
    "parse_level",
    "resolve_level_file",
    "level_theme",
    "sprite_file",
    "sprite_fields",
    "problem_at",
    "MAX_FILE_BYTES",
    "MAX_ASSET_BYTES",
    "MAX_SPRITE_BYTES",
    "MAX_SPRITE_SIDE",
    "MAX_SPRITE_PIXELS",
    "MAX_SPRITE_TOTAL_PIXELS",
]

MAX_FILE_BYTES: Final = 1_000_000
"""A level is a few kilobytes; anything this large is a mistake or an attack."""
MAX_ASSET_BYTES: Final = 1_000_000
"""Largest theme file a level may name (a theme is a few hundred bytes)."""
MAX_SPRITE_BYTES: Final = 2_000_000
"""Largest sprite image file."""
MAX_SPRITE_SIDE: Final = 2048
"""Largest width or height of a sprite image, px."""
MAX_SPRITE_PIXELS: Final = 1024 * 1024
"""Pixels in one sprite image (decoded, each takes 4 bytes)."""
MAX_SPRITE_TOTAL_PIXELS: Final = 8 * 1024 * 1024
"""Pixels of a level's distinct sprite images together: bounds the memory a level's art takes."""
_PNG_SIGNATURE: Final = b"\x89PNG\r\n\x1a\n"
MAX_KEY_PARTS: Final = 8
"""Parts of one dotted key or table header (``a.b.c`` has 3); the format needs 3 at most."""
MAX_NESTING: Final = 8
"""Arrays and inline tables inside each other; the format needs 3 at most."""
MAX_TOKEN_CHARS: Final = 100
"""Characters of one bare key or number (a float needs 25)."""
MAX_STRING_CHARS: Final = 10_000
"""Characters of one string, as written (a description may have 2000)."""
MAX_PROBLEMS: Final = 50
"""Problems listed for one file: more than this helps nobody, and each costs time."""

_TAGGED: Final = ("script", "obstacles", "props")
"""Lists of tagged unions: pydantic names the member's tag after the index."""
_TAGS: Final = frozenset(
    ("reach", "follow", "wait", "set", "sequence", "segment", "circle", "ball", "box")
)
"""The tags themselves, told apart from field names a level-wide check may point at."""
_FOLLOW_KEYS: Final = {
    shape: frozenset(f.alias or name for name, f in model.model_fields.items())
    for shape, model in FOLLOW_SHAPES.items()
}
_TOML_AT = re.compile(r"\(at line (\d+), column (\d+)\)$")
_KEY = re.compile(r'^\s*"?([A-Za-z0-9_\-]+)"?\s*[=.]')
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

    >>> from ikgame.level.library import DEFAULT_LEVEL
    >>> load_level(DEFAULT_LEVEL).level.name
    'First reach'
    """
    path = Path(path)
    name = str(path)
    try:
        if path.is_dir():
            raise LevelError([Problem(name, None, "", "is a folder, not a level file")])
        if path.exists() and not path.is_file():
            raise LevelError([Problem(name, None, "", "is not a regular file")])
        # Read one byte past the limit rather than trust a size the file system reports.
        with path.open("rb") as handle:
            data = handle.read(MAX_FILE_BYTES + 1)
    except FileNotFoundError:
        raise LevelError([Problem(name, None, "", "no such level file")]) from None
    except OSError as exc:
        raise LevelError([Problem(name, None, "", f"cannot be read ({exc.strerror})")]) from None
    if len(data) > MAX_FILE_BYTES:
        raise LevelError([Problem(name, None, "", f"larger than {MAX_FILE_BYTES} bytes")])
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise LevelError([Problem(name, line, "", f"not UTF-8 text ({exc.reason})")]) from None
    level = parse_level(text, name)
    if level.level.theme is not None:
        try:
            level_theme(level, path)
        except ValueError as exc:
            line = _Locator(text)(("level", "theme"))
            raise LevelError([Problem(name, line, "level.theme", str(exc))]) from None
    problems = _sprite_problems(level, path, text)
    if problems:
        raise LevelError(problems)
    return level


def sprite_fields(level: Level) -> list[tuple[tuple[str | int, ...], str]]:
    """Every sprite a level names, as (field location, file name), links first.

    >>> from ikgame.level.library import LEVELS_DIR
    >>> sprite_fields(load_level(LEVELS_DIR / "14_skinned_arm.toml"))[0]
    (('chain', 'links', 0, 'sprite'), 'sprites/upper_arm.png')
    """
    fields: list[tuple[tuple[str | int, ...], str]] = []
    chain = level.chain
    for i, link in enumerate(chain.entries):
        if link.sprite is not None:
            fields.append((("chain", chain.entry_field, i, "sprite"), link.sprite))
    for i, prop in enumerate(level.props):
        if prop.sprite is not None:
            fields.append((("props", i, "sprite"), prop.sprite))
    return fields


def sprite_file(name: str, level_file: str | Path) -> tuple[Path, tuple[int, int]]:
    """The real path of a sprite image a level names and its size (width, height) in px.

    ``ValueError`` when :func:`resolve_level_file` refuses it, when it is not a whole PNG file
    (signature, chunk lengths and checksums, IHDR first, IEND last), or when it is larger than
    ``MAX_SPRITE_SIDE`` px a side or ``MAX_SPRITE_PIXELS`` pixels.

    >>> from ikgame.level.library import LEVELS_DIR
    >>> sprite_file("sprites/ball.png", LEVELS_DIR / "14_skinned_arm.toml")[1]
    (96, 96)
    """
    path = resolve_level_file(name, level_file, MAX_SPRITE_BYTES)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ValueError(f"{name!r} cannot be read ({exc.strerror})") from None
    width, height = _png_size(data, name)
    if not (
        0 < width <= MAX_SPRITE_SIDE
        and 0 < height <= MAX_SPRITE_SIDE
        and width * height <= MAX_SPRITE_PIXELS
    ):
        raise ValueError(
            f"{name!r} is {width}x{height} px; a sprite is at most {MAX_SPRITE_SIDE} px a side "
            f"and {MAX_SPRITE_PIXELS:,} pixels"
        )
    return path, (width, height)


def _png_size(data: bytes, name: str) -> tuple[int, int]:
    """Width and height of PNG ``data`` once its chunk structure checks out."""
    if not data.startswith(_PNG_SIGNATURE):
        raise ValueError(f"{name!r} is not a PNG image")
    chunks: list[bytes] = []
    pos = len(_PNG_SIGNATURE)
    while pos < len(data) and (not chunks or chunks[-1] != b"IEND"):
        if pos + 12 > len(data):
            raise ValueError(f"{name!r} is cut short (a damaged PNG)")
        length, kind = struct.unpack(">I4s", data[pos : pos + 8])
        end = pos + 12 + length
        if end > len(data):
            raise ValueError(f"{name!r} is cut short (a damaged PNG)")
        (crc,) = struct.unpack(">I", data[end - 4 : end])
        if zlib.crc32(data[pos + 4 : end - 4]) != crc:
            raise ValueError(f"{name!r} is damaged (a PNG chunk fails its checksum)")
        chunks.append(kind)
        pos = end
    if not chunks or chunks[0] != b"IHDR" or b"IDAT" not in chunks or chunks[-1] != b"IEND":
        raise ValueError(f"{name!r} is not a whole PNG image (IHDR, IDAT or IEND missing)")
    width, height = struct.unpack(">II", data[16:24])
    return width, height


def _sprite_problems(level: Level, level_file: Path, text: str) -> list[Problem]:
    """Every sprite that cannot be used, and the pixel budget of them all."""
    fields = sprite_fields(level)
    if not fields:
        return []
    locate = _Locator(text)
    problems = []
    # Each file is read once, however many links name it: a level may name 300 sprites.
    checked: dict[str, tuple[Path, int] | str] = {}
    for loc, name in fields:
        if name not in checked:
            try:
                path, (width, height) = sprite_file(name, level_file)
                checked[name] = (path, width * height)
            except ValueError as exc:
                checked[name] = str(exc)
        result = checked[name]
        if isinstance(result, str):
            where = locate(loc)
            problems.append(Problem(str(level_file), where, _field_path(loc), result))
    sizes = dict(r for r in checked.values() if not isinstance(r, str))
    if not problems and sum(sizes.values()) > MAX_SPRITE_TOTAL_PIXELS:
        loc = fields[-1][0]
        problems.append(
            Problem(
                str(level_file),
                locate(loc),
                _field_path(loc),
                f"the level's sprite images hold {sum(sizes.values()):,} pixels together; "
                f"at most {MAX_SPRITE_TOTAL_PIXELS:,}",
            )
        )
    return problems


def problem_at(level_file: str | Path, loc: tuple[str | int, ...], message: str) -> Problem:
    """A problem found after loading, at the field ``loc`` of ``level_file`` (its line looked up
    in the file as it is now).

    >>> from ikgame.level.library import DEFAULT_LEVEL
    >>> str(problem_at(DEFAULT_LEVEL, ("chain", "solver"), "no"))  # doctest: +ELLIPSIS
    '...01_first_reach.toml:...: chain.solver: no'
    """
    try:
        with open(level_file, "rb") as handle:
            text = handle.read(MAX_FILE_BYTES).decode("utf-8", errors="replace")
        line = _Locator(text)(loc)
    except OSError:
        line = None
    return Problem(str(level_file), line, _field_path(loc), message)


def resolve_level_file(name: str, level_file: str | Path, max_bytes: int = MAX_ASSET_BYTES) -> Path:
    """The real path of a file a level names: looked up in the level's folder, then in
    ``assets/``; ``ValueError`` when it is missing, larger than ``max_bytes``, or a symlink leads
    out of both.

    ``name`` has passed :func:`~ikgame.level.model.check_relative_file` (no absolute path, no
    ``..``); resolving catches the symlinks.

    >>> from ikgame.level.library import DEFAULT_LEVEL
    >>> resolve_level_file("themes/dark.json", DEFAULT_LEVEL).name
    'dark.json'
    """
    roots = (Path(level_file).resolve().parent, ASSETS_DIR.resolve())
    for root in roots:
        candidate = root / name
        if not (candidate.exists() or candidate.is_symlink()):
            continue
        real = candidate.resolve()
        if not any(real.is_relative_to(r) for r in roots):
            raise ValueError(
                f"{name!r} leads outside the level's folder and assets/ (through a symlink)"
            )
        if not real.is_file():
            raise ValueError(f"{name!r} is not a file")
        if real.stat().st_size > max_bytes:
            raise ValueError(f"{name!r} is larger than {max_bytes:,} bytes")
        return real
    raise ValueError(f"no file {name!r} in the level's folder or assets/")


def level_theme(level: Level, level_file: str | Path) -> str | Path | None:
    """The level's theme as the renderer's ``load_theme`` takes it: a shipped theme's name, the
    real path of a theme file (checked by :func:`resolve_level_file`), or None.

    >>> from ikgame.level.library import DEFAULT_LEVEL
    >>> level_theme(load_level(DEFAULT_LEVEL), DEFAULT_LEVEL) is None
    True
    """
    theme = level.level.theme
    if theme is None or theme.endswith(".json"):
        return None if theme is None else resolve_level_file(theme, level_file)
    if not (THEMES_DIR / f"{theme}.json").is_file():
        shipped = ", ".join(sorted(p.stem for p in THEMES_DIR.glob("*.json")))
        raise ValueError(f"no shipped theme {theme!r} (shipped: {shipped})")
    return theme


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
    _check_shape(text, file)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        # Python < 3.14 puts the position only in the message: "... (at line 2, column 21)".
        message = str(exc)
        at = _TOML_AT.search(message)
        line = int(at.group(1)) if at else None
        if message.endswith("(at end of document)"):
            line = text.count("\n") + (not text.endswith("\n"))
            message = message.removesuffix(" (at end of document)") + " (at the end of the file)"
        if at:
            message = f"{message[: at.start()]}(column {at.group(2)})"
        raise LevelError([Problem(file, line, "", f"invalid TOML: {message}")]) from None
    except (RecursionError, ValueError) as exc:
        # ValueError: an integer past Python's digit limit slipped through (not a TOMLDecodeError).
        what = "nested too deeply" if isinstance(exc, RecursionError) else "a number too long"
        raise LevelError([Problem(file, None, "", f"invalid TOML: {what}")]) from None
    try:
        return Level.model_validate(data)
    except ValidationError as exc:
        locate = _Locator(text)
        problems = []
        for err in exc.errors(include_url=False):
            loc = _without_tags(err["loc"])
            message = _message(err)
            if err["type"] in ("union_tag_invalid", "union_tag_not_found"):
                loc = (*loc, err["ctx"]["discriminator"].strip("'"))
            problems.append(Problem(file, locate(loc), _field_path(loc), message))
            if len(problems) == MAX_PROBLEMS:
                more = exc.error_count() - MAX_PROBLEMS
                if more:
                    problems.append(Problem(file, None, "", f"and {more} more problems"))
                break
        raise LevelError(problems) from None


_BARE = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-+")


def _check_shape(text: str, file: str) -> None:
    """Refuse TOML shapes that no level has and that make parsers slow: keys of many dotted
    parts, deep nesting, very long bare tokens (huge numbers) and strings.

    One pass over the text, so a hostile megabyte costs milliseconds. Strings and comments are
    skipped as TOML reads them; anything this scanner gets wrong is left to the TOML parser.

    >>> _check_shape("a.b.c.d.e.f.g.h.i = 1", "x.toml")
    Traceback (most recent call last):
    ...
    ikgame.level.loader.LevelError: x.toml:1: a key of more than 8 dotted parts
    """

    def refuse(what: str) -> LevelError:
        return LevelError([Problem(file, line, "", what)])

    line, depth, parts, token, i, n = 1, 0, 1, 0, 0, len(text)
    in_key = True  # at a key (line start, after '{' or ',' in an inline table) until '='
    while i < n:
        c = text[i]
        if c in _BARE:
            token += 1
            if token > MAX_TOKEN_CHARS:
                raise refuse(f"a bare key or number longer than {MAX_TOKEN_CHARS} characters")
            i += 1
            continue
        token = 0
        if c == "\n":
            line += 1
            parts, in_key = 1, depth == 0
        elif c == "#":
            end = text.find("\n", i)
            i = n if end < 0 else end
            continue
        elif c in "\"'":
            quote = text[i : i + 3] if text.startswith(c * 3, i) else c
            end = text.find(quote, i + len(quote))
            while quote[0] == '"' and end > 0 and _escaped(text, end):
                end = text.find(quote, end + 1)
            while len(quote) == 3 and end > 0 and text.startswith(quote, end + 1):
                end += 1  # """a"""" ends with a quote inside
            if end < 0 or (len(quote) == 1 and "\n" in text[i:end]):
                return  # unterminated: the TOML parser says where
            if end - i > MAX_STRING_CHARS:
                raise refuse(f"a string longer than {MAX_STRING_CHARS} characters")
            line += text.count("\n", i, end)
            i = end + len(quote)
            continue
        elif c in "[{":
            depth += 1
            if depth > MAX_NESTING:
                raise refuse(f"arrays or tables nested more than {MAX_NESTING} deep")
            in_key = in_key or c == "{"
        elif c in "]}":
            depth = max(0, depth - 1)
        elif c == "." and in_key:
            parts += 1
            if parts > MAX_KEY_PARTS:
                raise refuse(f"a key of more than {MAX_KEY_PARTS} dotted parts")
        elif c == "=":
            in_key, parts = False, 1
        elif c == ",":
            in_key, parts = True, 1
        i += 1


def _escaped(text: str, at: int) -> bool:
    """Whether the quote at ``at`` follows an odd number of backslashes."""
    count = 0
    while at - count - 1 >= 0 and text[at - count - 1] == "\\":
        count += 1
    return count % 2 == 1


def _without_tags(loc: tuple[object, ...]) -> tuple[object, ...]:
    """Drop the union tags pydantic puts in a path: ``script[0].reach.hold`` is
    ``script[0].hold``, ``script[0].follow.circle.radius`` is ``script[0].radius``, and
    ``script[0].reach.reach.table.left`` (a point or a table) is ``script[0].reach.left``; a
    dict key's own marker goes too."""
    loc = tuple(part for part in loc if part != "[key]")
    if len(loc) > 2 and loc[0] in _TAGGED and isinstance(loc[1], int) and loc[2] in _TAGS:
        rest = loc[3:]
        if loc[2] == "follow" and rest and rest[0] in FOLLOW_SHAPES:
            rest = rest[1:]
        if loc[2] == "reach" and rest[:1] == ("reach",) and rest[1:2] in (("point",), ("table",)):
            rest = rest[:1] + rest[2:]
        return loc[:2] + rest
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
    kind = err["type"]
    if kind == "extra_forbidden":
        loc = err["loc"]
        if len(loc) == 5 and loc[2] == "follow" and loc[3] in FOLLOW_SHAPES:
            return _follow_key_message(loc[3], str(loc[4]))
        if loc[2:] == ("reach", "effector"):
            return "a reach step names its effectors in a table: reach = { name = [x, y] }"
        return "unknown key (check the spelling; see docs/levels.md)"
    if kind == "missing" and isinstance(err["loc"][-1], int):
        return "too few values"
    if kind in ("missing", "union_tag_not_found"):
        return "Field required"
    if kind == "string_pattern_mismatch" and err["ctx"]["pattern"] == KEY_PATTERN:
        return f"must be letters, digits, '_' and '-' only (got {err['input']!r})"
    if kind == "string_pattern_mismatch":
        return f"must be printable text, without control characters (got {err['input']!r})"
    if kind == "union_tag_invalid":
        return f"must be one of {err['ctx']['expected_tags']} (got {err['ctx']['tag']!r})"
    if kind in ("level_rule", "step_kind"):
        return message
    value = err.get("input")
    if isinstance(value, dict | list) or value is None:
        return message
    return f"{message} (got {value!r})"


def _follow_key_message(shape: str, key: str) -> str:
    """Name the shapes a misplaced follow key belongs to, and the keys this shape takes."""
    common = frozenset.intersection(*_FOLLOW_KEYS.values())
    own = ", ".join(sorted(_FOLLOW_KEYS[shape] - common))
    owners = [s for s, keys in _FOLLOW_KEYS.items() if key in keys]
    if not owners:
        return f"unknown key (follow = {shape!r} takes {own}; see docs/levels.md)"
    return (
        f"belongs to follow = {' or '.join(repr(o) for o in owners)}, "
        f"not {shape!r} (which takes {own})"
    )


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
        for cut in range(1, len(path)):  # ``[a.b]`` defines ``a`` too, on the same line
            tables.setdefault(tuple(path[:cut]), number)
    return tables


class _Locator:
    """Finds the line of a field's path in a level's text; each table's keys are indexed once,
    so locating every problem of a file takes time linear in the file."""

    def __init__(self, text: str) -> None:
        self.lines = text.splitlines()
        self.tables = _tables(text)
        self._keys: dict[int, dict[str, int]] = {}

    def __call__(self, loc: tuple[object, ...]) -> int | None:
        """The line of ``loc``: its key inside the deepest table that contains it."""
        tables = self.tables
        for cut in range(len(loc), -1, -1):
            prefix = tuple(loc[:cut])
            if prefix not in tables:
                continue
            start = tables[prefix]
            if cut == len(loc) or not isinstance(loc[cut], str):
                return start if prefix else None
            if (*prefix, loc[cut], 0) in tables:  # an array of tables: its first header
                return tables[(*prefix, loc[cut], 0)]
            found = self._table_keys(start if prefix else 1).get(str(loc[cut]))
            return found if found is not None else start if prefix else None
        return None

    def _table_keys(self, start: int) -> dict[str, int]:
        """The first line of each key (``key =``, or a dotted ``key.sub =``) from ``start`` to
        the next table header."""
        if start not in self._keys:
            keys: dict[str, int] = {}
            for number in range(start, len(self.lines) + 1):
                line = self.lines[number - 1]
                if number > start and _HEADER.match(line):
                    break
                match = _KEY.match(line)
                if match:
                    keys.setdefault(match.group(1), number)
            self._keys[start] = keys
        return self._keys[start]
