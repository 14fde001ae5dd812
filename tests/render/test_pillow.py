"""render_snapshot: pixels land where the camera says, deterministically."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from PIL import Image, ImageDraw

from ikgame.render import pillow
from ikgame.render.camera import Camera
from ikgame.render.pillow import render_snapshot
from ikgame.render.theme import load_theme
from ikgame.snapshot import PropShape, Scene, Snapshot

SIZE = (160, 90)
LIGHT = load_theme("light")


def _bare_scene(**overrides) -> Scene:
    fields = dict(
        level_name="bare",
        segments=np.zeros((0, 5)),
        circles=np.zeros((0, 3)),
        link_widths=np.array([12.0]),
        reach=100.0,
        step_count=0,
    )
    fields.update(overrides)
    return Scene(**fields)


def _one_link(torque_limited=False, **overrides) -> Snapshot:
    """A single horizontal link from (-50, 0) to (50, 0)."""
    fields = dict(
        time=0.0,
        tick=0,
        joints=np.array([[-50.0, 0.0], [50.0, 0.0]]),
        angles=np.zeros(1),
        world_angles=np.zeros(1),
        torque_limited=np.array([torque_limited]),
    )
    fields.update(overrides)
    return Snapshot(**fields)


def _pixel(image: Image.Image, camera: Camera, world) -> tuple[int, int, int]:
    x, y = camera.world_to_pixel([world])[0]
    return image.getpixel((int(x), int(y)))


def test_image_has_camera_size_and_is_not_blank(run):
    scene, snaps = run(4)
    camera = Camera.fit(scene, snaps, SIZE)
    image = render_snapshot(scene, snaps[2], camera, LIGHT, trail=np.array([[0, 0], [10, 10.0]]))
    assert image.mode == "RGB" and image.size == SIZE
    colors = image.getcolors(SIZE[0] * SIZE[1])
    assert len(colors) > 50, "anti-aliasing and the scene should give many colours"
    background = max(colors)[1]
    assert background == LIGHT.background


def test_link_pixels_are_where_the_camera_says():
    scene = _bare_scene()
    camera = Camera((200, 100), center=(0.0, 30.0), scale=1.0)
    image = render_snapshot(scene, _one_link(), camera, LIGHT, hud=False)
    assert _pixel(image, camera, (0.0, 0.0)) == LIGHT.link
    assert _pixel(image, camera, (-25.0, 2.0)) == LIGHT.link
    # Well clear of the 12 px wide bar, above it and off the grid lines: background.
    assert _pixel(image, camera, (13.0, 20.0)) == LIGHT.background


def test_torque_limited_links_are_tinted():
    scene = _bare_scene()
    camera = Camera((200, 100), scale=1.0)
    image = render_snapshot(scene, _one_link(torque_limited=True), camera, LIGHT, hud=False)
    assert _pixel(image, camera, (0.0, 0.0)) == LIGHT.torque_limited


def test_thin_links_keep_a_minimum_width():
    scene = _bare_scene(link_widths=np.array([0.1]))
    camera = Camera((200, 100), scale=1.0)
    image = render_snapshot(scene, _one_link(), camera, LIGHT, hud=False)
    column = np.asarray(image)[:, 100]
    assert np.sum(np.any(column != LIGHT.background, axis=1)) >= pillow.MIN_LINK_WIDTH


def test_target_trail_and_goal_are_drawn():
    scene = _bare_scene(goals=np.array([[40.0, 20.0, 80.0, 45.0]]))
    camera = Camera((200, 100), scale=1.0)
    target = np.array([-60.0, 30.0])
    snap = _one_link(target=target)
    trail = np.array([[60.0, -40.0], [80.0, -40.0]])
    image = render_snapshot(scene, snap, camera, LIGHT, trail=trail, hud=False)
    centre = np.array(_pixel(image, camera, target))  # the crosshair's small centre dot
    assert np.abs(centre - LIGHT.target).max() < 40
    assert _pixel(image, camera, (75.0, -40.0)) != LIGHT.background  # the newest trail end
    goal_fill = pillow._blend(LIGHT.background, LIGHT.goal, pillow.GOAL_FILL_ALPHA)
    assert _pixel(image, camera, (60.0, 32.0)) == goal_fill


def test_rendering_is_deterministic(run):
    scene, snaps = run(5)
    camera = Camera.fit(scene, snaps, SIZE)
    first = render_snapshot(scene, snaps[3], camera, LIGHT, trail=np.zeros((3, 2))).tobytes()
    pillow._static_layers.cache_clear()
    second = render_snapshot(scene, snaps[3], camera, LIGHT, trail=np.zeros((3, 2))).tobytes()
    assert first == second


def test_the_static_layer_is_held_as_exact_flat_fills_a_byte_per_pixel(run):
    """The supersampled static layer is a palette image of the theme's fills alone, and the
    shrunk layer, made strip by strip, is the block average of the whole layer in RGB."""
    scene, snaps = run(2)
    camera = Camera.fit(scene, snaps, (160, 3 * pillow.STATIC_STRIP // 2))  # a partial strip
    pillow._static_layers.cache_clear()
    big, small = pillow._static_layers(scene, camera, LIGHT, 3)
    assert big.mode == "P" and big.size == camera.scaled(3).size
    goal_fill = pillow._blend(LIGHT.background, LIGHT.goal, pillow.GOAL_FILL_ALPHA)
    fills = {LIGHT.background, LIGHT.grid, goal_fill, LIGHT.goal}
    fills |= {LIGHT.obstacle, LIGHT.obstacle_outline}
    rgb = big.convert("RGB")
    assert {color for _, color in rgb.getcolors()} == fills
    assert small.mode == "RGB" and small.tobytes() == rgb.reduce(3).tobytes()


def test_redrawing_only_the_moving_parts_matches_a_full_frame(run):
    """render_snapshot redraws only the rectangle around the moving parts and shrinks only the
    tiles they touch: nothing may be clipped, so it matches drawing and shrinking the whole frame
    but for a few edge pixels that Pillow's rasteriser rounds differently at shifted
    coordinates."""
    scene, snaps = run(5)
    camera = Camera.fit(scene, snaps, SIZE)
    trail = np.array([s.joints[-1] for s in snaps[:4]])
    fast = render_snapshot(scene, snaps[3], camera, LIGHT, trail=trail, hud=False)

    big = camera.scaled(3)
    full = pillow._static_layers(scene, camera, LIGHT, 3)[0].convert("RGB")
    pillow._draw_dynamic(
        pillow._Painter(ImageDraw.Draw(full), big, LIGHT, 3), scene, snaps[3], trail
    )
    full = full.reduce(3)
    diff = np.abs(np.asarray(fast, dtype=int) - np.asarray(full, dtype=int)).max(axis=2)
    assert np.count_nonzero(diff) < 0.005 * diff.size
    assert diff.mean() < 0.2


def test_dirty_rects_cover_every_box_with_tiles_and_no_more():
    boxes = [(10.0 * k, 6.0 * k, 10.0 * k + 12, 6.0 * k + 12) for k in range(60)]  # a diagonal
    size, ss = (640, 360), 3
    rects = pillow._dirty_rects(boxes, size, ss)
    covered = np.zeros(size[::-1], dtype=int)
    for x0, y0, x1, y1 in rects:
        covered[y0:y1, x0:x1] += 1
    assert covered.max() == 1  # no pixel pasted twice
    for x0, y0, x1, y1 in boxes:
        x0, y0 = int(x0 // ss), int(y0 // ss)
        x1, y1 = min(size[0], -int(-x1 // ss)), min(size[1], -int(-y1 // ss))
        assert covered[y0:y1, x0:x1].all()
    # Far less than the rectangle around the diagonal, which the tiles would all fill.
    assert covered.sum() < 0.5 * (600 / ss + 12) * (354 / ss + 12)
    for outside in [
        (-90.0, -90.0, -10.0, -10.0),
        (-900.0, 9.0, -500.0, 30.0),
        (9e3, 9e3, 1e4, 1e4),
    ]:
        assert pillow._dirty_rects([outside], size, ss) == []


def test_a_chain_out_of_the_picture_leaves_the_static_scene(run):
    scene, snaps = run(2)
    camera = Camera.fit(scene, snaps, SIZE)
    away = dataclasses.replace(
        snaps[0], joints=snaps[0].joints + 1e5, target=None, props=np.zeros((0, 3))
    )
    away_scene = dataclasses.replace(scene, props=(), targets=np.zeros((0, 2)))
    image = render_snapshot(away_scene, away, camera, LIGHT, hud=False)
    static = pillow._static_layers(away_scene, camera, LIGHT, 3)[1]
    assert image.tobytes() == static.tobytes()


def test_hud_changes_only_the_top_left_corner(run):
    scene, snaps = run(3)
    camera = Camera.fit(scene, snaps, (320, 180))
    with_hud = np.asarray(render_snapshot(scene, snaps[1], camera, LIGHT))
    without = np.asarray(render_snapshot(scene, snaps[1], camera, LIGHT, hud=False))
    rows, cols = np.nonzero(np.any(with_hud != without, axis=2))
    assert len(rows) > 0
    assert rows.max() < 90 and cols.max() < 250


def test_supersample_one_draws_without_shrinking(run):
    scene, snaps = run(3)
    camera = Camera.fit(scene, snaps, SIZE)
    image = render_snapshot(scene, snaps[1], camera, LIGHT, supersample=1)
    assert image.size == SIZE


@pytest.mark.parametrize("value", [0, 9, 2.0, True])
def test_bad_supersample_raises(run, value):
    scene, snaps = run(2)
    with pytest.raises(ValueError, match="supersample"):
        render_snapshot(scene, snaps[0], Camera(SIZE), LIGHT, supersample=value)


def test_mismatched_scene_and_snapshot_raise():
    camera = Camera((100, 100))
    with pytest.raises(ValueError, match="link widths"):
        render_snapshot(_bare_scene(link_widths=np.ones(2)), _one_link(), camera, LIGHT)
    with pytest.raises(ValueError, match="prop poses"):
        render_snapshot(
            _bare_scene(props=(PropShape("ball", (5.0, 5.0)),)), _one_link(), camera, LIGHT
        )
    bad_prop = _bare_scene(props=(PropShape("cone", (5.0, 5.0)),))
    with pytest.raises(ValueError, match="unknown prop kind"):
        render_snapshot(bad_prop, _one_link(props=np.zeros((1, 3))), camera, LIGHT)
    with pytest.raises(ValueError, match="joints"):
        render_snapshot(_bare_scene(), _one_link(joints=np.zeros((1, 2))), camera, LIGHT)


def test_upcoming_targets_follow_the_current_one():
    targets = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]])
    scene = _bare_scene(targets=targets, step_count=4)  # a follow step among the reach steps
    at_second = _one_link(target=targets[1], step_index=2)
    assert pillow._upcoming(scene, at_second).tolist() == [[2.0, 2.0]]
    following = _one_link(target=np.array([9.0, 9.0]), step_index=1)
    assert len(pillow._upcoming(scene, following)) == 0
    one_per_step = _bare_scene(targets=targets, step_count=3)
    assert len(pillow._upcoming(one_per_step, _one_link(step_index=0))) == 2
    done = _one_link(target=targets[0], step_index=4)
    assert len(pillow._upcoming(scene, done)) == 0


def test_a_dashed_path_to_a_far_target_draws_only_the_dashes_inside_the_frame():
    from ikgame.render.pillow import _dashed

    class Lines:
        def __init__(self):
            self.drawn = []

        def line(self, xy, fill=None, width=1):
            self.drawn.append(xy)

    frame = (np.array([0.0, 0.0]), np.array([100.0, 100.0]))
    far, near = Lines(), Lines()
    _dashed(far, np.array([50.0, 50.0]), np.array([1e9, 50.0]), (0, 0, 0), frame, 1, 5.0)
    _dashed(near, np.array([50.0, 50.0]), np.array([120.0, 50.0]), (0, 0, 0), frame, 1, 5.0)
    assert far.drawn == near.drawn  # the same dashes where they can be seen, none beyond
    assert len(far.drawn) == 6
    outside = Lines()
    _dashed(outside, np.array([-1e9, -5e8]), np.array([1e9, -5e8]), (0, 0, 0), frame, 1, 5.0)
    assert outside.drawn == []


# -- trees -----------------------------------------------------------------------------------------

TREE_CAMERA = Camera((240, 180), center=(0.0, 50.0), scale=1.0)


def _near(image: Image.Image, camera: Camera, world, color, radius: int = 2) -> bool:
    """Whether a pixel within ``radius`` of ``world`` is within 40 of ``color`` on every
    channel (a small marker's centre is anti-aliased into its neighbours)."""
    x, y = (int(v) for v in camera.world_to_pixel([world])[0])
    block = np.asarray(image, dtype=int)[y - radius : y + radius + 1, x - radius : x + radius + 1]
    return bool(np.any(np.abs(block - np.array(color)).max(axis=2) < 40))


def test_a_tree_draws_every_link_and_each_effector_in_its_own_colour(tree_run):
    scene, snaps = tree_run(4)
    snap = snaps[-1]
    styles = LIGHT.effector_styles(2)
    trail = np.array([[[-60.0, 100.0], [60.0, 100.0]], [[-40.0, 110.0], [40.0, 110.0]]])
    image = render_snapshot(scene, snap, TREE_CAMERA, LIGHT, trail=trail, hud=False)
    starts, ends = snap.joints[:5], snap.joints[5:]
    for i in range(5):  # the middle of every link, the trunk and both arms
        middle = starts[i] + 0.45 * (ends[i] - starts[i])
        assert _pixel(image, TREE_CAMERA, middle) == LIGHT.link, i
    for j, link in enumerate(scene.effector_links):
        assert _pixel(image, TREE_CAMERA, ends[link]) == styles[j].tip
        assert _near(image, TREE_CAMERA, snap.targets[j], styles[j].target)  # crosshair dot
        assert _near(image, TREE_CAMERA, trail[-1, j] - (2.0, 0.0), styles[j].trail, 1)
    assert styles[0].target != styles[1].target
    # Not the chain's one target colour: each effector has its own.
    assert not _near(image, TREE_CAMERA, snap.targets[0], LIGHT.target, 4)


def test_a_tree_joint_sits_where_the_arms_branch(tree_run):
    scene, snaps = tree_run(2)
    image = render_snapshot(scene, snaps[0], TREE_CAMERA, LIGHT, hud=False)
    branch = snaps[0].joints[5 + 0]  # the trunk's end, where both arms start
    assert _pixel(image, TREE_CAMERA, branch) == LIGHT.joint
    assert _pixel(image, TREE_CAMERA, snaps[0].joints[0]) == LIGHT.base  # the root's bolt


def test_an_effector_without_a_target_has_no_marker_but_its_upcoming_ones(tree_run):
    scene, snaps = tree_run(3)
    first = snaps[0]  # the right arm has no target yet
    assert np.isnan(first.targets[1]).all()
    assert pillow._upcoming(scene, first, 0).tolist() == [[-80.0, 20.0]]
    np.testing.assert_array_equal(pillow._upcoming(scene, first, 1), scene.effector_targets[1])
    assert pillow._upcoming(scene, snaps[1], 1).tolist() == [[90.0, 90.0]]
    following = dataclasses.replace(snaps[1], targets=np.array([[5.0, 5.0], [6.0, 6.0]]))
    assert len(pillow._upcoming(scene, following, 0)) == 0
    image = render_snapshot(scene, first, TREE_CAMERA, LIGHT, hud=False)
    right = LIGHT.effector_styles(2)[1]
    assert not _near(image, TREE_CAMERA, scene.effector_targets[1][0], right.target, 4)
    pixels = np.asarray(image).reshape(-1, 3)
    assert np.any(np.all(pixels == right.upcoming, axis=1))  # its upcoming rings


def test_redrawing_only_a_trees_moving_parts_matches_a_full_frame(tree_run):
    scene, snaps = tree_run(5)
    camera = Camera.fit(scene, snaps, SIZE)
    from ikgame.render.export import trail_at

    trail = trail_at(scene, snaps, 3)
    fast = render_snapshot(scene, snaps[3], camera, LIGHT, trail=trail, hud=False)
    full = pillow._static_layers(scene, camera, LIGHT, 3)[0].convert("RGB")
    pillow._draw_dynamic(
        pillow._Painter(ImageDraw.Draw(full), camera.scaled(3), LIGHT, 3), scene, snaps[3], trail
    )
    full = full.reduce(3)
    diff = np.abs(np.asarray(fast, dtype=int) - np.asarray(full, dtype=int)).max(axis=2)
    assert np.count_nonzero(diff) < 0.005 * diff.size
    assert diff.mean() < 0.2


def test_the_hud_lists_each_effectors_error_in_its_colour(tree_run):
    scene, snaps = tree_run(2)
    lines = pillow._hud_lines(scene, snaps[0], LIGHT)
    styles = LIGHT.effector_styles(2)
    (effectors,) = [line for line in lines if line[0][0] == "left"]
    text = "".join(run for run, _ in effectors)
    assert text == f"left {snaps[0].errors[0]:.1f}   right - px"
    assert (("left", styles[0].target) in effectors) and (("right", styles[1].target) in effectors)
    many = dataclasses.replace(
        scene,
        effector_names=tuple("abcdef"),
        parents=np.array([-1] * 6),
        effector_links=np.arange(6),
        link_widths=np.ones(6),
        effector_targets=(),
    )
    snap = dataclasses.replace(snaps[0], errors=np.arange(6.0))
    assert len(pillow._effector_lines(many, snap, LIGHT)) == 2  # four to a line
    # A chain's HUD is as it was: no effector line.
    assert pillow._effector_lines(_bare_scene(), _one_link(), LIGHT) == []
    image = render_snapshot(scene, snaps[0], TREE_CAMERA, LIGHT)
    assert image.size == TREE_CAMERA.size


def test_a_tree_snapshot_that_does_not_fit_its_scene_raises(tree_run):
    scene, snaps = tree_run(1)
    with pytest.raises(ValueError, match=r"a tree of 5 links needs \(10, 2\)"):
        render_snapshot(
            scene, dataclasses.replace(snaps[0], joints=np.zeros((6, 2))), TREE_CAMERA, LIGHT
        )
    with pytest.raises(ValueError, match="3 target rows for 2 effectors"):
        render_snapshot(
            scene, dataclasses.replace(snaps[0], targets=np.zeros((3, 2))), TREE_CAMERA, LIGHT
        )
    with pytest.raises(ValueError, match="trail has shape"):
        render_snapshot(scene, snaps[0], TREE_CAMERA, LIGHT, trail=np.zeros((4, 3, 2)))


def test_a_tree_links_sprite_lies_along_that_link(tree_run):
    from ikgame.snapshot import Sprite

    red = np.zeros((8, 40, 4), dtype=np.uint8)
    red[...] = (255, 0, 0, 255)
    sprites = (None, None, None, Sprite(red, (0.0, 4.0), 1.0), None)  # the right upper arm
    scene, snaps = tree_run(2, link_sprites=sprites)
    snap = snaps[-1]
    image = render_snapshot(scene, snap, TREE_CAMERA, LIGHT, hud=False)
    starts, ends = snap.joints[:5], snap.joints[5:]
    assert _pixel(image, TREE_CAMERA, (starts[3] + ends[3]) / 2) == (255, 0, 0)
    assert _pixel(image, TREE_CAMERA, (starts[1] + ends[1]) / 2) == LIGHT.link


def test_roots_spread_over_a_body_stand_on_no_pedestal():
    def image(starts):
        scene = _bare_scene(
            link_widths=np.full(2, 12.0),
            parents=np.array([-1, -1]),
            effector_links=np.array([0, 1]),
            effector_names=("a", "b"),
        )
        joints = np.vstack([starts, starts + [0.0, 40.0]])
        snap = Snapshot(0.0, 0, joints, np.zeros(2), np.zeros(2), targets=np.full((2, 2), np.nan))
        return render_snapshot(scene, snap, Camera((200, 100), scale=1.0), LIGHT, hud=False)

    camera = Camera((200, 100), scale=1.0)
    shared = image(np.array([[0.0, 0.0], [0.0, 0.0]]))
    assert _pixel(shared, camera, (0.0, -12.0)) == LIGHT.base  # the pedestal under the base
    spread = image(np.array([[-40.0, 0.0], [40.0, 0.0]]))
    for x in (-40.0, 40.0):
        assert _pixel(spread, camera, (x, -12.0)) == LIGHT.background
        assert _pixel(spread, camera, (x, 0.0)) == LIGHT.base  # each root's bolt
