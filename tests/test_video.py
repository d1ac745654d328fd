"""Reading videos: metadata, streaming, random access, downscaling, and every kind of
bad input refused with a one-line MocapError that names the file and the problem."""

from __future__ import annotations

import types

import cv2
import numpy as np
import pytest
from helpers import png_avi, text_mp4

from mocap.errors import MocapError, MocapWarning
from mocap.io.video import iter_frames, open_video, processing_scale, read_frame, sample_frames

SIZE = (96, 64)  # width, height


def write_clip(
    path, n: int = 20, fourcc: str = "MJPG", fps: float = 12.5, size: tuple[int, int] = SIZE, texture: int = 12
) -> str:
    """A clip whose frame i has mean grey level 20 + 7 * i (frames identify
    themselves) plus a fixed noise texture of +-`texture` (which makes frames big)."""
    shape = (size[1], size[0], 3)
    texture = np.random.default_rng(0).integers(-texture, texture + 1, shape, np.int16)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), fps, size)
    assert writer.isOpened()
    for i in range(n):
        writer.write((20 + 7 * i + texture).astype(np.uint8))
    writer.release()
    return str(path)


def level(frame: np.ndarray) -> int:
    """The index a frame of write_clip shows."""
    return int(round((frame.mean() - 20) / 7))


@pytest.mark.parametrize("name, fourcc", [("clip.avi", "MJPG"), ("clip.mp4", "mp4v")])
def test_metadata_of_a_written_clip(tmp_path, name, fourcc):
    info = open_video(write_clip(tmp_path / name, fourcc=fourcc))
    assert (info.width, info.height, info.frame_count) == (96, 64, 20)
    assert info.fps == pytest.approx(12.5)


@pytest.mark.parametrize("name, fourcc", [("clip.avi", "MJPG"), ("clip.mp4", "mp4v")])
def test_streaming_and_random_access_agree(tmp_path, name, fourcc):
    info = open_video(write_clip(tmp_path / name, n=24, fourcc=fourcc))
    stream = iter_frames(info)
    assert isinstance(stream, types.GeneratorType)
    frames = dict(stream)
    assert [level(frames[i]) for i in range(24)] == list(range(24))
    for i in (23, 0, 17, 5, 6, 22):  # backwards and forwards
        assert np.array_equal(read_frame(info, i), frames[i])
    assert [i for i, _ in iter_frames(info, start=3, stop=20, step=4)] == [3, 7, 11, 15, 19]
    assert [i for i, _ in iter_frames(info.path, start=20, stop=99)] == [20, 21, 22, 23]
    assert [i for i, f in sample_frames(info, 5) if level(f) == i] == [0, 6, 12, 17, 23]


def test_bad_ranges_are_refused(tmp_path):
    info = open_video(write_clip(tmp_path / "clip.avi"))
    with pytest.raises(MocapError, match="out of range"):
        read_frame(info, 20)
    with pytest.raises(MocapError, match="bad frame range"):
        list(iter_frames(info, step=0))


def test_4k_clip_is_read_downscaled(tmp_path):
    info = open_video(write_clip(tmp_path / "big.mp4", n=3, fourcc="mp4v", size=(3840, 2160), texture=0))
    assert (info.width, info.height, info.frame_count) == (3840, 2160, 3)
    scale = processing_scale(info)
    assert scale == pytest.approx(1 / 3)
    frames = [f for _, f in iter_frames(info, scale=scale)]
    assert [f.shape for f in frames] == [(720, 1280, 3)] * 3
    assert [level(f) for f in frames] == [0, 1, 2]
    assert read_frame(info, 2, scale=scale).shape == (720, 1280, 3)
    assert processing_scale(open_video(write_clip(tmp_path / "small.avi"))) == 1.0


def test_truncated_avi_reads_the_frames_that_decode(tmp_path):
    data = open(write_clip(tmp_path / "full.avi", n=30), "rb").read()
    cut = tmp_path / "cut.avi"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.warns(MocapWarning) as said:
        info = open_video(cut)
    assert 5 <= info.frame_count < 30
    assert [str(w.message) for w in said] == [
        f"{cut}: only {info.frame_count} of the 30 frames the file announces decode (truncated or damaged); using those"
    ]
    frames = [f for _, f in iter_frames(info)]
    assert len(frames) == info.frame_count
    assert [level(f) for f in frames] == list(range(info.frame_count))


def _zero_frame_avi(tmp_path):
    return write_clip(tmp_path / "zero.avi", n=0)


def _truncated_mp4(tmp_path):
    data = open(write_clip(tmp_path / "full.mp4", fourcc="mp4v"), "rb").read()
    path = tmp_path / "cut.mp4"
    path.write_bytes(data[: len(data) // 2])  # the index (moov) is at the end: lost
    return path


def _unknown_codec_avi(tmp_path):
    data = open(write_clip(tmp_path / "good.avi"), "rb").read()
    path = tmp_path / "odd.avi"
    path.write_bytes(data.replace(b"MJPG", b"QZQZ"))
    return path


def _empty_file(tmp_path):
    path = tmp_path / "empty.mp4"
    path.write_bytes(b"")
    return path


@pytest.mark.parametrize(
    "make, problem",
    [
        (lambda p: p / "missing.mp4", "no such file"),
        (lambda p: p, "is a directory"),
        (_empty_file, "empty"),
        (text_mp4, "not a video file"),
        (png_avi, "still image"),
        (_zero_frame_avi, "no frames"),
        (_truncated_mp4, "truncated"),
        (_unknown_codec_avi, "codec 'QZQZ'"),
    ],
)
def test_bad_inputs_are_refused_with_one_line(tmp_path, make, problem):
    path = str(make(tmp_path))
    with pytest.raises(MocapError) as caught:
        open_video(path)
    message = str(caught.value)
    assert problem in message and path in message and "\n" not in message
    with pytest.raises(MocapError):
        list(iter_frames(path))
