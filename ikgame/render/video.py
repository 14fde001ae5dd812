"""MP4 export: H.264 in yuv420p, the pixel format every browser and phone plays, through
imageio-ffmpeg (the optional ``video`` extra, which ships its own ffmpeg binary).

Frames are streamed to the encoder one at a time through a pipe, so a long run never sits in
memory. yuv420p stores colour at half resolution, so both sides of the picture must be even: an
odd width or height loses its last column or row. The file is encoded under a temporary name in
its folder and renamed into place once ffmpeg has finished, like every file ikgame writes.
"""

from __future__ import annotations

import importlib.util
import os
import uuid
from pathlib import Path
from types import TracebackType
from typing import Final

__all__ = ["INSTALL_VIDEO", "Mp4Writer", "check_video", "even_size"]

INSTALL_VIDEO: Final = "python -m pip install 'ikgame[video]'"
"""The command that installs what MP4 export needs."""
QUALITY: Final = 6  # imageio-ffmpeg's 1..10 scale; 6 is x264's CRF 20, crisp on flat colours


def check_video() -> None:
    """Raise ``ValueError`` with the install command when MP4 export cannot run here.

    >>> check_video() is None  # imageio-ffmpeg is installed with the test extra
    True
    """
    if importlib.util.find_spec("imageio_ffmpeg") is None:
        raise ValueError(f"MP4 export needs the video extra (imageio-ffmpeg): {INSTALL_VIDEO}")
    import imageio_ffmpeg

    try:
        imageio_ffmpeg.get_ffmpeg_exe()
    except RuntimeError as exc:
        raise ValueError(
            f"imageio-ffmpeg has no ffmpeg binary here ({exc}); {INSTALL_VIDEO}"
        ) from None


def even_size(size: tuple[int, int]) -> tuple[int, int]:
    """The video's size for frames of ``size``: each odd side one pixel shorter.

    >>> even_size((961, 540))
    (960, 540)
    """
    width, height = size
    return width - width % 2, height - height % 2


class Mp4Writer:
    """Write an MP4 file frame by frame: ``add`` each frame's RGB bytes (of the even size, see
    :func:`even_size`), ``close`` to finish; used as a context manager, a failure leaves no file.

    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "run.mp4"
    >>> with Mp4Writer(path, (32, 16), 30.0) as video:
    ...     for shade in range(3):
    ...         video.add(bytes([shade * 100]) * (32 * 16 * 3))
    >>> path.stat().st_size > 0
    True
    """

    def __init__(self, path: str | os.PathLike[str], size: tuple[int, int], fps: float) -> None:
        check_video()
        import imageio_ffmpeg

        if size != even_size(size):
            raise ValueError(f"an MP4 frame needs even sides, got {size[0]}x{size[1]}")
        self.path = Path(path)
        self.size = size
        # ffmpeg picks the container from the name, so the temporary name ends in .mp4 too.
        self._temp = self.path.with_name(f".{self.path.name}.{uuid.uuid4().hex[:12]}.tmp.mp4")
        self._frames = 0
        self._encoder = imageio_ffmpeg.write_frames(
            str(self._temp),
            size,
            fps=fps,
            pix_fmt_out="yuv420p",
            quality=QUALITY,
            macro_block_size=2,
            ffmpeg_log_level="error",
            # The index first, so a browser starts playing before the whole file has arrived.
            output_params=["-movflags", "+faststart"],
        )
        self._encoder.send(None)

    def add(self, rgb: bytes) -> None:
        """One frame: ``width * height * 3`` bytes, rows from the top."""
        expected = self.size[0] * self.size[1] * 3
        if len(rgb) != expected:
            raise ValueError(f"a frame of {self.size} takes {expected} bytes, got {len(rgb)}")
        self._encoder.send(rgb)
        self._frames += 1

    def close(self) -> Path:
        """Finish the file and move it into place; returns its path."""
        self._encoder.close()
        if not self._frames or not self._temp.is_file() or not self._temp.stat().st_size:
            self._temp.unlink(missing_ok=True)
            raise RuntimeError(f"ffmpeg wrote no video for {self.path.name}")
        os.replace(self._temp, self.path)
        return self.path

    def __enter__(self) -> Mp4Writer:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if kind is None:
            self.close()
        else:
            self._encoder.close()
            self._temp.unlink(missing_ok=True)
