"""Checks on what an export may write, made before anything is drawn."""

import numpy as np
import pytest

from ikgame.render.output import check_export_size, check_out_dir, parse_size


def test_check_out_dir_refuses_a_non_empty_folder_unless_forced(tmp_path):
    assert check_out_dir(tmp_path / "new", force=False) == tmp_path / "new"
    assert check_out_dir(tmp_path, force=False) == tmp_path
    (tmp_path / "old.png").write_bytes(b"")
    with pytest.raises(ValueError, match="is not empty"):
        check_out_dir(tmp_path, force=False)
    assert check_out_dir(tmp_path, force=True) == tmp_path
    with pytest.raises(ValueError, match="not a folder"):
        check_out_dir(tmp_path / "old.png", force=True)


def test_parse_size_accepts_sizes_in_range():
    assert parse_size("960x540") == (960, 540)
    assert parse_size(" 1080X1920 ") == (1080, 1920)
    assert parse_size("3840x2160") == (3840, 2160)
    assert parse_size("16x16") == (16, 16)


@pytest.mark.parametrize(
    "text, message",
    [
        ("0x0", "out of range"),
        ("-5x3", "out of range"),
        ("15x100", "out of range"),
        ("3841x100", "out of range"),
        ("3840x3840", "out of range"),
        ("abc", "WIDTHxHEIGHT"),
        ("960x", "WIDTHxHEIGHT"),
        ("960x540x3", "WIDTHxHEIGHT"),
        ("9.5x4", "WIDTHxHEIGHT"),
        ("", "WIDTHxHEIGHT"),
    ],
)
def test_parse_size_rejects_bad_sizes(text, message):
    with pytest.raises(ValueError, match=message):
        parse_size(text)


def test_check_export_size_takes_numpy_ints_but_not_bools_or_floats():
    assert check_export_size((np.int64(64), np.int32(48))) == (64, 48)
    for bad in [(True, 48), (64.0, 48), (64,), "64x48"]:
        with pytest.raises(ValueError):
            check_export_size(bad)
