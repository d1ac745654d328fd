"""Reading video frames and metadata with OpenCV (FFmpeg backend), and writing videos.

Frames are BGR uint8, streamed one at a time; every bad input is a one-line ``MocapError`` naming the
file. A video is the complete frames that decode (``open_video`` counts them). With ``scale`` (see
``processing_scale``) frames come area-downscaled and results are in downscaled pixels: divide
coordinates by the scale for the original frame's (CONTRACT.md)."""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from mocap.errors import MocapError, MocapWarning
from mocap.io.fileio import check_writable

DEFAULT_FPS = 25.0  # used when the container does not state a usable frame rate
_MAX_GRAB_GAP = 32  # forward jumps up to this many frames decode instead of seeking
_FOURCC = {".mp4": "mp4v", ".avi": "MJPG"}  # the codec `write_video` uses for each suffix

_CONTAINERS = (  # (offset, magic bytes, name) for the error message of unopenable files
    (8, b"AVI ", "AVI"),
    (4, b"ftyp", "MP4/MOV"),
    (0, b"\x1aE\xdf\xa3", "Matroska/WebM"),
    (0, b"OggS", "Ogg"),
    (0, b"FLV", "FLV"),
)


@dataclass(frozen=True)
class VideoInfo:
    """A video that opened and decodes: `frame_count` frames of `width` x `height`
    pixels at `fps` frames per second (DEFAULT_FPS when the file states none)."""

    path: str
    width: int
    height: int
    fps: float
    frame_count: int


def open_video(path: str | os.PathLike) -> VideoInfo:
    """Open `path`, check that it is a video with decodable frames, and describe it."""
    path = os.fspath(path)
    _check_file(path)
    cap = _capture(path)
    try:
        ok, frame = cap.read()
        if not ok:
            raise MocapError(_no_frame_message(path, cap))
        fps = cap.get(cv2.CAP_PROP_FPS)
        count = _count_frames(cap, path)
    finally:
        cap.release()
    fps = fps if math.isfinite(fps) and 0 < fps <= 1000 else DEFAULT_FPS
    return VideoInfo(path, frame.shape[1], frame.shape[0], float(fps), count)


def processing_scale(info: VideoInfo, max_side: int = 1280) -> float:
    """The factor (<= 1) that brings the longer side of the frames to `max_side`."""
    return min(1.0, max_side / max(info.width, info.height))


def iter_frames(
    source: VideoInfo | str | os.PathLike, start: int = 0, stop: int | None = None, step: int = 1, scale: float = 1.0
) -> Iterator[tuple[int, np.ndarray]]:
    """Yield ``(index, frame)`` for start, start+step, ... before ``stop`` (default and limit: the frame
    count), decoded one by one, downscaled (area averaging) when ``scale`` < 1."""
    info = source if isinstance(source, VideoInfo) else open_video(source)
    stop = info.frame_count if stop is None else min(stop, info.frame_count)
    if start < 0 or step < 1:
        raise MocapError(f"{info.path}: bad frame range start={start} step={step}")
    reader = _Reader(info)
    try:
        for index in range(start, stop, step):
            yield index, _resize(reader.read(index), scale)
    finally:
        reader.close()


def rescaled(points: np.ndarray, factor: float) -> np.ndarray:
    """Pixel coordinates (..., 2) in a frame ``factor`` times as large: pixel centres stay pixel centres (a
    point at 0 is the first pixel's centre, whose left edge is -0.5)."""
    return (np.asarray(points, float) + 0.5) * factor - 0.5


def read_frame(info: VideoInfo, index: int, scale: float = 1.0) -> np.ndarray:
    """Frame `index` (random access: seek, or decode forward when seeking is unreliable)."""
    if not 0 <= index < info.frame_count:
        raise MocapError(f"{info.path}: frame {index} is out of range (the video has {info.frame_count} frames)")
    reader = _Reader(info)
    try:
        return _resize(reader.read(index), scale)
    finally:
        reader.close()


def sample_frames(info: VideoInfo, n: int, scale: float = 1.0) -> list[tuple[int, np.ndarray]]:
    """About `n` `(index, frame)` pairs spread evenly over the whole clip, first and last
    included (all frames when the clip is shorter): the input of background estimation."""
    indices = np.unique(np.linspace(0, info.frame_count - 1, max(n, 1)).round().astype(int))
    reader = _Reader(info)
    try:
        return [(int(i), _resize(reader.read(int(i)), scale)) for i in indices]
    finally:
        reader.close()


class _Reader:
    """An open capture that knows the index of the frame it decodes next."""

    def __init__(self, info: VideoInfo):
        self.info = info
        self.cap = _capture(info.path)
        self.next = 0

    def read(self, index: int) -> np.ndarray:
        self._go_to(index)
        ok, frame = self.cap.read()
        if not ok:
            raise MocapError(f"{self.info.path}: frame {index} could not be decoded")
        self.next = index + 1
        return frame

    def close(self) -> None:
        self.cap.release()

    def _go_to(self, index: int) -> None:
        """Seek when it pays and lands exactly; otherwise decode forward from frame 0."""
        if index < self.next or index - self.next > _MAX_GRAB_GAP:
            self.cap.set(cv2.CAP_PROP_POS_FRAMES, index)
            if self.cap.get(cv2.CAP_PROP_POS_FRAMES) == index:
                self.next = index
                return
            self.cap.release()
            self.cap = _capture(self.info.path)
            self.next = 0
        while self.next < index:
            if not self.cap.grab():
                raise MocapError(f"{self.info.path}: frame {self.next} could not be decoded")
            self.next += 1


def _capture(path: str) -> cv2.VideoCapture:
    cap = cv2.VideoCapture(path, cv2.CAP_FFMPEG)
    if not cap.isOpened():
        raise MocapError(_unopenable_message(path))
    return cap


def _check_file(path: str) -> None:
    """Refuse what is not a regular, non-empty, non-image file before FFmpeg sees it."""
    if not os.path.exists(path):
        raise MocapError(f"{path}: no such file")
    if os.path.isdir(path):
        raise MocapError(f"{path}: is a directory, not a video file")
    if not os.access(path, os.R_OK):
        raise MocapError(f"{path}: cannot be read (permission denied)")
    if os.path.getsize(path) == 0:
        raise MocapError(f"{path}: the file is empty, not a video")
    if cv2.haveImageReader(path):
        raise MocapError(f"{path}: is a still image, not a video")


def _count_frames(cap: cv2.VideoCapture, path: str) -> int:
    """Complete frames that decode: the container's count if its last frame decodes and nothing follows,
    else every frame grabbed and counted, less the cut-off last one (with a ``MocapWarning``) when fewer
    than announced."""
    claimed = cap.get(cv2.CAP_PROP_FRAME_COUNT)
    announced = 0 < claimed < 2**31
    if announced:
        last = int(claimed) - 1
        cap.set(cv2.CAP_PROP_POS_FRAMES, last)
        if cap.get(cv2.CAP_PROP_POS_FRAMES) == last and cap.grab() and not cap.grab():
            return last + 1
    cap.release()
    cap.open(path, cv2.CAP_FFMPEG)
    count = 0
    while cap.grab():
        count += 1
    if announced and count < claimed:
        count -= 1
    if count == 0:
        raise MocapError(f"{path}: no complete frame decodes (the file is truncated or damaged)")
    if announced and count < claimed:
        warnings.warn(
            f"{path}: only {count} of the {int(claimed)} frames the file announces "
            "decode (truncated or damaged); using those",
            MocapWarning,
            stacklevel=2,
        )
    return count


def _no_frame_message(path: str, cap: cv2.VideoCapture) -> str:
    if cap.get(cv2.CAP_PROP_FRAME_COUNT) == 0:
        return f"{path}: the video contains no frames"
    return f"{path}: no frame could be decoded (unsupported codec or damaged data)"


def _unopenable_message(path: str) -> str:
    """A message naming the container when recognisable: a damaged or unsupported video, or no video."""
    with open(path, "rb") as f:
        head = f.read(4096)
    for offset, magic, name in _CONTAINERS:
        if head[offset : offset + len(magic)] == magic:
            codec = _avi_codec(head) if name == "AVI" else ""
            return (
                f"{path}: cannot open this {name} video{codec}: unsupported codec, or the file is truncated or damaged"
            )
    return f"{path}: not a video file (unrecognised format)"


def _avi_codec(head: bytes) -> str:
    """' (codec XXXX)' from the video stream header of an AVI file, if found."""
    at = head.find(b"vids")
    if at < 0 or len(head) < at + 8:
        return ""
    return f" (codec {head[at + 4 : at + 8].decode('latin-1')!r})"


def _resize(frame: np.ndarray, scale: float) -> np.ndarray:
    if scale >= 1.0:
        return frame
    h, w = frame.shape[:2]
    size = (max(1, round(w * scale)), max(1, round(h * scale)))
    return cv2.resize(frame, size, interpolation=cv2.INTER_AREA)


def write_video(path: str | Path, frames, fps: float, size: tuple[int, int]) -> int:
    """Write BGR frames (mp4v for .mp4, MJPG for .avi); check the count by reopening."""
    path = Path(path)
    code = _FOURCC.get(path.suffix.lower())
    if code is None:
        raise MocapError(f"{path}: video must end in {' or '.join(_FOURCC)}")
    check_writable(path)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*code), float(fps), size)
    if not writer.isOpened():
        raise MocapError(f"{path}: OpenCV cannot write {code} video here")
    count = 0
    try:
        for frame in frames:
            writer.write(frame)
            count += 1
    finally:
        writer.release()
    cap = cv2.VideoCapture(str(path))
    found = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
    cap.release()
    if found != count:
        raise MocapError(f"{path}: wrote {count} frames but the file holds {found}")
    return count
