"""The export registry: one table of every format a motion is written as, read by the command line
(``mocap fit --out/--bvh/--glb/--csv/--html``) and the app's download buttons alike."""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from mocap.errors import MocapError
from mocap.io.export.atomic import write_export

if TYPE_CHECKING:
    from mocap.lift.motion import Motion


@dataclass(frozen=True, eq=False)
class Clip:
    """What every format is made from: the clip's name (the video's stem), the motion file's ``video``
    entry and frames, the motion, and the motion file's optional top-level fields (``extra``)."""

    name: str
    video: dict
    frames: list[dict]
    motion: "Motion"
    extra: dict = field(default_factory=dict)


def _always() -> bool:
    return True


@dataclass(frozen=True)
class Format:
    """A file format: its key (command line and app), button label, file ending, what it holds, its
    bytes of a clip, and whether this installation can write it (else ``needs`` says how)."""

    key: str
    label: str
    suffix: str
    holds: str
    render: Callable[[Clip], bytes]
    available: Callable[[], bool] = _always
    needs: str = ""  # how to make it available, where it is not


# Each format's module is imported when it is first written: the command line reads
# the table for its options, and its --help stays instant without numpy and scipy.


def _json(clip: Clip) -> bytes:
    from mocap.io.export.motion_json import motion_text

    # the exports' world origin (Motion.origin) with what the run adds (CONTRACT.md)
    extra = {"origin": [round(float(v), 4) for v in clip.motion.origin]} | clip.extra
    return motion_text(clip.video, clip.frames, extra).encode()


def _bvh(clip: Clip) -> bytes:
    from mocap.io.export.bvh import bvh_text

    return bvh_text(clip.motion).encode()


def _glb(clip: Clip) -> bytes:
    from mocap.io.export.glb import glb_bytes

    return glb_bytes(clip.motion)


def _fbx(clip: Clip) -> bytes:
    from mocap.io.export.fbx import fbx_bytes

    return fbx_bytes(clip.motion)


def _has_blender() -> bool:
    from mocap.io.export.fbx import has_blender

    return has_blender()


def _csv(clip: Clip) -> bytes:
    from mocap.io.export.csv import csv_text

    return csv_text(clip.motion, clip.frames).encode()


def _html(clip: Clip) -> bytes:
    from mocap.io.export.html import motion_html

    return motion_html(clip.motion, clip.name).encode("utf-8")


FORMATS: dict[str, Format] = {
    f.key: f
    for f in (
        Format("json", "motion JSON", ".motion.json", "the motion file (CONTRACT.md)", _json),
        Format("bvh", "BVH", ".bvh", "the animation as BVH", _bvh),
        Format("glb", "GLB", ".glb", "the animated cylinder body as GLB", _glb),
        Format(
            "fbx",
            "FBX",
            ".fbx",
            "the skinned character as FBX (needs the fbx extra: Blender)",
            _fbx,
            _has_blender,
            "FBX export needs Blender as a Python module: pip install 'mocap[fbx]' (Python 3.11)",
        ),
        Format("csv", "CSV", ".csv", "every frame's 2D and world joints, score and foot contacts as CSV", _csv),
        Format("html", "HTML page", ".html", "the playback page (one file, opens without a server)", _html),
    )
}


def export_format(key: str) -> Format:
    """The format of ``key``; an unknown key is a MocapError naming the known ones."""
    if key not in FORMATS:
        raise MocapError(f"no export format {key!r} (known: {', '.join(FORMATS)})")
    return FORMATS[key]


def require(key: str) -> Format:
    """The format of ``key`` if this installation can write it, else a MocapError
    saying what it needs."""
    fmt = export_format(key)
    if not fmt.available():
        raise MocapError(fmt.needs)
    return fmt


def check_ending(key: str, path: str | os.PathLike) -> None:
    """Refuse a file for format ``key`` named with another format's ending (``--glb
    walk.bvh``): the options mixed up."""
    fmt, name = FORMATS[key], os.fspath(path).lower()
    for other in FORMATS.values():
        if name.endswith(other.suffix) and not name.endswith(fmt.suffix):
            raise MocapError(
                f"{path}: the {fmt.label} would go into a file named like a {other.label} "
                f"({other.suffix}); name it {fmt.suffix}"
            )


def export_file(key: str, clip: Clip) -> tuple[str, bytes]:
    """(file name, content) of a clip in a format."""
    fmt = require(key)
    return clip.name + fmt.suffix, fmt.render(clip)


def write_format(key: str, path: str | os.PathLike, clip: Clip) -> Path:
    """Write a clip in a format, atomically; an unwritable path is a MocapError."""
    fmt = require(key)
    return write_export(path, fmt.render(clip), fmt.label)
