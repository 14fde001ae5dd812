"""Sprites on the frame: where the link or prop is, at its angle, over the dirty rectangle, with
clean edges, the same pixels every time."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest
from PIL import Image

from ikgame.render import sprites as sprite_module
from ikgame.render.camera import Camera
from ikgame.render.pillow import _static_layers, render_snapshot
from ikgame.render.sprites import decode_sprite, draw_sprite, sprite_corners
from ikgame.render.theme import load_theme
from ikgame.snapshot import PropShape, Scene, Snapshot, Sprite

MAGENTA = (230, 0, 200)
SIZE = (320, 240)


def _solid(width: int, height: int, color=MAGENTA, pivot=(0.0, 0.5), scale=1.0) -> Sprite:
    rgba = np.zeros((height, width, 4), dtype=np.uint8)
    rgba[...] = (*color, 255)
    return Sprite(rgba, (pivot[0] * width, pivot[1] * height), scale)


def _one_link(angle: float, sprite: Sprite | None, length: float = 100.0) -> tuple[Scene, Snapshot]:
    scene = Scene(
        "sprites",
        np.zeros((0, 5)),
        np.zeros((0, 3)),
        np.full(1, 10.0),
        length,
        link_sprites=() if sprite is None else (sprite,),
    )
    joints = np.array([[0.0, 0.0], [length * math.cos(angle), length * math.sin(angle)]])
    return scene, Snapshot(0.0, 0, joints, np.array([angle]), np.array([angle]))


def _camera() -> Camera:
    return Camera(SIZE, scale=1.0, center=(0.0, 0.0))


def _render(scene: Scene, snap: Snapshot) -> np.ndarray:
    image = render_snapshot(scene, snap, _camera(), load_theme("light"), hud=False)
    return np.asarray(image, dtype=int)


def _close(pixel: np.ndarray, color: tuple[int, int, int], tolerance: int = 12) -> bool:
    return bool(np.all(np.abs(pixel - np.array(color)) <= tolerance))


@pytest.mark.parametrize("degrees", [30.0, 125.0])
def test_a_link_sprite_covers_the_link_at_its_angle(degrees):
    angle = math.radians(degrees)
    scene, snap = _one_link(angle, _solid(100, 16))
    pixels = _render(scene, snap)
    camera = _camera()
    mid = camera.world_to_pixel([[50 * math.cos(angle), 50 * math.sin(angle)]])[0]
    x, y = int(mid[0]), int(mid[1])
    assert _close(pixels[y, x], MAGENTA)
    # Turned with the link: the same distance out, 90 degrees away, is not the sprite.
    off = camera.world_to_pixel([[50 * math.cos(angle + 1.2), 50 * math.sin(angle + 1.2)]])[0]
    assert not _close(pixels[int(off[1]), int(off[0])], MAGENTA, tolerance=60)
    # The sprite replaces the capsule: no link colour left along the link.
    link = load_theme("light").link
    assert not any(_close(p, link, 20) for p in pixels.reshape(-1, 3)[::7])


def test_without_a_sprite_the_link_is_a_capsule_of_the_theme_colour():
    scene, snap = _one_link(0.5, None)
    pixels = _render(scene, snap)
    mid = _camera().world_to_pixel([[50 * math.cos(0.5), 50 * math.sin(0.5)]])[0]
    assert _close(pixels[int(mid[1]), int(mid[0])], load_theme("light").link)


def test_a_sprite_larger_than_its_link_is_drawn_whole_despite_the_dirty_rectangle():
    # A crossbar 160 px tall on a 40 px link: far outside the box the capsule would cover.
    scene, snap = _one_link(0.0, _solid(40, 160), length=40.0)
    pixels = _render(scene, snap)
    for world_y in (-70.0, 70.0):
        x, y = _camera().world_to_pixel([[20.0, world_y]])[0].astype(int)
        assert _close(pixels[y, x], MAGENTA)


def test_a_prop_sprite_sits_on_the_prop_and_turns_with_it():
    bar = _solid(60, 10, pivot=(0.5, 0.5))
    scene = Scene(
        "prop",
        np.zeros((0, 5)),
        np.zeros((0, 3)),
        np.full(1, 6.0),
        30.0,
        props=(PropShape("box", (60.0, 10.0)),),
        prop_sprites=(bar,),
    )
    joints = np.array([[-100.0, -80.0], [-100.0, -50.0]])
    camera = _camera()
    for angle, inside, outside in (
        (0.0, (75.0, 40.0), (60.0, 65.0)),
        (math.pi / 2, (60.0, 65.0), (75.0, 40.0)),
    ):
        snap = Snapshot(
            0.0, 0, joints, np.zeros(1), np.zeros(1), props=np.array([[60.0, 40.0, angle]])
        )
        pixels = _render(scene, snap)
        x, y = camera.world_to_pixel([inside])[0].astype(int)
        assert _close(pixels[y, x], MAGENTA)
        x, y = camera.world_to_pixel([outside])[0].astype(int)
        assert not _close(pixels[y, x], MAGENTA, tolerance=60)


def test_transparent_pixels_do_not_darken_the_edges():
    # White on white: straight alpha filtered without premultiplying would leave a dark rim
    # where the transparent (black) pixels bleed into the white ones.
    rgba = np.zeros((40, 40, 4), dtype=np.uint8)
    rgba[10:30, 10:30] = (255, 255, 255, 255)
    canvas = Image.new("RGB", (120, 120), "white")
    draw_sprite(canvas, Sprite(rgba, (20.0, 20.0), 1.0), (60.3, 60.7), 0.4, 1.7)
    assert np.asarray(canvas).min() >= 250


def test_the_same_frame_twice_is_the_same_pixels_even_with_fresh_caches():
    scene, snap = _one_link(0.7, _solid(100, 16))
    first = _render(scene, snap)
    sprite_module._image.cache_clear()
    sprite_module._shrunk.cache_clear()
    _static_layers.cache_clear()
    assert np.array_equal(first, _render(scene, snap))


def test_a_large_image_drawn_small_is_shrunk_first_and_still_lands_on_the_link():
    sprite = _solid(1000, 100, scale=0.1)  # 1000 image px for a 100 px link
    scene, snap = _one_link(0.3, sprite)
    pixels = _render(scene, snap)
    x, y = _camera().world_to_pixel([[50 * math.cos(0.3), 50 * math.sin(0.3)]])[0].astype(int)
    assert _close(pixels[y, x], MAGENTA)


def test_corners_follow_pivot_scale_and_angle():
    sprite = _solid(40, 10, pivot=(0.25, 0.5), scale=2.0)
    corners = sprite_corners(sprite, (0.0, 0.0), 0.0, 1.5)
    # 40 image px x 2 world px x 1.5 drawing px, starting a quarter of the way in.
    assert corners[:, 0].min() == pytest.approx(-30.0)
    assert corners[:, 0].max() == pytest.approx(90.0)
    assert corners[:, 1].min() == pytest.approx(-15.0)


def test_decode_sprite_sizes_the_image_to_the_span_or_the_scale():
    buffer = io.BytesIO()
    Image.new("RGBA", (50, 20), (1, 2, 3, 128)).save(buffer, "PNG")
    fitted = decode_sprite(buffer.getvalue(), (0.5, 0.5), None, 200.0)
    assert fitted.scale == 4.0 and fitted.pivot == (25.0, 10.0)
    assert fitted.rgba.shape == (20, 50, 4) and tuple(fitted.rgba[0, 0]) == (1, 2, 3, 128)
    assert decode_sprite(buffer.getvalue(), (0.0, 0.0), 0.5, 200.0).scale == 0.5


def test_bytes_that_are_not_a_png_do_not_decode():
    with pytest.raises(ValueError, match="cannot be decoded as a PNG image"):
        decode_sprite(b"\x89PNG\r\n\x1a\n" + b"\0" * 40, (0.0, 0.5), None, 10.0)
    buffer = io.BytesIO()
    Image.new("RGB", (4, 4)).save(buffer, "GIF")
    with pytest.raises(ValueError, match="cannot be decoded"):
        decode_sprite(buffer.getvalue(), (0.0, 0.5), None, 10.0)


def test_a_scene_whose_sprites_do_not_match_its_links_is_refused():
    scene, snap = _one_link(0.0, None)
    bad = Scene(
        "x", np.zeros((0, 5)), np.zeros((0, 3)), np.full(1, 10.0), 100.0, link_sprites=(None, None)
    )
    with pytest.raises(ValueError, match="2 link sprites for 1 links"):
        render_snapshot(bad, snap, _camera(), load_theme("light"))


def test_a_sprite_drawn_smaller_than_a_pixel_leaves_the_canvas_alone():
    canvas = Image.new("RGB", (40, 40), "white")
    red = np.zeros((10, 10, 4), dtype=np.uint8)
    red[...] = (255, 0, 0, 255)
    draw_sprite(canvas, Sprite(red, (5.0, 5.0), 1e-300), (20.5, 20.5), 0.3, 1e-30)
    assert canvas.getcolors() == [(1600, (255, 255, 255))]
