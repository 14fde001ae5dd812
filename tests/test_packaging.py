"""The package as a wheel installs it: levels, themes, sprites and the schema inside, and a run
that finds them without the checkout beside it."""

import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    # Built from a copy: a build writes build/ and egg-info beside the sources it reads.
    source = tmp_path_factory.mktemp("source")
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, source / name)
    for name in ("ikgame", "assets", "levels"):
        shutil.copytree(ROOT / name, source / name, ignore=shutil.ignore_patterns("__pycache__"))
    out = tmp_path_factory.mktemp("wheel")
    built = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", str(source), "-w", str(out)],
        capture_output=True,
        text=True,
    )
    if built.returncode != 0:
        pytest.fail(f"building the wheel failed:\n{built.stdout}\n{built.stderr}")
    return next(out.glob("ikgame-*.whl"))


def test_the_wheel_carries_every_level_and_asset(wheel: Path) -> None:
    names = set(zipfile.ZipFile(wheel).namelist())
    data = [
        f"ikgame/{path.relative_to(ROOT).as_posix()}"
        for folder in ("levels", "assets")
        for path in sorted((ROOT / folder).rglob("*"))
        if path.is_file()
    ]
    # pyproject.toml lists the subpackages by name (the data folders are mapped in beside them).
    code = [path.relative_to(ROOT).as_posix() for path in sorted((ROOT / "ikgame").rglob("*.py"))]
    shipped = data + code
    assert len(data) > 20 and len(code) > 50
    assert [name for name in shipped if name not in names] == []


def test_an_installed_wheel_runs_the_default_level(wheel: Path, tmp_path: Path) -> None:
    site = tmp_path / "site"
    zipfile.ZipFile(wheel).extractall(site)
    # Run from elsewhere, with only the unpacked wheel importable: no checkout to fall back on.
    env = {**os.environ, "PYTHONPATH": str(site)}
    run = subprocess.run(
        [sys.executable, "-m", "ikgame", "run", "--no-frames", "--quiet", "--out", "out"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stderr
    results = json.loads((tmp_path / "out" / "results.json").read_text())
    assert (results["level"], results["status"]) == ("First reach", "passed")
    themes = subprocess.run(
        [sys.executable, "-c", "import ikgame.render.theme as t; print(t.THEMES_DIR)"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
    )
    assert Path(themes.stdout.strip()).is_relative_to(site)
