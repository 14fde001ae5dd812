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
