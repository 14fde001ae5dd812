"""The two animated formats of an export, GIF and APNG, written as streams: frames go in one at a
time, so a long run is never held in memory.

Internal to the render package (:func:`~ikgame.render.export.export_run` drives it; nothing here
is re-exported). Every byte written is a deterministic function of the frames, so the files are
the same whichever process drew them.

The GIF has one palette for the whole run, built from a sample of frames with the flat fills kept
exact, and each frame after the first stored as the rectangle that changed. The APNG reuses the
encoded PNG frames' image data as is, so nothing is compressed twice.
"""

from __future__ import annotations

import math
import mmap
import struct
from collections import Counter
from collections.abc import Iterable, Sequence
from fractions import Fraction
from functools import lru_cache
from typing import IO

import numpy as np
from PIL import GifImagePlugin, Image

from ikgame.render.png import PNG_SIGNATURE, png_chunk, png_chunks
from ikgame.render.theme import RGB, Theme

__all__ = [
    "ApngWriter",
    "GifWriter",
    "build_palette",
    "color_counts",
    "gif_durations",
    "quantizer",
]

GIF_COLORS = 255  # palette entries for pixels; the 256th is the transparent "unchanged" index
GIF_TRANSPARENT = 255
GIF_FREQUENT = 64  # most common exact colours kept as they are: the flat fills never dither
# New colours matched to the palette at a time: a frame can bring thousands (a sprite, a
# gradient), and each block's distances to the 255 entries take 512 * 255 * 3 * 4 bytes (1.6 MB).
NEAREST_BLOCK = 512


# -- GIF -----------------------------------------------------------------------------------------


def color_counts(image: Image.Image) -> list[tuple[int, RGB]]:
    """Each colour of ``image`` with its number of pixels, ``(count, (r, g, b))``: what
    :func:`build_palette` needs of a sample frame, a few thousand pairs where the frame is
    millions of bytes.

    >>> color_counts(Image.new("RGB", (3, 2), (9, 8, 7)))
    [(6, (9, 8, 7))]
    """
    rgb = image if image.mode == "RGB" else image.convert("RGB")  # no copy of a frame
    return rgb.getcolors(rgb.width * rgb.height) or []


def build_palette(
    samples: Iterable[Sequence[tuple[int, RGB]]], theme: Theme, extra: Sequence[RGB] = ()
) -> bytes:
    """One palette for the whole GIF, ``GIF_COLORS`` RGB entries, from the
    :func:`color_counts` of a sample of frames.

    The theme's colours, the ``extra`` colours (a tree's effector colours) and the samples'
    most common exact colours come first, so flat fills map to themselves with no dithering;
    the rest of the entries adapt (median cut) to the remaining pixels: anti-aliased edges, the
    trail's fade, text. ``samples`` is read once, one frame's counts at a time, so a caller can
    draw each sample, count it and let it go before drawing the next.
    """
    totals: Counter[RGB] = Counter()
    for counts in samples:
        totals.update({c: n for n, c in counts})
    counts = sorted(((n, rgb) for rgb, n in totals.items()), key=lambda item: (-item[0], item[1]))
    frequent = [rgb for _, rgb in counts[:GIF_FREQUENT]]
    fixed = list(dict.fromkeys(theme.colors() + list(extra) + frequent))
    fixed = fixed[:GIF_COLORS]
    taken = set(fixed)
    rest = [(n, rgb) for n, rgb in counts if rgb not in taken]
    room = GIF_COLORS - len(fixed)
    if len(rest) <= room:
        adaptive = [rgb for _, rgb in rest]
    else:
        weights = np.array([n for n, _ in rest])
        pixels = np.repeat(np.array([rgb for _, rgb in rest], dtype=np.uint8), weights, axis=0)
        strip = Image.fromarray(pixels.reshape(1, -1, 3))
        quantized = strip.quantize(room, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
        flat = quantized.getpalette() or []
        adaptive = [tuple(flat[i : i + 3]) for i in range(0, 3 * room, 3)]
    colors = list(dict.fromkeys(fixed + adaptive))
    # Pad by repeating the background: duplicates are harmless, the quantizer picks the first.
    colors += [colors[0]] * (GIF_COLORS - len(colors))
    return bytes(c for rgb in colors[:GIF_COLORS] for c in rgb)


class _Quantizer:
    """Maps RGB frames to palette indices: a colour in the palette to itself, any other to the
    nearest entry, with no dithering.

    Pillow's own palette mapping looks colours up on a coarse colour cube, so even a flat
    background can land on a neighbouring entry; this looks up exact 24-bit colours instead, in
    a table filled as colours first appear (frames reuse almost all of them).
    """

    def __init__(self, palette: bytes) -> None:
        self.colors = np.frombuffer(palette, dtype=np.uint8).reshape(-1, 3).astype(np.int32)
        # Index + 1 per colour, 0 for colours not looked up yet: a zeroed table is memory the
        # system hands out untouched, so only the pages of colours that occur take up room.
        self.table = _zeroed(1 << 24)

    def indices(self, image: Image.Image) -> bytes:
        # RGBX is Pillow's own layout: one little-endian uint32 per pixel, R in the low byte,
        # X masked off.
        rgb = image if image.mode == "RGB" else image.convert("RGB")  # no copy of a frame
        rgbx = rgb.tobytes("raw", "RGBX")
        packed = np.frombuffer(rgbx, dtype="<u4") & 0xFFFFFF
        found = self.table[packed]
        missing = found == 0
        if missing.any():
            new = np.unique(packed[missing])
            self.table[new] = self._nearest(new) + 1
            found = self.table[packed]
        found -= 1
        return found.tobytes()

    def _nearest(self, packed: np.ndarray) -> np.ndarray:
        # Weighted RGB distance (2, 4, 3): a cheap stand-in for perceived difference. At most
        # (2 + 4 + 3) * 255^2, so int32 holds it exactly.
        weights = np.array([2, 4, 3], dtype=np.int32)
        out = np.empty(len(packed), dtype=np.uint8)
        for start in range(0, len(packed), NEAREST_BLOCK):
            block = packed[start : start + NEAREST_BLOCK].astype(np.int32)
            rgb = np.stack([block & 255, block >> 8 & 255, block >> 16], axis=1)
            diff = rgb[:, None, :] - self.colors[None, :, :]
            diff *= diff
            diff *= weights
            out[start : start + NEAREST_BLOCK] = np.argmin(diff.sum(axis=2), axis=1)
        return out


def _zeroed(size: int) -> np.ndarray:
    """``size`` zero bytes, (size,) uint8, of which only the 4 KB pages written to take memory.

    Not ``np.zeros``: NumPy asks Linux for 2 MB pages on arrays of 4 MB and more, and a 2 MB
    page is taken whole at its first write, so the colour table's scattered colours took up
    14 of its 16 MB (555 pages of 4 KB, 2 MB, for all of a 960x540 ``06_circle``).
    """
    if not hasattr(mmap, "MAP_PRIVATE"):  # Windows: no flags, and no 2 MB pages unasked
        return np.zeros(size, dtype=np.uint8)
    memory = mmap.mmap(-1, size, flags=mmap.MAP_PRIVATE)  # shared memory is taken when read
    if hasattr(mmap, "MADV_NOHUGEPAGE"):
        memory.madvise(mmap.MADV_NOHUGEPAGE)  # where 2 MB pages are the system's default
    return np.frombuffer(memory, dtype=np.uint8)


@lru_cache(maxsize=1)
def quantizer(palette: bytes) -> _Quantizer:
    """The quantizer for ``palette``: one per palette and process, so its table fills once per
    export (in each worker too). Its table takes a few MB: call ``quantizer.cache_clear()`` when
    the export is done."""
    return _Quantizer(palette)


def gif_durations(frames: int, fps: float, stride: int) -> list[int]:
    """Per-frame GIF delays in ms, each a whole number of centiseconds (the GIF unit).

    Each delay is the gap between rounded frame times, so delays alternate (30 fps: 30, 40,
    30 ms ...) and the total never drifts from the run's length by more than half a centisecond.
    ``stride`` is how many run frames each GIF frame stands for.

    >>> gif_durations(3, 30.0, 1), gif_durations(3, 60.0, 2)
    ([30, 40, 30], [30, 40, 30])
    """
    edges = [math.floor(k * stride * 100 / fps + 0.5) for k in range(frames + 1)]
    return [10 * (b - a) for a, b in zip(edges[:-1], edges[1:], strict=True)]


class GifWriter:
    """Streams a looping GIF: one global palette, and each frame after the first stored as the
    rectangle that changed, unchanged pixels transparent (they compress to almost nothing)."""

    def __init__(self, fp: IO[bytes], size: tuple[int, int], palette: bytes) -> None:
        self.fp = fp
        self.size = size
        self.palette = palette + palette[:3]  # the transparent slot; its colour never shows
        self.previous: np.ndarray | None = None
        width, height = size
        # Logical screen: 0xF7 = global colour table of 256 entries, 8 bits per primary.
        fp.write(b"GIF89a" + struct.pack("<HHBBB", width, height, 0xF7, 0, 0) + self.palette)
        # NETSCAPE2.0 application extension: loop count 0 = forever.
        fp.write(b"!\xff\x0bNETSCAPE2.0\x03\x01" + struct.pack("<H", 0) + b"\x00")

    def add(self, indices: bytes, duration_ms: int) -> None:
        """Append a frame given as palette indices, one byte per pixel, row by row."""
        width, height = self.size
        frame = np.frombuffer(indices, dtype=np.uint8).reshape(height, width)
        # Disposal 1 (leave in place): each frame draws over the previous one.
        params: dict[str, int] = {"duration": duration_ms, "disposal": 1}
        if self.previous is None:
            region, offset = frame, (0, 0)
        else:
            changed = frame != self.previous
            rows, cols = np.flatnonzero(changed.any(axis=1)), np.flatnonzero(changed.any(axis=0))
            if rows.size == 0:
                # An unchanged frame still takes its time: one transparent pixel.
                region, offset = np.full((1, 1), GIF_TRANSPARENT, dtype=np.uint8), (0, 0)
            else:
                y0, y1, x0, x1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
                region = frame[y0:y1, x0:x1].copy()
                region[~changed[y0:y1, x0:x1]] = GIF_TRANSPARENT
                offset = (int(x0), int(y0))
            params["transparency"] = GIF_TRANSPARENT
        image = Image.frombytes("P", (region.shape[1], region.shape[0]), region.tobytes())
        image.putpalette(self.palette)
        for block in GifImagePlugin.getdata(image, offset, **params):
            self.fp.write(block)
        self.previous = frame

    def close(self) -> None:
        """Write the trailer; the GIF is complete after this."""
        self.fp.write(b";")


# -- APNG ----------------------------------------------------------------------------------------


class ApngWriter:
    """Streams an APNG from already-encoded PNG frames: each frame's image data is reused as is
    (IDAT for the first frame, fdAT for the others), so nothing is encoded twice."""

    def __init__(self, fp: IO[bytes], frames: int, size: tuple[int, int], fps: float) -> None:
        self.fp = fp
        self.frames = frames
        self.size = size
        delay = 1 / Fraction(fps).limit_denominator(1000)
        if delay.numerator > 0xFFFF or delay.denominator > 0xFFFF:
            raise ValueError(f"fps {fps} cannot be written as an APNG frame delay")
        self.delay = delay
        self.sequence = 0
        self.written = 0
        fp.write(PNG_SIGNATURE)

    def add(self, png: bytes) -> None:
        """Append a frame given as a complete PNG file of ``size``."""
        width, height = self.size
        # fcTL: sequence, size, offset 0,0, delay, dispose op 0 (none), blend op 0 (source).
        control = struct.pack(
            ">IIIIIHHBB",
            self.sequence,
            width,
            height,
            0,
            0,
            self.delay.numerator,
            self.delay.denominator,
            0,
            0,
        )
        self.sequence += 1
        first = self.written == 0
        control_written = False
        for kind, body in png_chunks(png):
            if kind == b"IEND":
                break
            if kind == b"IDAT":
                if not control_written:
                    self.fp.write(png_chunk(b"fcTL", control))
                    control_written = True
                if first:
                    self.fp.write(png_chunk(b"IDAT", body))
                else:
                    self.fp.write(png_chunk(b"fdAT", struct.pack(">I", self.sequence) + body))
                    self.sequence += 1
            elif first:
                self.fp.write(png_chunk(kind, body))
                if kind == b"IHDR":
                    # acTL: frame count, plays 0 = loop forever; it must precede any IDAT.
                    self.fp.write(png_chunk(b"acTL", struct.pack(">II", self.frames, 0)))
        self.written += 1

    def close(self) -> None:
        """Write the trailer, after checking that every announced frame was added."""
        if self.written != self.frames:
            raise ValueError(f"APNG announced {self.frames} frames but got {self.written}")
        self.fp.write(png_chunk(b"IEND", b""))
