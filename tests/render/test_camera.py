"""Camera: the world <-> image transform and fitting a run into a frame."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ikgame.render.camera import Camera, check_size
from ikgame.snapshot import Scene

finite = st.floats(-1e4, 1e4, allow_nan=False)


@given(
    cx=finite,
    cy=finite,
    scale=st.floats(0.01, 100.0),
    points=st.lists(st.tuples(finite, finite), min_size=1, max_size=8),
)
def test_world_pixel_world_round_trip(cx, cy, scale, points):
    cam = Camera((320, 180), center=(cx, cy), scale=scale)
    back = cam.pixel_to_world(cam.world_to_pixel(points))
    np.testing.assert_allclose(back, points, rtol=1e-9, atol=1e-6)


def test_center_maps_to_image_middle_and_y_flips():
    cam = Camera((200, 100), center=(10.0, 20.0), scale=2.0)
    np.testing.assert_allclose(cam.world_to_pixel([[10.0, 20.0]]), [[100.0, 50.0]])
    up, right = cam.world_to_pixel([[10.0, 30.0], [15.0, 20.0]])
    assert up[1] < 50.0, "world y up must go up the image (smaller pixel y)"
    assert right[0] > 100.0


def test_scale_is_equal_on_both_axes():
    cam = Camera((300, 100), scale=1.5)
    a, b, c = cam.world_to_pixel([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]])
    assert abs(b[0] - a[0]) == pytest.approx(abs(c[1] - a[1])) == pytest.approx(15.0)


def test_scaled_keeps_the_view():
    cam = Camera((160, 90), center=(5.0, -3.0), scale=0.5)
    big = cam.scaled(3)
    assert big.size == (480, 270)
    point = [[12.0, 7.0]]
    np.testing.assert_allclose(big.world_to_pixel(point), cam.world_to_pixel(point) * 3)


def _scene(**overrides) -> Scene:
    fields = dict(
        level_name="fit",
        segments=np.array([[-400.0, -50.0, 300.0, -50.0, 10.0]]),
        circles=np.array([[250.0, 200.0, 30.0]]),
        link_widths=np.full(2, 8.0),
        reach=150.0,
        targets=np.array([[-350.0, 260.0]]),
        goals=np.array([[100.0, 100.0, 180.0, 320.0]]),
    )
    fields.update(overrides)
    return Scene(**fields)


@pytest.mark.parametrize("size", [(960, 540), (400, 600), (160, 90)])
def test_fit_contains_all_geometry_inside_the_margin(size):
    scene = _scene()
    base = (20.0, 0.0)
    margin = 0.05
    cam = Camera.fit(scene, base, size=size, margin=margin)
    angles = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    reach_circle = np.c_[np.cos(angles), np.sin(angles)] * scene.reach + base
    seg = scene.segments[0]
    points = np.vstack(
        [
            seg[:2] - seg[4],
            seg[2:4] + seg[4],
            scene.circles[:, :2] + scene.circles[:, 2:],
            scene.circles[:, :2] - scene.circles[:, 2:],
            scene.targets,
            scene.goals[:, :2],
            scene.goals[:, 2:],
            reach_circle,
        ]
    )
    pixels = cam.world_to_pixel(points)
    pad = margin * min(size) - 1e-6
    assert np.all(pixels >= pad)
    assert np.all(pixels <= np.array(size) - pad)
    # Tight on the limiting axis: the geometry spans the image minus the margins.
    span = pixels.max(axis=0) - pixels.min(axis=0)
    assert np.any(np.isclose(span, np.array(size) - 2 * margin * min(size), rtol=1e-6))


def test_fit_shows_everywhere_the_chain_went_including_a_moving_base(run):
    scene, snaps = run(4)
    moved = [dataclasses.replace(s, joints=s.joints + [300.0, 0.0]) for s in snaps[2:]]
    run_snaps = snaps[:2] + moved
    cam = Camera.fit(scene, run_snaps, size=(320, 180))
    pixels = cam.world_to_pixel(np.concatenate([s.joints for s in run_snaps]))
    assert np.all(pixels >= 0) and np.all(pixels <= [320, 180])


def test_fit_to_a_run_is_no_looser_than_the_reach_square_of_its_base(run):
    # A run shows where the chain went; the full reach square is for a lone base point.
    scene, snaps = run(3)
    from_run = Camera.fit(scene, snaps, (320, 180))
    from_base = Camera.fit(scene, snaps[0].joints[0], (320, 180))
    assert from_run.scale >= from_base.scale


def test_fit_uses_scene_bounds_exactly_and_centred():
    scene = _scene(bounds=(-100.0, -50.0, 300.0, 150.0))
    cam = Camera.fit(scene, (0.0, 0.0), size=(800, 800))
    corners = cam.world_to_pixel([[-100.0, -50.0], [300.0, 150.0]])
    np.testing.assert_allclose(corners[:, 0], [0.0, 800.0])  # width limits
    np.testing.assert_allclose(corners[:, 1], [600.0, 200.0])  # centred vertically


def test_fit_of_an_empty_scene_is_finite():
    scene = _scene(
        segments=np.zeros((0, 5)),
        circles=np.zeros((0, 3)),
        targets=np.zeros((0, 2)),
        goals=np.zeros((0, 4)),
        reach=0.0,
    )
    cam = Camera.fit(scene, (0.0, 0.0), size=(100, 100), margin=0.0)
    assert cam.scale == pytest.approx(1.0)


@pytest.mark.parametrize("size", [(0, 10), (10, -1), (10.5, 3), "abc", (True, True), (1, 2, 3)])
def test_bad_sizes_raise(size):
    with pytest.raises(ValueError, match="size"):
        check_size(size)
    with pytest.raises(ValueError, match="size"):
        Camera.fit(_scene(), (0.0, 0.0), size=size)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(scale=0.0), "scale"),
        (dict(scale=float("nan")), "scale"),
        (dict(center=(float("inf"), 0.0)), "center"),
    ],
)
def test_bad_camera_fields_raise(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Camera((10, 10), **kwargs)


def test_bad_inputs_to_fit_and_transforms_raise():
    with pytest.raises(ValueError, match="margin"):
        Camera.fit(_scene(), (0.0, 0.0), margin=0.5)
    with pytest.raises(ValueError, match="snapshots or a base point"):
        Camera.fit(_scene(), [], size=(10, 10))
    with pytest.raises(ValueError, match="bounds"):
        Camera.fit(_scene(bounds=(0.0, 0.0, 0.0, 10.0)), (0.0, 0.0))
    with pytest.raises(ValueError, match=r"shape \(k, 2\)"):
        Camera((10, 10)).world_to_pixel([1.0, 2.0, 3.0])


def test_fit_holds_every_effectors_targets_and_the_tree(tree_run):
    scene, snaps = tree_run(3)
    camera = Camera.fit(scene, snaps, (320, 180))
    far = (np.array([[-500.0, 0.0], [0.0, 0.0]]), np.array([[0.0, 0.0], [0.0, 400.0]]))
    wide = Camera.fit(dataclasses.replace(scene, effector_targets=far), snaps, (320, 180))
    moved = [
        dataclasses.replace(s, targets=np.array([[0.0, -300.0], [np.nan, np.nan]])) for s in snaps
    ]
    low = Camera.fit(scene, moved, (320, 180))
    for cam, points in [
        (camera, np.concatenate([*scene.effector_targets, *(s.joints for s in snaps)])),
        (wide, np.concatenate(far)),
        (low, [[0.0, -300.0]]),
    ]:
        pixels = cam.world_to_pixel(points)
        assert np.all(pixels >= 0) and np.all(pixels <= [320, 180])
