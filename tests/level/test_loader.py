"""The loader against hostile and odd input: every failure is a LevelError naming the file."""

import os
import string
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ikgame.level.library import ASSETS_DIR, LEVELS_DIR
from ikgame.level.loader import (
    MAX_FILE_BYTES,
    LevelError,
    level_theme,
    load_level,
    parse_level,
    resolve_level_file,
)

GOOD = (LEVELS_DIR / "01_first_reach.toml").read_text(encoding="utf-8")
SMALL = (
    '[level]\nname = "x"\nduration = 2.0\n[chain]\n[[chain.links]]\nlength = 50.0\n'
    "[[script]]\nwait = 1.0\n"
)


def _problems(text: str) -> list[str]:
    with pytest.raises(LevelError) as exc:
        parse_level(text, "t.toml")
    return [str(p) for p in exc.value.problems]


def test_a_file_over_the_size_limit_is_refused_before_parsing(tmp_path):
    path = tmp_path / "big.toml"
    path.write_text(GOOD + "#" * MAX_FILE_BYTES)
    with pytest.raises(LevelError, match=f"larger than {MAX_FILE_BYTES} bytes"):
        load_level(path)


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="needs /dev/zero")
def test_a_device_is_refused_not_read_forever():
    with pytest.raises(LevelError, match="not a regular file"):
        load_level("/dev/zero")


def test_a_folder_and_a_missing_file_are_named(tmp_path):
    with pytest.raises(LevelError, match="is a folder"):
        load_level(tmp_path)
    with pytest.raises(LevelError, match="no such level file"):
        load_level(tmp_path / "nope.toml")


def test_deeply_nested_toml_is_an_error_not_a_crash():
    problems = _problems("a = " + "[" * 100_000 + "]" * 100_000)
    assert problems == ["t.toml:1: arrays or tables nested more than 8 deep"]


def test_too_many_steps_counting_each_sequence_point():
    points = ", ".join(["[10.0, 10.0]"] * 300)
    text = SMALL + f"[[script]]\nsequence = [{points}]\n" * 2
    assert _problems(text) == [
        "t.toml:7: script: the script runs 601 steps (each sequence point counts); at most 500"
    ]


def test_too_many_polyline_points():
    points = ", ".join(f"[{i}.0, 0.0]" for i in range(1001))
    text = SMALL + f'[[script]]\nfollow = "polyline"\npoints = [{points}]\nspeed = 10.0\n'
    assert _problems(text) == [
        "t.toml:11: script[1].points: List should have at most 1000 items after validation, "
        "not 1001"
    ]


def test_a_polyline_too_long_for_the_duration_limit():
    text = SMALL + '[[script]]\nfollow = "polyline"\npoints = [[0, 0], [9000, 0]]\nspeed = 1.0\n'
    assert _problems(text) == [
        "t.toml:12: script[1].speed: the path takes 9000 s at this speed; at most 600"
    ]


def test_too_many_ticks():
    text = SMALL.replace("duration = 2.0", "duration = 500.0") + "[world]\ntick_rate = 1000\n"
    assert _problems(text) == [
        "t.toml:3: level.duration: 500 s at 1000 ticks/s runs 500000 ticks; at most 300000 "
        "(shorten the level or lower world.tick_rate)"
    ]


def test_dotted_keys_and_sub_tables_are_located():
    text = SMALL + "[[script]]\nset.gravity = [0.0, 1e9]\n"
    assert _problems(text) == [
        "t.toml:10: script[1].set.gravity[1]: Input should be less than or equal to 100000 "
        "(got 1000000000.0)"
    ]
    text = SMALL + "[[script]]\n[script.set]\ngain = -1.0\n"
    assert _problems(text) == [
        "t.toml:11: script[1].set.gain: Input should be greater than 0 (got -1.0)"
    ]


def test_infinity_is_refused_like_nan():
    assert _problems(SMALL.replace("length = 50.0", "length = inf")) == [
        "t.toml:6: chain.links[0].length: Input should be a finite number (got inf)"
    ]


def test_a_level_names_files_only_inside_its_folder_or_assets(tmp_path):
    level_file = tmp_path / "lvl.toml"
    (tmp_path / "mine.json").write_text("{}")
    assert resolve_level_file("mine.json", level_file) == (tmp_path / "mine.json").resolve()
    assert resolve_level_file("themes/dark.json", level_file) == ASSETS_DIR / "themes/dark.json"
    (tmp_path / "sub").mkdir()
    with pytest.raises(ValueError, match="'sub' is not a file"):
        resolve_level_file("sub", level_file)
    outside = tmp_path.parent / f"{tmp_path.name}-outside.json"
    outside.write_text("{}")
    os.symlink(outside, tmp_path / "link.json")
    with pytest.raises(ValueError, match="leads outside"):
        resolve_level_file("link.json", level_file)


def test_a_symlink_that_stays_inside_the_allowed_folders_is_fine(tmp_path):
    os.symlink(ASSETS_DIR / "themes" / "dark.json", tmp_path / "night.json")
    level_file = tmp_path / "lvl.toml"
    level_file.write_text(SMALL.replace('name = "x"', 'name = "x"\ntheme = "night.json"'))
    assert level_theme(load_level(level_file), level_file) == ASSETS_DIR / "themes/dark.json"


def test_a_shipped_theme_is_named_not_resolved(tmp_path):
    level_file = tmp_path / "lvl.toml"
    level_file.write_text(SMALL.replace('name = "x"', 'name = "x"\ntheme = "light"'))
    assert level_theme(load_level(level_file), level_file) == "light"


@pytest.mark.parametrize(
    ("theme", "message"),
    [
        ("C:/themes/x.json", "not an absolute path"),
        ("a\\\\b.json", "with '/' separators"),
        ("themes/../../x.json", "'..' is not allowed"),
        ("dark.txt", "a shipped theme's name or a .json file"),
    ],
)
def test_theme_paths_that_could_escape_are_refused_even_without_a_file(theme, message):
    (problem,) = _problems(SMALL.replace('name = "x"', f'name = "x"\ntheme = "{theme}"'))
    assert problem.startswith("t.toml:3: level.theme: ") and message in problem


@settings(max_examples=200, deadline=None)
@given(st.text(alphabet=string.printable, max_size=300))
def test_any_text_is_a_level_or_a_level_error(text):
    try:
        parse_level(text, "t.toml")
    except LevelError as exc:
        assert exc.problems and all(str(p).startswith("t.toml") for p in exc.problems)


_VALUES = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(10**20), max_value=10**20),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=5),
    st.lists(st.floats(allow_nan=False, allow_infinity=False, width=32), max_size=3),
)


@settings(max_examples=200, deadline=None)
@given(line=st.integers(min_value=0, max_value=GOOD.count("\n") - 1), value=_VALUES)
def test_replacing_any_value_of_a_good_level_gives_a_level_or_a_level_error(line, value):
    lines = GOOD.splitlines()
    if " = " not in lines[line]:
        return
    key = lines[line].split(" = ")[0]
    lines[line] = f"{key} = {_toml(value)}" if value is not None else ""
    try:
        parse_level("\n".join(lines), "t.toml")
    except LevelError as exc:
        assert all(p.line is None or 1 <= p.line <= len(lines) for p in exc.problems)


def _toml(value: object) -> str:
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return {"nan": "nan", "inf": "inf", "-inf": "-inf"}.get(str(value), repr(value))
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return str(value)


def test_the_solver_names_a_level_may_use_are_the_registered_solvers():
    from ikgame.kinematics import SOLVERS
    from ikgame.level.model import SOLVER_NAMES

    assert sorted(SOLVER_NAMES) == sorted(SOLVERS)


# -- sprite images -------------------------------------------------------------------------------

SKINNED = SMALL.replace("length = 50.0", 'length = 50.0\nsprite = "arm.png"')  # sprite: line 7


def _png(path: Path, size=(40, 10), color=(200, 60, 60, 255)) -> bytes:
    from PIL import Image

    Image.new("RGBA", size, color).save(path, "PNG")
    return path.read_bytes()


def _load_problems(level_file: Path) -> list[str]:
    with pytest.raises(LevelError) as exc:
        load_level(level_file)
    return [str(p).replace(str(level_file), level_file.name) for p in exc.value.problems]


def test_a_sprite_in_the_level_folder_or_in_assets_loads(tmp_path):
    level_file = tmp_path / "lvl.toml"
    _png(tmp_path / "arm.png")
    level_file.write_text(SKINNED)
    assert load_level(level_file).chain.links[0].sprite == "arm.png"
    level_file.write_text(SKINNED.replace("arm.png", "sprites/ball.png"))
    assert load_level(level_file).chain.links[0].sprite_pivot == (0.0, 0.5)


def _damaged(data: bytes) -> bytes:
    at = data.index(b"IDAT") + 6
    return data[:at] + bytes([data[at] ^ 0xFF]) + data[at + 1 :]


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (None, "no file 'arm.png' in the level's folder or assets/"),
        (lambda png: b"GIF89a not a png at all", "'arm.png' is not a PNG image"),
        (lambda png: png[: len(png) // 2], "'arm.png' is cut short (a damaged PNG)"),
        (_damaged, "'arm.png' is damaged (a PNG chunk fails its checksum)"),
    ],
)
def test_a_sprite_that_cannot_be_used_is_reported_at_its_line(tmp_path, content, message):
    level_file = tmp_path / "lvl.toml"
    level_file.write_text(SKINNED)
    png = _png(tmp_path / "arm.png")
    if content is None:
        (tmp_path / "arm.png").unlink()
    else:
        (tmp_path / "arm.png").write_bytes(content(png))
    assert _load_problems(level_file) == [f"lvl.toml:7: chain.links[0].sprite: {message}"]


@pytest.mark.parametrize(
    ("size", "shown"), [((1100, 1000), "1100x1000"), ((2049, 4), "2049x4"), ((0, 0), "0x0")]
)
def test_a_sprite_too_large_in_pixels_is_refused_before_it_is_decoded(tmp_path, size, shown):
    # Only the header is read: forge one, so the test needs no megapixel image.
    import struct
    import zlib

    def chunk(kind: bytes, body: bytes) -> bytes:
        return (
            struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
        )

    header = struct.pack(">IIBBBBB", *size, 8, 6, 0, 0, 0)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", b"") + chunk(b"IEND", b"")
    (tmp_path / "arm.png").write_bytes(data)
    level_file = tmp_path / "lvl.toml"
    level_file.write_text(SKINNED)
    (problem,) = _load_problems(level_file)
    assert problem.startswith(f"lvl.toml:7: chain.links[0].sprite: 'arm.png' is {shown} px")


def test_a_sprite_file_too_large_in_bytes_is_refused(tmp_path):
    from ikgame.level.loader import MAX_SPRITE_BYTES

    (tmp_path / "arm.png").write_bytes(b"\0" * (MAX_SPRITE_BYTES + 1))
    level_file = tmp_path / "lvl.toml"
    level_file.write_text(SKINNED)
    assert _load_problems(level_file) == [
        f"lvl.toml:7: chain.links[0].sprite: 'arm.png' is larger than {MAX_SPRITE_BYTES:,} bytes"
    ]


def test_a_sprite_outside_the_level_folder_and_assets_is_refused(tmp_path):
    inside = tmp_path / "level"
    inside.mkdir()
    _png(tmp_path / "secret.png")
    os.symlink(tmp_path / "secret.png", inside / "arm.png")
    level_file = inside / "lvl.toml"
    level_file.write_text(SKINNED)
    (problem,) = _load_problems(level_file)
    assert problem.startswith("lvl.toml:7: chain.links[0].sprite: 'arm.png' leads outside")
    assert _problems(SKINNED.replace("arm.png", "../secret.png")) == [
        "t.toml:7: chain.links[0].sprite: must stay inside the level's folder or assets/: "
        "'..' is not allowed (got '../secret.png')"
    ]
    assert "not an absolute path" in _problems(SKINNED.replace("arm.png", "/tmp/arm.png"))[0]
    assert "must be a .png file" in _problems(SKINNED.replace("arm.png", "arm.jpg"))[0]


def test_the_sprites_of_a_level_share_a_pixel_budget(tmp_path):
    from ikgame.level.loader import MAX_SPRITE_PIXELS, MAX_SPRITE_TOTAL_PIXELS

    count = MAX_SPRITE_TOTAL_PIXELS // MAX_SPRITE_PIXELS + 1
    links = ""
    for k in range(count):
        _png(tmp_path / f"p{k}.png", size=(1024, 1024), color=(k, 0, 0, 255))
        links += f'[[chain.links]]\nlength = 10.0\nsprite = "p{k}.png"\n'
    level_file = tmp_path / "lvl.toml"
    level_file.write_text(SMALL.replace("[[chain.links]]\nlength = 50.0\n", links))
    (problem,) = _load_problems(level_file)
    assert f"chain.links[{count - 1}].sprite: the level's sprite images hold" in problem
    assert f"at most {MAX_SPRITE_TOTAL_PIXELS:,}" in problem


def test_sprite_pivot_and_scale_need_a_sprite():
    text = SMALL.replace("length = 50.0", "length = 50.0\nsprite_scale = 2.0")
    assert _problems(text) == ["t.toml:7: chain.links[0].sprite_scale: only applies with sprite"]
    prop = '[[props]]\nkind = "ball"\nname = "b"\nposition = [0.0, 0.0]\nradius = 5.0\n'
    text = SMALL + prop + "sprite_pivot = [0.5, 2.0]\n"
    assert _problems(text) == [
        "t.toml:14: props[0].sprite_pivot[1]: Input should be less than or equal to 1 (got 2.0)"
    ]


def test_a_missing_sprite_named_twice_is_reported_at_both_lines(tmp_path):
    level_file = tmp_path / "lvl.toml"
    level_file.write_text(
        SKINNED.replace(
            "[[script]]", '[[chain.links]]\nlength = 20.0\nsprite = "arm.png"\n[[script]]'
        )
    )
    assert [p.split(": ")[0] for p in _load_problems(level_file)] == ["lvl.toml:7", "lvl.toml:10"]
