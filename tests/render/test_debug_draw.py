"""PillowDrawOptions: any pymunk Space drawn through the same camera transform as the frames."""

from __future__ import annotations

import pymunk
import pytest
from PIL import Image

from ikgame.render.camera import Camera
from ikgame.render.debug_draw import PillowDrawOptions


def _pixel(image: Image.Image, camera: Camera, world) -> tuple[int, int, int]:
    x, y = camera.world_to_pixel([world])[0]
    return image.getpixel((int(x), int(y)))


def test_pillow_draw_options_draws_a_pymunk_space():
    space = pymunk.Space()
    floor = pymunk.Segment(space.static_body, (-80, -30), (80, -30), 5)
    body = pymunk.Body(1, 100)
    body.position = (20, 10)
    ball = pymunk.Circle(body, 12)
    box = pymunk.Poly.create_box(body, (10, 10))
    space.add(floor, body, ball, box)
    image = Image.new("RGB", (200, 100), "white")
    camera = Camera((200, 100), center=(0.0, 0.0), scale=1.0)
    options = PillowDrawOptions(image, camera)
    space.debug_draw(options)
    white = (255, 255, 255)
    assert _pixel(image, camera, (0.0, -30.0)) != white  # the floor
    assert _pixel(image, camera, (20.0 - 8.0, 10.0 + 3.0)) != white  # inside the ball
    assert _pixel(image, camera, (0.0, 30.0)) == white


def test_pillow_draw_options_default_camera_is_y_up_from_the_bottom_left():
    space = pymunk.Space()
    space.add(pymunk.Segment(space.static_body, (10, 5), (90, 5), 2))
    image = Image.new("RGB", (100, 50), "white")
    space.debug_draw(PillowDrawOptions(image))
    assert image.getpixel((50, 44)) != (255, 255, 255)  # 5 px above the bottom edge
    assert image.getpixel((50, 5)) == (255, 255, 255)


def test_pillow_draw_options_rejects_a_camera_of_another_size():
    with pytest.raises(ValueError, match="camera size"):
        PillowDrawOptions(Image.new("RGB", (10, 10)), Camera((20, 20)))
