"""Themes: the shipped palettes load, and a broken theme file says what is wrong."""

from __future__ import annotations

import json
from dataclasses import fields

import pytest

from ikgame.render.theme import EFFECTOR_PALETTE, Theme, available_themes, load_theme

COLOURS = [f.name for f in fields(Theme) if f.name != "effector_palette"]


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
    data = {name: "#102030" for name in COLOURS}
    data["link"] = [1, 2, 3]
    theme = load_theme(_write(tmp_path, data))
    assert theme.background == (16, 32, 48)
    assert theme.link == (1, 2, 3)
    assert theme.effector_palette == EFFECTOR_PALETTE  # optional in a theme file
    data["effector_palette"] = ["#ff0000", [0, 0, 255]]
    assert load_theme(_write(tmp_path, data)).effector_palette == ((255, 0, 0), (0, 0, 255))


@pytest.mark.parametrize("palette", [[], "#ff0000", ["#ff0000", "red"], [[0, 0, 999]]])
def test_a_bad_effector_palette_names_the_field(tmp_path, palette):
    data = {name: "#000000" for name in COLOURS} | {"effector_palette": palette}
    with pytest.raises(ValueError, match="effector_palette: expected"):
        load_theme(_write(tmp_path, data))


def test_one_effector_keeps_the_theme_colours_and_several_take_the_palette():
    for theme in (load_theme("light"), load_theme("dark")):
        (lone,) = theme.effector_styles(1)
        assert (lone.target, lone.trail, lone.tip, lone.upcoming) == (
            theme.target,
            theme.trail,
            theme.effector,
            theme.target_upcoming,
        )
        palette = theme.effector_palette
        styles = theme.effector_styles(len(palette) + 1)
        assert [s.target for s in styles] == [*palette, palette[0]]  # round again past the end
        assert all(s.trail == s.tip == s.target for s in styles)
        # Distinct colours, none of them the links' (the effector colours mark the tips).
        assert len(set(palette)) == len(palette) and theme.link not in palette
        assert all(s.upcoming not in (s.target, theme.background) for s in styles)


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
    data = {name: "#000000" for name in COLOURS} | change
    with pytest.raises(ValueError, match=message):
        load_theme(_write(tmp_path, data))


def test_missing_colours_and_files_raise(tmp_path):
    data = {name: "#000000" for name in COLOURS}
    del data["grid"]
    with pytest.raises(ValueError, match=r"missing colours \['grid'\]"):
        load_theme(_write(tmp_path, data))
    with pytest.raises(ValueError, match="not found"):
        load_theme(tmp_path / "absent.json")
    (tmp_path / "broken.json").write_text("{")
    with pytest.raises(ValueError, match="cannot read JSON"):
        load_theme(tmp_path / "broken.json")
