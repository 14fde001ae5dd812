"""MP4 export: H.264 in yuv420p at the run's frame rate, streamed, atomic, even-sided."""

from __future__ import annotations

import importlib.util
import re

import numpy as np
import pytest

pytest.importorskip("imageio_ffmpeg", reason="MP4 export needs the video extra: ikgame[video]")

from ikgame.render import video  # noqa: E402
from ikgame.render.export import export_run  # noqa: E402
from ikgame.render.video import INSTALL_VIDEO, Mp4Writer, check_video, even_size  # noqa: E402


def test_the_writer_streams_frames_into_an_h264_yuv420p_file(tmp_path, probe_video):
    path = tmp_path / "clip.mp4"
    with Mp4Writer(path, (64, 36), 24.0) as writer:
        for shade in range(10):
            writer.add(bytes([shade * 20, 100, 200]) * (64 * 36))
    assert probe_video(path) == {
        "codec": "h264",
        "pix_fmt": "yuv420p",
        "size": (64, 36),
        "fps": 24.0,
        "frames": 10,
    }
    assert [p.name for p in tmp_path.iterdir()] == ["clip.mp4"]


def test_a_failure_while_writing_leaves_no_file_behind(tmp_path):
    path = tmp_path / "clip.mp4"
    with pytest.raises(RuntimeError, match="boom"), Mp4Writer(path, (32, 16), 30.0) as writer:
        writer.add(bytes(32 * 16 * 3))
        raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []


def test_frames_of_the_wrong_size_and_odd_sides_are_refused(tmp_path):
    with pytest.raises(ValueError, match="even sides"):
        Mp4Writer(tmp_path / "odd.mp4", (33, 16), 30.0)
    with Mp4Writer(tmp_path / "ok.mp4", (32, 16), 30.0) as writer:
        with pytest.raises(ValueError, match="takes 1536 bytes, got 3"):
            writer.add(b"abc")
        writer.add(bytes(32 * 16 * 3))
    assert even_size((33, 17)) == (32, 16) and even_size((32, 16)) == (32, 16)


def test_without_the_extra_the_message_says_how_to_install_it(monkeypatch):
    real = importlib.util.find_spec
    monkeypatch.setattr(
        video.importlib.util,
        "find_spec",
        lambda name, *a: None if name == "imageio_ffmpeg" else real(name, *a),
    )
    with pytest.raises(ValueError, match=re.escape(INSTALL_VIDEO)):
        check_video()


def test_export_writes_every_frame_of_an_odd_sized_run_cropped_to_even(tmp_path, run, probe_video):
    scene, snaps = run(count=7, fps=25.0)
    written = export_run(
        tmp_path, scene, snaps, size=(81, 45), frames=False, gif=False, mp4=True, progress=False
    )
    assert tmp_path / "run.mp4" in written
    info = probe_video(tmp_path / "run.mp4")
    assert info["size"] == (80, 44) and info["frames"] == 7 and info["fps"] == 25.0
    # The picture is the frames': the last frame's mean colour survives the encoding.
    import imageio_ffmpeg
    from PIL import Image

    reader = imageio_ffmpeg.read_frames(str(tmp_path / "run.mp4"))
    meta = next(reader)
    decoded = [np.frombuffer(f, dtype=np.uint8) for f in reader]
    assert meta["size"] == (80, 44) and len(decoded) == 7
    export_run(tmp_path / "png", scene, snaps, size=(81, 45), gif=False, progress=False)
    last = np.asarray(Image.open(tmp_path / "png/frames/000006.png").convert("RGB"))[:44, :80]
    assert abs(decoded[-1].mean() - last.mean()) < 3.0
