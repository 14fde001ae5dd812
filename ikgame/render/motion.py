"""The baked motion of a run, ``motion.json``: keyframes a game engine can import.

Apart from :mod:`ikgame.render.export` because a run without pictures writes it too, and should
not load Pillow for that. The file is streamed a keyframe at a time, so a long run's keyframes
are never all in memory as JSON.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import IO, Any

import numpy as np

from ikgame._files import atomic_open
from ikgame.snapshot import Scene, Snapshot, effector_positions, link_segments

__all__ = ["check_run", "motion_json", "write_motion"]


def check_run(scene: Scene, snapshots: Sequence[Snapshot]) -> None:
    """``ValueError`` unless ``snapshots`` is a run to export: one frame at least, at a
    positive frame rate."""
    if not snapshots:
        raise ValueError("no snapshots to export")
    if not (math.isfinite(scene.fps) and scene.fps > 0):
        raise ValueError(f"scene.fps must be a positive number, got {scene.fps!r}")


def motion_json(scene: Scene, snapshots: Sequence[Snapshot]) -> dict[str, Any]:
    """The run as keyframes a game engine can import: one entry per recorded frame.

    Each frame has every joint's local angle (radians and degrees), every link's world angle,
    the world positions of the joints (base first, end effector last), the target and the
    solver's status. Positions are world px with y up; NaN errors become null.

    A tree's header also has ``parents`` (each link's parent, -1 for a root), ``effector_links``
    and ``effector_names``; its ``joints`` are the link starts, then the link ends; and in place
    of ``target`` each frame has ``effectors`` (each effector's position), ``targets`` (its
    target, or null) and ``errors`` (px, or null), one entry per effector, while ``error`` is
    the largest.

    >>> scene = Scene("demo", np.zeros((0, 5)), np.zeros((0, 3)), np.full(1, 8.0), 100.0)
    >>> snap = Snapshot(0.0, 0, np.array([[0.0, 0.0], [0.0, 100.0]]), np.array([1.5708]),
    ...                 np.array([1.5708]))
    >>> motion = motion_json(scene, [snap])
    >>> motion["link_lengths"], motion["frames"][0]["angles_deg"]
    ([100.0], [90.0002])
    """
    return _motion_header(scene, snapshots) | {
        "frames": [_motion_frame(scene, s) for s in snapshots]
    }


def _motion_header(scene: Scene, snapshots: Sequence[Snapshot]) -> dict[str, Any]:
    """Everything in :func:`motion_json` but the frames."""
    check_run(scene, snapshots)
    starts, ends = link_segments(scene, snapshots[0])
    lengths = np.linalg.norm(ends - starts, axis=1)
    joints = "world positions: the base, each following joint, then the end effector"
    if scene.is_tree:
        joints = "world positions: where each link starts, then where each link ends"
    header = {
        "format": "ikgame-motion",
        "version": 1,
        "level": scene.level_name,
        "fps": float(scene.fps),
        "frame_count": len(snapshots),
        "duration": _round(len(snapshots) / scene.fps, 6),
        "units": {"length": "px", "angle": "rad, and deg in *_deg", "time": "s", "y_axis": "up"},
        "conventions": {
            "angles": "local joint angle of each link relative to its parent link, counter-clockwise",
            "world_angles": "each link's direction relative to +x, counter-clockwise",
            "joints": joints,
        },
        "link_count": len(lengths),
        "link_lengths": [_round(v, 3) for v in lengths],
        "link_widths": [_round(v, 3) for v in np.asarray(scene.link_widths, dtype=float)],
    }
    if scene.is_tree:
        header |= {
            "parents": [int(p) for p in scene.parents],
            "effector_links": [int(i) for i in scene.effector_links],
            "effector_names": list(scene.effector_names),
        }
    return header


def _motion_frame(scene: Scene, snap: Snapshot) -> dict[str, Any]:
    # Read as lists of floats: the same values, without a numpy scalar made for each number.
    angles = np.asarray(snap.angles, dtype=float)
    error = float(snap.error)
    frame = {
        "time": _round(snap.time, 6),
        "tick": int(snap.tick),
        "step_index": int(snap.step_index),
        "angles_rad": [_round(a, 6) for a in angles.tolist()],
        "angles_deg": [_round(a, 4) for a in np.degrees(angles).tolist()],
        "world_angles_rad": [
            _round(a, 6) for a in np.asarray(snap.world_angles, dtype=float).tolist()
        ],
        "joints": [
            [_round(x, 3), _round(y, 3)] for x, y in np.asarray(snap.joints, dtype=float).tolist()
        ],
        "target": None if snap.target is None else [_round(v, 3) for v in snap.target],
        "error": _length(error),
        "solver_status": str(snap.solver_status),
        "torque_limited": np.asarray(snap.torque_limited, dtype=bool).tolist(),
    }
    if scene.is_tree:
        del frame["target"]
        frame |= {
            "effectors": _points(effector_positions(scene, snap)),
            "targets": _points(snap.target_points),
            "errors": [_length(e) for e in snap.effector_errors],
        }
    return frame


def _points(points: np.ndarray) -> list[list[float] | None]:
    """``[x, y]`` per row, rounded; null for a row that is not finite."""
    return [
        [_round(x, 3), _round(y, 3)] if math.isfinite(x) and math.isfinite(y) else None
        for x, y in np.asarray(points, dtype=float)
    ]


def _length(value: float) -> float | None:
    """A distance, px, rounded; null when not finite."""
    return _round(value, 3) if math.isfinite(value) else None


def _round(value: float, digits: int) -> float:
    # +0.0 turns -0.0 into 0.0, which would otherwise print as "-0.0" in the keyframes.
    return round(float(value), digits) + 0.0


def _write_motion(fp: IO[bytes], scene: Scene, snapshots: Sequence[Snapshot]) -> None:
    """Write :func:`motion_json` as JSON: an indented header, then one line per frame so runs
    diff well. Streamed a frame at a time: a long run's keyframes are never all in memory."""
    head = json.dumps(_motion_header(scene, snapshots), indent=2, allow_nan=False)
    fp.write(f'{head[:-2]},\n  "frames": [\n    '.encode())
    for index, snap in enumerate(snapshots):
        separator = ",\n    " if index else ""
        fp.write((separator + json.dumps(_motion_frame(scene, snap), allow_nan=False)).encode())
    fp.write(b"\n  ]\n}\n")


def write_motion(
    out_dir: str | os.PathLike[str], scene: Scene, snapshots: Sequence[Snapshot]
) -> Path:
    """Write ``motion.json`` (see :func:`motion_json`) into ``out_dir`` and return its path.

    >>> import tempfile
    >>> scene = Scene("demo", np.zeros((0, 5)), np.zeros((0, 3)), np.full(1, 8.0), 100.0)
    >>> snap = Snapshot(0.0, 0, np.array([[0.0, 0.0], [0.0, 100.0]]), np.zeros(1), np.zeros(1))
    >>> with tempfile.TemporaryDirectory() as out:
    ...     write_motion(out, scene, [snap]).name
    'motion.json'
    """
    snapshots = tuple(snapshots)
    check_run(scene, snapshots)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "motion.json"
    with atomic_open(path) as fp:
        _write_motion(fp, scene, snapshots)
    return path
