"""Themes: the shipped palettes load, and a broken theme file says what is wrong."""

from __future__ import annotations

import json
from dataclasses import fields

import pytest

from ikgame.render.theme import Theme, available_themes, load_theme


def test_shipped_themes_load_and_differ():
    assert available_themes() == ["dark", "light"]
    light, dark = load_theme("light"), load_theme("dark")
    assert light.background != dark.background
    for theme in (light, dark):
        assert all(len(c) == 3 and all(0 <= v <= 255 for v in c) for c in theme.colors())


def test_unknown_theme_names_the_available_ones():
    with pytest.raises(ValueError, match=r"^unknown theme 'x'; available: dark, light$"):
        load_theme("x")


def _write(tmp_path, data) -> str:
    path = tmp_path / "mine.json"
    path.write_text(json.dumps(data))
    return str(path)


def test_theme_file_by_path_accepts_hex_and_lists(tmp_path):
    data = {f.name: "#102030" for f in fields(Theme)}
    data["link"] = [1, 2, 3]
    theme = load_theme(_write(tmp_path, data))
    assert theme.background == (16, 32, 48)
    assert theme.link == (1, 2, 3)


@pytest.mark.parametrize(
    "change, message",
    [
        ({"extra": "#000000"}, "unknown keys"),
        ({"link": "#12345"}, "link: expected"),
        ({"link": [0, 0, 256]}, "link: expected"),
        ({"link": "#gggggg"}, "link: expected"),
    ],
)
def test_bad_theme_files_raise(tmp_path, change, message):
    data = {f.name: "#000000" for f in fields(Theme)} | change
    with pytest.raises(ValueError, match=message):
        load_theme(_write(tmp_path, data))


def test_missing_colours_and_files_raise(tmp_path):
    data = {f.name: "#000000" for f in fields(Theme)}
    del data["grid"]
    with pytest.raises(ValueError, match=r"missing colours \['grid'\]"):
        load_theme(_write(tmp_path, data))
    with pytest.raises(ValueError, match="not found"):
        load_theme(tmp_path / "absent.json")
    (tmp_path / "broken.json").write_text("{")
    with pytest.raises(ValueError, match="cannot read JSON"):
        load_theme(tmp_path / "broken.json")
