"""A level's sprites, decoded once into its Scene; images that pass the level checks but do not
decode are still reported at their line."""

import struct
import zlib

import pytest
from PIL import Image

from ikgame.level.library import LEVELS_DIR
from ikgame.level.loader import LevelError, load_level
from ikgame.sim import Simulation
from ikgame.skins import level_sprites, skin_scene

LEVEL = """\
[level]
name = "skins"
duration = 1.0
[chain]
[[chain.links]]
length = 60.0
repeat = 2
sprite = "arm.png"
[[chain.links]]
length = 30.0
[[props]]
kind = "ball"
name = "b"
position = [100.0, 0.0]
radius = 10.0
sprite = "ball.png"
[[props]]
kind = "box"
name = "c"
position = [-100.0, 0.0]
size = [40.0, 20.0]
[[script]]
wait = 0.5
"""


@pytest.fixture
def level_file(tmp_path):
    Image.new("RGBA", (30, 6), (10, 200, 10, 255)).save(tmp_path / "arm.png")
    Image.new("RGBA", (16, 16), (200, 10, 10, 255)).save(tmp_path / "ball.png")
    path = tmp_path / "skins.toml"
    path.write_text(LEVEL)
    return path


def test_each_link_and_prop_gets_its_sprite_sized_by_default_to_its_shape(level_file):
    links, props = level_sprites(load_level(level_file), level_file)
    assert [s is not None for s in links] == [True, True, False]
    assert links[0] is links[1]  # one decode for the repeated link
    assert links[0].scale == 60.0 / 30 and links[0].pivot == (0.0, 3.0)
    assert props[0].scale == 20.0 / 16 and props[0].pivot == (8.0, 8.0)
    assert props[1] is None


def test_skin_scene_keeps_the_scene_and_adds_the_sprites(level_file):
    level = load_level(level_file)
    scene = Simulation(level).scene
    skinned = skin_scene(scene, level, level_file)
    assert skinned.level_name == scene.level_name and skinned.props == scene.props
    assert len(skinned.link_sprites) == 3 and len(skinned.prop_sprites) == 2
    plain = load_level(LEVELS_DIR / "01_first_reach.toml")
    plain_scene = Simulation(plain).scene
    assert skin_scene(plain_scene, plain, LEVELS_DIR / "01_first_reach.toml") is plain_scene


def _chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


def test_a_whole_png_whose_pixels_do_not_decode_is_reported_at_its_line(level_file):
    level = load_level(level_file)
    # Every chunk's checksum is right, so the level checks pass; the pixel data is not zlib.
    header = struct.pack(">IIBBBBB", 30, 6, 8, 6, 0, 0, 0)
    broken = (
        b"\x89PNG\r\n\x1a\n"
        + _chunk(b"IHDR", header)
        + _chunk(b"IDAT", b"not zlib data")
        + _chunk(b"IEND", b"")
    )
    (level_file.parent / "arm.png").write_bytes(broken)
    with pytest.raises(LevelError) as exc:
        level_sprites(level, level_file)
    (problem,) = exc.value.problems
    assert str(problem).startswith(
        f"{level_file}:8: chain.links[0].sprite: 'arm.png' cannot be decoded as a PNG image"
    )
