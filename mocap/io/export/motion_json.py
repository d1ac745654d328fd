"""The motion file (`mocap-motion` JSON, CONTRACT.md): written here, read here."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from mocap.body import JOINTS
from mocap.errors import MocapError
from mocap.io.export.atomic import write_export
from mocap.io.jsoncheck import Bad, describe, expect, is_number

FORMAT, VERSION = "mocap-motion", 1
_METRES = ("joints3d", "root")


def motion_dict(video: dict, frames: list[dict], extra: dict | None = None) -> dict:
    """The motion file's content; frames hold numpy arrays or lists; ``extra`` adds
    optional top-level fields (CONTRACT.md: "masks")."""
    return {
        "format": FORMAT,
        "version": VERSION,
        "video": video,
        "joints": list(JOINTS),
        **(extra or {}),
        "frames": [_frame_entry(f) for f in frames],
    }


def _frame_entry(frame: dict) -> dict:
    entry = {}
    for key, value in frame.items():
        if isinstance(value, np.ndarray):
            # metres to 0.1 mm (the exports are checked against them to 1 mm), pixels to 0.001
            value = np.round(value.astype(float), 4 if key in _METRES else 3).tolist()
        elif isinstance(value, (np.floating, float)):
            value = round(float(value), 4)
        entry[key] = value
    return entry


def motion_text(video: dict, frames: list[dict], extra: dict | None = None) -> str:
    """The motion file's text."""
    return json.dumps(motion_dict(video, frames, extra), indent=1) + "\n"


def write_motion(path: str | os.PathLike, video: dict, frames: list[dict], extra: dict | None = None) -> Path:
    """Write the motion file atomically."""
    return write_export(path, motion_text(video, frames, extra).encode(), "motion")


def read_motion(path: str | os.PathLike) -> dict:
    """Read and check a motion file; joints2d/joints3d/root/confidence come back as
    numpy arrays. Anything its readers would trip on is one MocapError naming the place."""
    try:
        data = json.loads(Path(path).read_text())
    except FileNotFoundError:
        raise MocapError(f"{path}: no such motion file") from None
    except (OSError, UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise MocapError(f"{path}: not a motion file ({exc})") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT or data.get("version") != VERSION:
        raise MocapError(f"{path}: not a {FORMAT} version {VERSION} file")
    try:
        _check_video(data.get("video", {}))
        for i, frame in enumerate(expect(data.get("frames", []), list, "frames", "a list of frames")):
            _check_frame(frame, f"frames[{i}]")
    except Bad as exc:
        raise MocapError(f"{path}: {exc}") from None
    return data


# per-frame arrays: their shape (16: one per joint, canonical order)
_ARRAYS = {"joints2d": (len(JOINTS), 2), "joints3d": (len(JOINTS), 3), "root": (3,), "confidence": (len(JOINTS),)}


def _check_video(video) -> None:
    expect(video, dict, "video", "an object")
    for key in ("width", "height", "frame_count"):
        if video.get(key) is not None:
            expect(video[key], int, f"video.{key}", "a whole number")
    if video.get("fps") is not None and not (is_number(video["fps"]) and video["fps"] >= 0):
        raise Bad("video.fps", f"expected frames per second, got {describe(video['fps'])}")


def _check_frame(frame, place: str) -> None:
    """Check one frame entry and turn its arrays into numpy arrays, in place."""
    expect(frame, dict, place, "an object")
    if "index" in frame:
        expect(frame["index"], int, f"{place}.index", "a frame index")
    if frame.get("score") is not None and not is_number(frame["score"]):
        raise Bad(f"{place}.score", f"expected a number, got {describe(frame['score'])}")
    for key, shape in _ARRAYS.items():
        if key in frame:
            frame[key] = np.asarray(_numbers(frame[key], shape, f"{place}.{key}"), dtype=float)


def _numbers(value, shape: tuple[int, ...], place: str):
    """value when it is nested lists of numbers of that shape, else Bad."""
    what = f"{shape[0]} numbers" if len(shape) == 1 else f"{shape[0]} joints"
    if not isinstance(value, list) or len(value) != shape[0]:
        raise Bad(place, f"expected {what}, got {describe(value)}")
    for i, item in enumerate(value):
        if len(shape) > 1:
            _numbers(item, shape[1:], f"{place}[{i}]")
        elif not is_number(item):
            raise Bad(f"{place}[{i}]", f"expected a number, got {describe(item)}")
    return value
