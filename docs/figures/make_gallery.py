"""Make the README's pictures from shipped levels: ``python docs/figures/make_gallery.py``.

Runs each level through the same path as ``ikgame run`` and keeps the animations of a few and
the contact sheets of others, small enough to commit.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from ikgame.level.library import LEVELS_DIR
from ikgame.level.loader import load_level
from ikgame.render.export import export_run
from ikgame.sim import Simulation
from ikgame.skins import skin_scene

HERE = Path(__file__).resolve().parent
ANIMATED = ("12_push_the_ball", "15_two_hands", "16_walker", "17_head_and_tail")
SHEETS = ("02_tentacle", "07_figure_eight", "10_moving_base", "13_conductor", "14_skinned_arm")
SIZE = (400, 225)  # px: small enough for a README, large enough to read


def _export(name: str, **options: bool) -> Path:
    path = LEVELS_DIR / f"{name}.toml"
    level = load_level(path)
    sim = Simulation(level)
    sim.run()
    out = Path(tempfile.mkdtemp()) / name
    scene = skin_scene(sim.scene, level, path)
    export_run(out, scene, sim.snapshots, size=SIZE, frames=False, motion=False, **options)
    return out


def main() -> None:
    for name in ANIMATED:
        shutil.copyfile(_export(name, gif=True) / "run.gif", HERE / f"{name}.gif")
    for name in SHEETS:
        shutil.copyfile(_export(name, gif=False, sheet=True) / "sheet.png", HERE / f"{name}.png")


if __name__ == "__main__":
    main()
