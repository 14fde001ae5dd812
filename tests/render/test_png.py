"""The PNG encoder: files any decoder reads back to the same pixels, at every level."""

import io
import tracemalloc

import numpy as np
import pytest
from PIL import Image

from ikgame.render.png import png_bytes, png_chunks


def _noise(mode: str, size=(37, 23), seed=3) -> Image.Image:
    rng = np.random.default_rng(seed)
    bands = len(mode)
    pixels = rng.integers(0, 256, (size[1], size[0], bands), dtype=np.uint8)
    # Flat runs too, like a rendered frame's fills, so the Up filter's zeros are exercised.
    pixels[5:15] = pixels[5]
    return Image.fromarray(pixels, mode)


@pytest.mark.parametrize("mode", ["RGB", "RGBA"])
@pytest.mark.parametrize("level", [0, 1, 9])
def test_pillow_reads_back_the_same_pixels(mode, level):
    image = _noise(mode)
    decoded = Image.open(io.BytesIO(png_bytes(image, level)))
    assert decoded.mode == mode
    assert decoded.tobytes() == image.tobytes()


def test_other_modes_are_written_as_rgb():
    image = _noise("RGB").convert("L")
    decoded = Image.open(io.BytesIO(png_bytes(image)))
    assert decoded.mode == "RGB"
    assert decoded.tobytes() == image.convert("RGB").tobytes()


def test_higher_levels_make_smaller_files_and_output_is_deterministic():
    image = Image.new("RGB", (300, 200), (240, 230, 220))
    image.paste(_noise("RGB", (120, 80)), (40, 50))
    assert len(png_bytes(image, 9)) < len(png_bytes(image, 0))
    assert png_bytes(image, 1) == png_bytes(image.copy(), 1)


@pytest.mark.parametrize("level", [-1, 10, 1.0, True, None])
def test_bad_levels_raise(level):
    with pytest.raises(ValueError, match="compress_level"):
        png_bytes(Image.new("RGB", (2, 2)), level)


def test_chunks_of_a_non_png_raise():
    with pytest.raises(ValueError, match="not a PNG"):
        list(png_chunks(b"GIF89a"))


def test_a_frame_is_encoded_with_its_filtered_rows_as_the_one_copy():
    """An RGB frame is read as it is and its filtered rows go to zlib as they are: the pixels
    and the filtered rows, no third copy of a frame per encoding."""
    image = Image.new("RGB", (960, 540), (240, 240, 235))
    frame_bytes = 960 * 540 * 3
    tracemalloc.start()
    try:
        png_bytes(image)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 2.5 * frame_bytes
