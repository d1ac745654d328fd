"""The export registry: every file format a motion is written as, in one table that
the command line (`mocap fit --out/--bvh/--glb/--csv/--html`) and the app (its
download buttons) both read, so that both offer every format."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from mocap.errors import MocapError
from mocap.io.export.atomic import write_export

if TYPE_CHECKING:
    from mocap.lift.motion import Motion


@dataclass(frozen=True, eq=False)
class Clip:
    """What every format is made from: the clip's name (the video's stem), the motion
    file's ``video`` entry and frames (CONTRACT.md), the motion, and the motion file's
    optional top-level fields (``extra``, e.g. CONTRACT.md's "masks")."""

    name: str
    video: dict
    frames: list[dict]
    motion: "Motion"
    extra: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Format:
    """A file format: its key (the command line's option, the app's), the app's
    button label, the file name's ending, what it holds, and its bytes of a clip."""

    key: str
    label: str
    suffix: str
    holds: str
    render: Callable[[Clip], bytes]


# Each format's module is imported when it is first written: the command line reads
# the table for its options, and its --help stays instant without numpy and scipy.

def _json(clip: Clip) -> bytes:
    from mocap.io.export.motion_json import motion_text
    return motion_text(clip.video, clip.frames, clip.extra).encode()


def _bvh(clip: Clip) -> bytes:
    from mocap.io.export.bvh import bvh_text
    return bvh_text(clip.motion).encode()


def _glb(clip: Clip) -> bytes:
    from mocap.io.export.glb import glb_bytes
    return glb_bytes(clip.motion)


def _csv(clip: Clip) -> bytes:
    from mocap.io.export.csv import csv_text
    return csv_text(clip.motion).encode()


def _html(clip: Clip) -> bytes:
    from mocap.io.export.html import motion_html
    return motion_html(clip.motion, clip.name).encode("utf-8")


FORMATS: dict[str, Format] = {f.key: f for f in (
    Format("json", "motion JSON", ".motion.json", "the motion file (CONTRACT.md)", _json),
    Format("bvh", "BVH", ".bvh", "the animation as BVH", _bvh),
    Format("glb", "GLB", ".glb", "the animated cylinder body as GLB", _glb),
    Format("csv", "CSV", ".csv", "the world joint positions as CSV", _csv),
    Format("html", "HTML page", ".html", "the playback page (one file, opens without a server)",
           _html),
)}


def export_format(key: str) -> Format:
    """The format of ``key``; an unknown key is a MocapError naming the known ones."""
    if key not in FORMATS:
        raise MocapError(f"no export format {key!r} (known: {', '.join(FORMATS)})")
    return FORMATS[key]


def export_file(key: str, clip: Clip) -> tuple[str, bytes]:
    """(file name, content) of a clip in a format."""
    fmt = export_format(key)
    return clip.name + fmt.suffix, fmt.render(clip)


def write_format(key: str, path: str | os.PathLike, clip: Clip) -> Path:
    """Write a clip in a format, atomically; an unwritable path is a MocapError."""
    fmt = export_format(key)
    return write_export(path, fmt.render(clip), fmt.label)
