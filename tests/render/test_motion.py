"""motion.json for trees: every effector's position, target and error, and the tree's shape in
the header. (A chain's motion.json is covered with the exports in test_export.py.)"""

from __future__ import annotations

import json

import numpy as np
import pytest

from ikgame.render.motion import motion_json, write_motion


def test_a_trees_header_has_its_parents_and_effector_names(tree_run):
    scene, snaps = tree_run(3)
    header = {k: v for k, v in motion_json(scene, snaps).items() if k != "frames"}
    assert header["parents"] == [-1, 0, 1, 0, 3]
    assert header["effector_names"] == ["left", "right"]
    assert header["effector_links"] == [2, 4]
    assert header["link_count"] == 5
    assert header["link_lengths"] == pytest.approx([40.0] * 5)
    assert "link starts" in header["conventions"]["joints"]


def test_each_tree_frame_has_every_effectors_position_target_and_error(tree_run):
    scene, snaps = tree_run(3)
    frames = motion_json(scene, snaps)["frames"]
    first, last = frames[0], frames[-1]
    assert "target" not in first
    tips = snaps[-1].joints[5:][[2, 4]]
    np.testing.assert_allclose(last["effectors"], tips, atol=1e-3)
    np.testing.assert_allclose(last["targets"], snaps[-1].targets, atol=1e-3)
    np.testing.assert_allclose(last["errors"], snaps[-1].errors, atol=1e-3)
    assert last["error"] == pytest.approx(max(snaps[-1].errors), abs=1e-3)
    # The right arm has no target in the first frame: null, not NaN.
    assert first["targets"][0] == pytest.approx(snaps[0].targets[0].tolist())
    assert first["targets"][1] is None and first["errors"][1] is None
    assert len(first["joints"]) == 10


def test_a_trees_motion_file_is_the_same_json(tmp_path, tree_run):
    scene, snaps = tree_run(3)
    text = write_motion(tmp_path, scene, snaps).read_text()
    assert "NaN" not in text
    assert json.loads(text) == json.loads(json.dumps(motion_json(scene, snaps)))


def test_a_chains_frames_have_no_tree_fields(run):
    scene, snaps = run(2)
    motion = motion_json(scene, snaps)
    assert not {"parents", "effector_names", "effector_links"} & set(motion)
    assert set(motion["frames"][0]) == {
        "time",
        "tick",
        "step_index",
        "angles_rad",
        "angles_deg",
        "world_angles_rad",
        "joints",
        "target",
        "error",
        "solver_status",
        "torque_limited",
    }
