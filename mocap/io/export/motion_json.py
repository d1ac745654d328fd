"""The motion file (`mocap-motion` JSON, CONTRACT.md): written here, read here."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from mocap.body import JOINTS
from mocap.errors import MocapError
from mocap.io.export.atomic import write_export

FORMAT, VERSION = "mocap-motion", 1


def motion_dict(video: dict, frames: list[dict]) -> dict:
    """The motion file's content; frames hold numpy arrays or lists."""
    return {"format": FORMAT, "version": VERSION, "video": video, "joints": list(JOINTS),
            "frames": [_frame_entry(f) for f in frames]}


def _frame_entry(frame: dict) -> dict:
    entry = {}
    for key, value in frame.items():
        if isinstance(value, np.ndarray):
            value = np.round(value.astype(float), 3).tolist()
        elif isinstance(value, (np.floating, float)):
            value = round(float(value), 4)
        entry[key] = value
    return entry


def motion_text(video: dict, frames: list[dict]) -> str:
    """The motion file's text."""
    return json.dumps(motion_dict(video, frames), indent=1) + "\n"


def write_motion(path: str | os.PathLike, video: dict, frames: list[dict]) -> Path:
    """Write the motion file atomically."""
    return write_export(path, motion_text(video, frames).encode(), "motion")


def read_motion(path: str | os.PathLike) -> dict:
    """Read and check a motion file; joints2d/joints3d come back as numpy arrays."""
    try:
        data = json.loads(Path(path).read_text())
    except FileNotFoundError:
        raise MocapError(f"{path}: no such motion file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise MocapError(f"{path}: not a motion file ({exc})") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT or data.get("version") != VERSION:
        raise MocapError(f"{path}: not a {FORMAT} version {VERSION} file")
    for frame in data.get("frames", []):
        for key in ("joints2d", "joints3d"):
            if key in frame:
                frame[key] = np.asarray(frame[key], dtype=float)
    return data
