"""Sprite images: decoded from PNG bytes once per run, then drawn turned and scaled on each frame.

Drawing maps the image onto the (supersampled) frame with one affine transform, so a sprite
lands at its exact sub-pixel place and angle, with no cache of turned copies to keep; the frame's
Lanczos shrink then smooths its edges like every other shape's. The transform filters bilinearly:
after that shrink a bicubic one differs by 0.13 of 255 on average over a 960x540 frame of the
skinned arm (invisible side by side) and costs 2.4 times as much, and the transform is most of
what a sprite costs. An image drawn at less than half its size is first shrunk with a Lanczos
filter (kept per run: the camera's scale does not change within one), since a transform alone
would skip source pixels and alias. Pillow premultiplies alpha while it filters, so transparent
pixels do not darken a sprite's edges.
"""

from __future__ import annotations

import io
import math
from functools import lru_cache

import numpy as np
from PIL import Image, UnidentifiedImageError

from ikgame.snapshot import Sprite

__all__ = ["decode_sprite", "sprite_corners", "draw_sprite"]


def decode_sprite(
    data: bytes, pivot: tuple[float, float], scale: float | None, span: float
) -> Sprite:
    """A :class:`~ikgame.snapshot.Sprite` from PNG bytes; ``ValueError`` when they cannot be
    decoded.

    ``pivot`` is given as fractions of the image's width and height (from its top-left corner);
    ``scale`` in world px per image px, or None for the image's width to span ``span`` world px.

    >>> image = Image.new("RGBA", (40, 10), (200, 40, 40, 255))
    >>> buffer = io.BytesIO(); image.save(buffer, "PNG")
    >>> sprite = decode_sprite(buffer.getvalue(), (0.0, 0.5), None, 120.0)
    >>> sprite.size, sprite.pivot, sprite.scale
    ((40, 10), (0.0, 5.0), 3.0)
    """
    try:
        with Image.open(io.BytesIO(data), formats=["PNG"]) as image:
            rgba = np.asarray(image.convert("RGBA"), dtype=np.uint8).copy()
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError) as exc:
        raise ValueError(f"cannot be decoded as a PNG image ({exc})") from None
    height, width = rgba.shape[:2]
    return Sprite(
        rgba=rgba,
        pivot=(pivot[0] * width, pivot[1] * height),
        scale=float(scale) if scale is not None else span / width,
    )


def _frame(
    sprite: Sprite, anchor: tuple[float, float], angle: float, scale: float
) -> tuple[np.ndarray, float]:
    """The linear map from image px (about the pivot) to drawing px, and drawing px per image
    px. Drawing coordinates have y down, so a world angle turns the other way on screen."""
    k = sprite.scale * scale
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, s], [-s, c]]) * k, k


def sprite_corners(
    sprite: Sprite, anchor: tuple[float, float], angle: float, scale: float
) -> np.ndarray:
    """The image's four corners in drawing px (4, 2), for a sprite whose pivot sits at
    ``anchor`` (drawing px, pixel corners at integers) turned by ``angle`` (world radians,
    counter-clockwise), at ``scale`` drawing px per world px.

    >>> sprite = Sprite(np.zeros((10, 40, 4), dtype=np.uint8), (0.0, 5.0), 1.0)
    >>> sprite_corners(sprite, (100.0, 50.0), math.pi / 2, 2.0).round(6).tolist()
    [[90.0, 50.0], [90.0, -30.0], [110.0, -30.0], [110.0, 50.0]]
    """
    matrix, _ = _frame(sprite, anchor, angle, scale)
    width, height = sprite.size
    corners = np.array([[0, 0], [width, 0], [width, height], [0, height]], dtype=float)
    return (corners - sprite.pivot) @ matrix.T + anchor


def draw_sprite(
    canvas: Image.Image,
    sprite: Sprite,
    anchor: tuple[float, float],
    angle: float,
    scale: float,
) -> None:
    """Draw ``sprite`` on the RGB ``canvas``, placed as :func:`sprite_corners` says, alpha
    blended over what is there.

    >>> canvas = Image.new("RGB", (80, 80), "white")
    >>> red = np.zeros((10, 40, 4), dtype=np.uint8); red[...] = (255, 0, 0, 255)
    >>> draw_sprite(canvas, Sprite(red, (0.0, 5.0), 1.0), (40.0, 40.0), math.pi / 2, 1.0)
    >>> canvas.getpixel((40, 20)), canvas.getpixel((60, 20))
    ((255, 0, 0), (255, 255, 255))
    """
    corners = sprite_corners(sprite, anchor, angle, scale)
    x0, y0 = np.maximum(np.floor(corners.min(axis=0)), 0).astype(int)
    x1 = min(int(math.ceil(corners[:, 0].max())), canvas.size[0])
    y1 = min(int(math.ceil(corners[:, 1].max())), canvas.size[1])
    if x0 >= x1 or y0 >= y1:
        return
    matrix, k = _frame(sprite, anchor, angle, scale)
    if abs(np.linalg.det(matrix)) < 1e-12:
        return  # drawn smaller than a millionth of a pixel: nothing to see
    source = _source(sprite, k)
    # Output px (X, Y) of the box -> image px about the pivot (the inverse of the frame), then
    # -> px of the (possibly shrunk) source.
    inverse = np.linalg.inv(matrix)
    ratio = np.array([source.size[0] / sprite.size[0], source.size[1] / sprite.size[1]])
    linear = inverse * ratio[:, None]
    offset = (np.asarray(sprite.pivot) + inverse @ (np.array([x0, y0]) - anchor)) * ratio
    data = (linear[0, 0], linear[0, 1], offset[0], linear[1, 0], linear[1, 1], offset[1])
    placed = source.transform(
        (int(x1 - x0), int(y1 - y0)),
        Image.Transform.AFFINE,
        tuple(float(v) for v in data),
        resample=Image.Resampling.BILINEAR,
    )
    canvas.paste(placed, (int(x0), int(y0)), placed)


def _source(sprite: Sprite, k: float) -> Image.Image:
    """The sprite as a Pillow image, shrunk first when it is drawn smaller than half size."""
    width, height = sprite.size
    if k >= 0.5:
        return _image(sprite)
    size = (max(1, round(width * k)), max(1, round(height * k)))
    return _shrunk(sprite, size)


@lru_cache(maxsize=64)
def _image(sprite: Sprite) -> Image.Image:
    """Keyed by the sprite's identity (``Sprite`` compares by identity), like the static layers."""
    return Image.fromarray(sprite.rgba, "RGBA")


@lru_cache(maxsize=64)
def _shrunk(sprite: Sprite, size: tuple[int, int]) -> Image.Image:
    return _image(sprite).resize(size, Image.Resampling.LANCZOS)
