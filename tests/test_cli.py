"""The command line end to end: exit codes, messages, files written (or not)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from ikgame.cli import main

ROOT = Path(__file__).resolve().parents[1]


def test_version_and_help(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert "ikgame 0.1.0" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    assert "exit codes" in capsys.readouterr().out


def test_run_writes_results_and_exits_zero(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", "--no-frames", "--out", str(out)]) == 0
    data = json.loads((out / "results.json").read_text())
    assert data["level"] == "First reach"
    assert data["status"] == "passed"
    assert all(step["final_error"] <= 6.0 for step in data["steps"])
    assert "passed" in capsys.readouterr().out
    # The trajectory comes without pictures too: tuning motion needs no rendering.
    motion = json.loads((out / "motion.json").read_text())
    assert abs(motion["frames"][-1]["time"] - data["sim_time"]) <= 1.0 / motion["fps"]
    assert not (out / "frames").exists() and not (out / "run.gif").exists()


def test_two_runs_write_byte_identical_results(tmp_path):
    assert main(["run", "--no-frames", "--quiet", "--out", str(tmp_path / "a")]) == 0
    assert main(["run", "--no-frames", "--quiet", "--out", str(tmp_path / "b")]) == 0
    assert (tmp_path / "a/results.json").read_bytes() == (tmp_path / "b/results.json").read_bytes()


def test_bad_level_exits_2_with_file_line_and_field(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(
        '[level]\nname = "x"\nduration = 5\n[chain]\n[[chain.links]]\nlength = -3\n'
        "[[script]]\nreach = [1, 2]\n"
    )
    out = tmp_path / "out"
    assert main(["run", str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert (
        f"{bad}:6: chain.links[0].length: Input should be greater than or equal to 0.1 (got -3)"
        in err
    )
    assert "Traceback" not in err
    assert not out.exists()


def test_missing_level_file_exits_2(tmp_path, capsys):
    assert main(["run", str(tmp_path / "nope.toml")]) == 2
    assert "no such level file" in capsys.readouterr().err


def test_refuses_a_non_empty_out_dir_unless_forced(tmp_path, capsys):
    (tmp_path / "keep.txt").write_text("mine")
    assert main(["run", "--no-frames", "--out", str(tmp_path)]) == 2
    assert "not empty" in capsys.readouterr().err
    assert not (tmp_path / "results.json").exists()
    assert main(["run", "--no-frames", "--quiet", "--force", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "keep.txt").read_text() == "mine"


def test_console_script_runs_as_a_module(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "ikgame", "run", "/nonexistent/level.toml"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr


def _modules_loaded_by(code: str, cwd: Path) -> set[str]:
    """The modules a fresh interpreter has imported after running ``code``."""
    script = f"import sys\n{code}\nprint(' '.join(sorted(sys.modules)))"
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, cwd=cwd, check=True
    )
    return set(proc.stdout.split())


# What each command must not pay for at start-up: drawing, plotting, the comparison, rich.
HEAVY = {"PIL", "ikgame.compare", "ikgame.render.plot", "ikgame.render.export", "rich"}


def test_version_loads_neither_the_simulation_nor_drawing(tmp_path):
    loaded = _modules_loaded_by(
        "from ikgame.cli import main\ntry:\n    main(['--version'])\nexcept SystemExit:\n    pass",
        tmp_path,
    )
    assert "ikgame.cli" in loaded
    assert not loaded & (HEAVY | {"numpy", "pydantic", "pymunk", "ikgame.sim"})


def test_run_without_frames_loads_no_drawing(tmp_path):
    out = tmp_path / "run"
    code = f"from ikgame.cli import main\nassert main(['run', '--no-frames', '--out', {str(out)!r}]) == 0"
    loaded = _modules_loaded_by(code, tmp_path)
    assert (out / "results.json").exists()
    assert "ikgame.sim" in loaded
    assert not loaded & (HEAVY - {"rich"})


def test_a_quiet_run_loads_no_rich_either(tmp_path):
    # A quiet run prints nothing: importing rich would cost it more than a short level runs.
    out = tmp_path / "run"
    code = f"from ikgame.cli import main\nassert main(['run', '--no-frames', '--quiet', '--out', {str(out)!r}]) == 0"
    loaded = _modules_loaded_by(code, tmp_path)
    assert (out / "results.json").exists() and (out / "motion.json").exists()
    assert "ikgame.sim" in loaded
    assert not loaded & HEAVY


def test_run_writes_frames_gif_and_motion_that_show_the_chain_moving(tmp_path):
    from PIL import Image, ImageChops

    out = tmp_path / "run"
    assert main(["run", "--quiet", "--size", "160x90", "--workers", "1", "--out", str(out)]) == 0
    frames = sorted((out / "frames").glob("*.png"))
    results = json.loads((out / "results.json").read_text())
    options = results["options"]
    # One frame at each t = k / fps before the run's end: ceil(ticks x fps / tick_rate).
    assert len(frames) == -(-results["ticks"] * options["fps"] // options["tick_rate"])
    assert frames[0].name == "000000.png"
    first, last = Image.open(frames[0]), Image.open(frames[-1])
    assert first.size == (160, 90)
    assert len(first.convert("RGB").getcolors(10_000)) > 2  # not blank
    assert ImageChops.difference(first.convert("RGB"), last.convert("RGB")).getbbox() is not None
    gif = Image.open(out / "run.gif")
    assert gif.is_animated and gif.n_frames > 1
    motion = json.loads((out / "motion.json").read_text())
    assert len(motion["frames"]) == len(frames)


def test_two_runs_give_byte_identical_frames(tmp_path):
    for name in ("a", "b"):
        args = ["run", "--quiet", "--no-gif", "--size", "96x54", "--out", str(tmp_path / name)]
        assert main(args) == 0
    a = sorted((tmp_path / "a/frames").iterdir())
    b = sorted((tmp_path / "b/frames").iterdir())
    assert [p.name for p in a] == [p.name for p in b]
    assert all(x.read_bytes() == y.read_bytes() for x, y in zip(a, b, strict=True))


def _first_frame_only(level_text: str) -> str:
    """A shipped level's text cut to its first frame (five ticks at 240 Hz, one frame at 30 fps):
    all a test of how that frame is drawn or stored needs to run."""
    assert "duration = 20.0\n" in level_text
    return level_text.replace("duration = 20.0\n", "duration = 0.02\n", 1)


def test_png_compression_reaches_the_frames_and_is_checked(tmp_path, capsys):
    level = tmp_path / "short.toml"
    level.write_text(_first_frame_only((ROOT / "levels" / "01_first_reach.toml").read_text()))
    out = tmp_path / "run"
    args = ["run", str(level), "--quiet", "--size", "160x90", "--no-gif", "--workers", "1"]
    args += ["--out", str(out)]
    assert main([*args, "--png-compression", "0"]) == 0
    # Level 0 stores the pixels uncompressed: a filter byte per row plus 3 bytes per pixel.
    assert (out / "frames/000000.png").stat().st_size > 90 * (1 + 160 * 3)
    with pytest.raises(SystemExit) as exc:
        main([*args, "--force", "--png-compression", "10"])
    assert exc.value.code == 2
    assert "--png-compression" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("option", "message"),
    [
        (["--size", "0x0"], "--size: size 0x0 is out of range"),
        (["--size", "big"], "--size: size must be WIDTHxHEIGHT"),
        (["--theme", "neon"], "--theme: unknown theme 'neon'; available: dark, light"),
        (["--workers", "0"], "--workers: must be at least 1"),
    ],
)
def test_bad_options_exit_2_and_write_nothing(tmp_path, capsys, option, message):
    out = tmp_path / "out"
    assert main(["run", "--out", str(out), *option]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_validate_lists_every_problem_and_exits_2(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('[level]\nname = "x"\nduration = -1\n[chain]\n[[chain.links]]\nlength = 0\n')
    assert main(["validate", str(ROOT / "levels"), str(bad)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert (
        f"error: {bad}:3: level.duration: Input should be greater than or equal to 0.001 (got -1)"
        in err
    )
    assert (
        f"error: {bad}:6: chain.links[0].length: Input should be greater than or equal to 0.1 (got 0)"
        in err
    )
    assert f"error: {bad}: script: Field required" in err


def test_validate_shipped_levels_exits_0(capsys):
    assert main(["validate", str(ROOT / "levels")]) == 0
    count = len(list((ROOT / "levels").glob("*.toml")))
    assert f"{count} level files valid" in capsys.readouterr().out


def test_list_shows_every_shipped_level(capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    for path in (ROOT / "levels").glob("*.toml"):
        assert path.stem in out


def test_schema_matches_the_shipped_copy(tmp_path):
    out = tmp_path / "schema.json"
    assert main(["schema", "--out", str(out)]) == 0
    assert out.read_bytes() == (ROOT / "assets" / "level.schema.json").read_bytes()


def test_compare_writes_json_and_png_and_rejects_unknown_solvers(tmp_path, capsys):
    out = tmp_path / "cmp"
    assert main(["compare", "03_elbow_limits", "--solvers", "ccd,dls", "--out", str(out)]) == 0
    data = json.loads((out / "compare.json").read_text())
    assert list(data["solvers"]) == ["ccd", "dls"]
    assert (out / "compare.png").stat().st_size > 0
    assert main(["compare", "--solvers", "ccd,magic", "--out", str(tmp_path / "x")]) == 2
    assert "unknown solver 'magic'" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_level_text_is_printed_as_text_not_console_markup(tmp_path, capsys):
    level = tmp_path / "odd.toml"
    level.write_text(
        '[level]\nname = "[/] [bold]odd"\nduration = 1.0\n[chain]\n[[chain.links]]\n'
        "length = 50.0\n[[script]]\nwait = 0.5\n"
    )
    assert main(["run", str(level), "--no-frames", "--out", str(tmp_path / "out")]) == 0
    assert "[/] [bold]odd (ccd): passed" in capsys.readouterr().out


def test_run_uses_the_level_theme_unless_told_otherwise(tmp_path):
    from PIL import Image

    level = tmp_path / "dark.toml"
    # Cut to its first frame, the one looked at.
    text = _first_frame_only((ROOT / "levels" / "01_first_reach.toml").read_text())
    level.write_text(text.replace("[level]\n", '[level]\ntheme = "dark"\n', 1))
    corners = {}
    for name, extra in (("own", []), ("light", ["--theme", "light"])):
        out = tmp_path / name
        args = ["run", str(level), "--quiet", "--no-gif", "--size", "64x36", "--out", str(out)]
        assert main(args + extra) == 0
        corners[name] = Image.open(out / "frames" / "000000.png").convert("L").getpixel((0, 0))
    assert corners["own"] < 100 < corners["light"]


_INVALID = sorted((ROOT / "tests" / "data" / "levels" / "invalid").glob("*.toml"))


@pytest.mark.parametrize("level", _INVALID, ids=[p.stem for p in _INVALID])
def test_every_broken_level_exits_2_names_its_field_and_writes_nothing(tmp_path, capsys, level):
    out = tmp_path / "out"
    assert main(["run", str(level), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    for line in level.with_suffix(".txt").read_text(encoding="utf-8").splitlines():
        assert f"error: {line.replace(level.name, str(level), 1)}" in err
    assert "Traceback" not in err
    assert not out.exists()


_SHIPPED = sorted((ROOT / "levels").glob("*.toml"))


@pytest.mark.parametrize("level", _SHIPPED, ids=[p.stem for p in _SHIPPED])
def test_compare_runs_every_solver_on_every_shipped_level(tmp_path, level):
    out = tmp_path / "cmp"
    assert main(["compare", str(level), "--quiet", "--out", str(out)]) == 0
    data = json.loads((out / "compare.json").read_text())
    assert list(data["solvers"]) == ["ccd", "jacobian_transpose", "dls", "fabrik"]


_THEMES = {
    "bad_json": b'{"background": ',
    "bad_colour": None,  # a complete theme with one colour broken, built below
    "missing_key": b'{"background": "#000000"}',
    "a_list": b"[1, 2, 3]",
    "latin1": '{"name": "caf\u00e9"'.encode("latin-1"),
    "deep": b"[" * 100_000 + b"]" * 100_000,
}


@pytest.mark.parametrize("case", sorted(_THEMES))
def test_a_broken_theme_file_is_reported_by_validate_and_run_with_its_line(tmp_path, capsys, case):
    from ikgame.render.theme import Theme, fields

    data = _THEMES[case]
    if data is None:
        colours = {f.name: "#000000" for f in fields(Theme)} | {"link": "#12345"}
        data = json.dumps(colours, indent=1).encode()
    (tmp_path / "mine.json").write_bytes(data)
    level = tmp_path / "level.toml"
    text = (ROOT / "levels" / "01_first_reach.toml").read_text()
    level.write_text(text.replace("[level]\n", '[level]\ntheme = "mine.json"\n', 1))
    assert main(["validate", str(level)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {tmp_path / 'mine.json'}") and "the theme of" in err, err
    if case == "bad_colour":
        assert f"mine.json:{list(colours).index('link') + 2}: link: expected" in err
    out = tmp_path / "out"
    assert main(["run", str(level), "--out", str(out)]) == 2
    assert capsys.readouterr().err.startswith(f"error: {tmp_path / 'mine.json'}")
    assert main(["run", "--theme", str(tmp_path / "mine.json"), "--out", str(out)]) == 2
    assert capsys.readouterr().err.startswith(f"error: --theme: {tmp_path / 'mine.json'}")
    assert not out.exists()


def test_schema_out_a_folder_or_an_unwritable_path_exits_2(tmp_path, capsys):
    assert main(["schema", "--out", str(tmp_path)]) == 2
    assert "is a folder" in capsys.readouterr().err
    (tmp_path / "file").write_text("x")
    assert main(["schema", "--out", str(tmp_path / "file" / "schema.json")]) == 2
    assert "cannot write" in capsys.readouterr().err


def test_an_expensive_level_is_refused_by_the_budget_before_it_runs(tmp_path, capsys):
    level = tmp_path / "huge.toml"
    level.write_text(
        '[level]\nname = "huge"\nduration = 600.0\n[world]\ntick_rate = 500\nfps = 30\n'
        "[chain]\niterations = 1000\n[[chain.links]]\nlength = 10.0\nrepeat = 200\n"
        "[[script]]\nwait = 600.0\n"
    )
    out = tmp_path / "out"
    assert main(["run", str(level), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "this run is estimated at about" in err and "300000 ticks" in err
    assert "--budget" in err and "--no-budget" in err
    assert not out.exists()
    assert main(["run", str(level), "--no-frames", "--budget", "0.001", "--out", str(out)]) == 2
    assert main(["run", "--no-frames", "--quiet", "--budget", "5", "--out", str(out)]) == 0


def test_an_output_folder_that_cannot_be_written_is_refused_before_simulating(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    (tmp_path / "dangling").symlink_to(tmp_path / "nowhere")
    gif_folder = tmp_path / "gif"
    (gif_folder / "run.gif").mkdir(parents=True)
    frames_link = tmp_path / "linked"
    frames_link.mkdir()
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / "elsewhere" / "000000.png").write_bytes(b"not ours")
    (frames_link / "frames").symlink_to(tmp_path / "elsewhere")
    cases = {
        tmp_path / "file" / "out": "cannot create",
        tmp_path / "dangling": "a symlink to nothing",
        gif_folder: "run.gif is not what ikgame writes there",
        frames_link: "frames is a symlink",
    }
    for out, message in cases.items():
        assert main(["run", "--no-frames", "--force", "--out", str(out)]) == 2
        assert message in capsys.readouterr().err
    assert not (tmp_path / "nowhere").exists()
    assert (tmp_path / "elsewhere" / "000000.png").read_bytes() == b"not ours"
    assert not (gif_folder / "results.json").exists()


def test_force_clears_the_earlier_run_first_and_keeps_other_files(tmp_path):
    out = tmp_path / "out"
    args = ["run", "--quiet", "--size", "32x18", "--out", str(out)]
    assert main(args) == 0
    assert (out / "run.gif").exists() and (out / "frames" / "000000.png").exists()
    (out / "notes.txt").write_text("mine")
    (out / ".run.gif.0123456789ab.tmp").write_bytes(b"left by a killed run")
    assert main([*args, "--force", "--no-frames"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["motion.json", "notes.txt", "results.json"]


def test_check_reproduces_a_run_and_reports_a_difference(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", "--quiet", "--size", "32x18", "--no-gif", "--out", str(out)]) == 0
    data = json.loads((out / "results.json").read_text())
    assert set(data["provenance"]["versions"]) == {"ikgame", "python", "pymunk", "numpy", "pillow"}
    assert data["outputs"]["frames"]["count"] == len(list((out / "frames").glob("*.png")))
    assert main(["check", str(out / "results.json")]) == 0
    assert "reproduces exactly (passed" in capsys.readouterr().out
    data["steps"][0]["final_error"] += 1.0
    (out / "results.json").write_text(json.dumps(data))
    assert main(["check", str(out / "results.json")]) == 3
    assert "steps[0].final_error" in capsys.readouterr().out
    (out / "results.json").write_text("{}")
    assert main(["check", str(out / "results.json")]) == 2


def test_a_full_disk_during_the_export_exits_2_and_says_so(tmp_path, capsys, monkeypatch):
    import errno

    import ikgame.render.export

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", str(tmp_path / "out" / "run.gif"))

    monkeypatch.setattr(ikgame.render.export, "export_run", full)
    assert main(["run", "--quiet", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "cannot write" in err and "run.gif: No space left on device" in err
    assert not (tmp_path / "out" / "results.json").exists()


# -- sprites and MP4 -----------------------------------------------------------------------------


def test_run_mp4_of_the_hero_level_is_h264_with_every_frame(tmp_path, probe_video):
    out = tmp_path / "run"
    args = ["run", "12_push_the_ball", "--quiet", "--mp4", "--no-gif", "--size", "321x181"]
    assert main([*args, "--out", str(out)]) == 0
    frames = len(list((out / "frames").glob("*.png")))
    assert frames > 100
    # An odd side loses its last pixel: H.264 in yuv420p needs even sides.
    assert probe_video(out / "run.mp4") == {
        "codec": "h264",
        "pix_fmt": "yuv420p",
        "size": (320, 180),
        "fps": 30.0,
        "frames": frames,
    }
    assert sorted(p.name for p in out.iterdir()) == [
        "frames",
        "motion.json",
        "results.json",
        "run.mp4",
    ]


def test_mp4_without_the_video_extra_exits_2_with_the_install_command_before_running(
    tmp_path, capsys, monkeypatch
):
    import importlib.util

    from ikgame.render import video
    from ikgame.sim import Simulation

    real = importlib.util.find_spec
    monkeypatch.setattr(
        video.importlib.util,
        "find_spec",
        lambda name, *a: None if name == "imageio_ffmpeg" else real(name, *a),
    )
    monkeypatch.setattr(Simulation, "run", lambda *a, **k: pytest.fail("simulated anyway"))
    out = tmp_path / "out"
    assert main(["run", "--mp4", "--out", str(out)]) == 2
    assert (
        "--mp4: MP4 export needs the video extra (imageio-ffmpeg): python -m pip install "
        "'ikgame[video]'" in capsys.readouterr().err
    )
    assert not out.exists()
    assert main(["run", "--mp4", "--no-frames", "--out", str(out)]) == 2
    assert "--mp4: there are no pictures to encode with --no-frames" in capsys.readouterr().err


def test_a_missing_sprite_exits_2_naming_its_line_in_run_and_validate(tmp_path, capsys):
    level = tmp_path / "skinned.toml"
    level.write_text(
        (ROOT / "levels" / "14_skinned_arm.toml")
        .read_text()
        .replace("sprites/forearm.png", "sprites/nope.png")
    )
    out = tmp_path / "out"
    assert main(["run", str(level), "--out", str(out)]) == 2
    line = level.read_text().splitlines().index('sprite = "sprites/nope.png"') + 1
    expected = f"{level}:{line}: chain.links[1].sprite: no file 'sprites/nope.png' in the level's"
    assert expected in capsys.readouterr().err
    assert not out.exists()
    assert main(["validate", str(level)]) == 2
    assert expected in capsys.readouterr().err


def test_a_skinned_level_gives_the_same_frames_serial_and_in_workers(tmp_path):
    # Its first 4 s (120 frames, enough for every worker to draw several): the sprites of every
    # link and prop are in each frame from the first.
    level = tmp_path / "skinned.toml"
    text = (ROOT / "levels" / "14_skinned_arm.toml").read_text()
    assert "duration = 12.0\n" in text
    level.write_text(text.replace("duration = 12.0\n", "duration = 4.0\n", 1))
    for name, workers in (("a", "1"), ("b", "2")):
        args = ["run", str(level), "--quiet", "--no-gif", "--size", "96x54"]
        assert main([*args, "--workers", workers, "--out", str(tmp_path / name)]) == 0
    a = sorted((tmp_path / "a/frames").iterdir())
    b = sorted((tmp_path / "b/frames").iterdir())
    assert len(a) == len(b) > 100
    assert all(x.read_bytes() == y.read_bytes() for x, y in zip(a, b, strict=True))


def test_a_creature_run_reports_its_footing(tmp_path, capsys):
    level = ROOT / "levels" / "16_walker.toml"
    text = level.read_text().replace("duration = 18.0", "duration = 3.0")
    short = tmp_path / "walker.toml"
    short.write_text(text.replace("over = 14.0", "over = 2.0"))
    out = tmp_path / "run"
    assert main(["run", str(short), "--no-frames", "--out", str(out)]) in (0, 1)
    footing = json.loads((out / "results.json").read_text())["footing"]
    assert set(footing) == {"foot_1", "foot_2", "foot_3", "foot_4"}
    assert all(leg["steps"] >= 1 for leg in footing.values())
    assert "footing:" in capsys.readouterr().out


def _short_walker(folder: Path) -> Path:
    """The shipped walker, carried 120 px in 1.5 s instead of 1000 px in 14 s: every foot still
    plants, lifts and lands."""
    text = (ROOT / "levels" / "16_walker.toml").read_text(encoding="utf-8")
    for old, new in (
        ("duration = 18.0", "duration = 2.5"),
        ("wait = 1.0", "wait = 0.2"),
        (
            "set = { base = [1000.0, 130.0], over = 14.0 }",
            "set = { base = [120.0, 130.0], over = 1.5 }",
        ),
        ("wait = 15.0", "wait = 2.0"),
    ):
        assert old in text, old
        text = text.replace(old, new, 1)
    path = folder / "walker.toml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("level", ["15_two_hands", "walker"])
def test_a_tree_run_twice_writes_byte_identical_results_motion_and_frames(tmp_path, level):
    path = _short_walker(tmp_path) if level == "walker" else ROOT / "levels" / f"{level}.toml"
    args = ["run", str(path), "--quiet", "--size", "160x90", "--workers", "1"]
    for name in ("a", "b"):
        assert main([*args, "--out", str(tmp_path / name)]) == 0
    a = sorted(p.relative_to(tmp_path / "a") for p in (tmp_path / "a").rglob("*") if p.is_file())
    b = sorted(p.relative_to(tmp_path / "b") for p in (tmp_path / "b").rglob("*") if p.is_file())
    assert a == b and {"results.json", "motion.json", "run.gif"} <= {str(p) for p in a}
    assert sum(p.parts[0] == "frames" for p in a) > 50
    for relative in a:
        assert (tmp_path / "a" / relative).read_bytes() == (tmp_path / "b" / relative).read_bytes()
    results = json.loads((tmp_path / "a" / "results.json").read_text())
    if level == "walker":
        assert all(leg["steps"] > 0 for leg in results["footing"].values()), results["footing"]
    else:
        assert results["status"] == "passed"


_TWO_HANDS_WAITING = """[level]
name = "Wait first"
duration = 0.5

[chain]
angle = 90.0

[[chain.bones]]
name = "torso"
length = 60.0

[[chain.bones]]
name = "left"
parent = "torso"
angle = 60.0
length = 40.0

[[chain.bones]]
name = "right"
parent = "torso"
angle = -60.0
length = 40.0

[[script]]
wait = 0.2

[[script]]
reach = { left = [-50.0, 80.0], right = [50.0, 80.0] }
"""


def test_a_tree_whose_script_starts_with_a_wait_draws_its_frames(tmp_path, capsys):
    level = tmp_path / "wait_first.toml"
    level.write_text(_TWO_HANDS_WAITING, encoding="utf-8")
    args = ["run", str(level), "--quiet", "--no-gif", "--size", "64x36", "--workers", "1"]
    assert main([*args, "--out", str(tmp_path / "out")]) == 0, capsys.readouterr().err


def test_a_vanishingly_small_sprite_is_refused_at_its_line(tmp_path, capsys):
    level = tmp_path / "tiny_sprite.toml"
    level.write_text(
        '[level]\nname = "Tiny sprite"\nduration = 0.2\n'
        "[world]\nbounds = [-300.0, -200.0, 300.0, 200.0]\n"
        '[chain]\n[[chain.links]]\nlength = 60.0\nsprite = "sprites/ball.png"\n'
        "sprite_scale = 5e-324\n[[script]]\nwait = 0.1\n",
        encoding="utf-8",
    )
    args = ["run", str(level), "--quiet", "--no-gif", "--size", "97x53", "--workers", "1"]
    assert main([*args, "--out", str(tmp_path / "out")]) == 2
    assert "tiny_sprite.toml:10: chain.links[0].sprite_scale" in capsys.readouterr().err


_STILL_JOINT = """[level]
name = "A joint that cannot turn"
duration = 3.0

[world]
gravity = [0.0, 0.0]

[chain]
angle = 0.0

[[chain.bones]]
name = "still"
at = [-20.0, 0.0]
angle = 90.0
length = 50.0
max_speed = 5e-324

[[chain.bones]]
name = "arm"
at = [20.0, 0.0]
angle = 90.0
length = 50.0

[[script]]
follow = "line"
effector = "arm"
from = [20.0, 50.0]
to = [60.0, 30.0]
duration = 0.8
"""


def test_a_joint_whose_speed_limit_rounds_to_zero_does_not_abort_the_run(tmp_path):
    # In a child process: the abort would take the test run down with it.
    level = tmp_path / "still.toml"
    level.write_text(_STILL_JOINT, encoding="utf-8")
    proc = subprocess.run(
        [sys.executable, "-m", "ikgame", "run", str(level), "--no-frames", "--quiet"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert proc.returncode in (0, 2), proc.stderr
    assert "Traceback" not in proc.stderr
