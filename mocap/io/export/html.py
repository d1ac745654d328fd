"""The playback page: ``static/playback.html`` (plain JavaScript on a 2D canvas: no library, server or
network) filled with the clip's name, frame rate and every frame's 16 world joints (metres, y up, z
toward the camera; ``null`` where the frame has no pose)."""

from __future__ import annotations

import html
import json
import os
from pathlib import Path

import numpy as np

from mocap import body
from mocap.errors import MocapError
from mocap.io.export.atomic import write_export
from mocap.io.export.marks import FACING_MARKS
from mocap.io.export.motion_json import read_motion
from mocap.lift.motion import Motion

STATIC = Path(__file__).resolve().parents[3] / "static"
TEMPLATE = STATIC / "playback.html"
DATA_SLOT, TITLE_SLOT = "/*MOCAP_DATA*/null", "__MOCAP_TITLE__"
COLOURS = {"torso": "#8a9bb0", "head": "#c9a27e", "l": "#3d8fb8", "r": "#d9822b", "mark": "#30343c"}


def playback_html(name: str, fps: float, joints: np.ndarray) -> str:
    """The page for a clip: ``joints`` (F, 16, 3) world joints, NaN where a frame has none."""
    joints = np.asarray(joints, dtype=float)
    if joints.ndim != 3 or joints.shape[1:] != (len(body.JOINTS), 3) or not len(joints):
        raise MocapError(f"a playback page needs (frames, {len(body.JOINTS)}, 3) joints, got shape {joints.shape}")
    if not fps > 0:
        raise MocapError(f"a playback page needs a positive frame rate, got {fps}")
    radii = body.semi_axes(body.BODY_HEIGHT_M).mean(axis=1)
    segments = [
        [
            body.JOINTS.index(a),
            body.JOINTS.index(b),
            round(float(radii[i]), 3),
            COLOURS[s] if s in COLOURS else COLOURS[s[-1]],
        ]
        for i, (s, (a, b)) in enumerate(body.SEGMENTS.items())
    ]
    frames = [None if not np.isfinite(f).all() else np.round(f, 3).tolist() for f in joints]
    data = {
        "name": name,
        "fps": float(fps),
        "n_frames": len(joints),
        "joints": list(body.JOINTS),
        "segments": segments,
        "marks": _marks(),
        "frames": frames,
    }
    # '<' escaped: no '</script>' in a clip's name can end the script early
    text = json.dumps(data, separators=(",", ":")).replace("<", "\\u003c")
    template = TEMPLATE.read_text(encoding="utf-8")
    return template.replace(DATA_SLOT, text, 1).replace(TITLE_SLOT, html.escape(name))


def _marks() -> dict:
    """What the page needs to draw the facing marks (io.export.marks): the joint pairs whose left minus right
    is the body's left, and per mark its segment's joints, place along it, offset in front, length, radius (m)."""
    units = body.BODY_HEIGHT_M / body.BODY_HEIGHT
    front = body.semi_axes(body.BODY_HEIGHT_M)[:, 1]
    return {
        "left": [
            [body.JOINT_INDEX[f"{names[0]}_l"], body.JOINT_INDEX[f"{names[0]}_r"]]
            for names in body.LIMB_JOINTS.values()
        ],
        "marks": [
            [
                *(body.JOINT_INDEX[j] for j in body.SEGMENTS[s]),
                along,
                round(float(front[body.SEGMENT_INDEX[s]]), 4),
                length * units,
                radius * units,
            ]
            for s, along, length, radius in FACING_MARKS.values()
        ],
        "colour": COLOURS["mark"],
    }


def motion_html(motion: Motion, name: str) -> str:
    """The page of a Motion (world joints: the pose moved by the root)."""
    return playback_html(name, motion.fps, motion.world_joints)


def motion_file_html(path: str | os.PathLike) -> str:
    """The page of a motion file: joints3d moved by each frame's ``root``, less the file's ``origin``
    (the exports' world, as ``mocap fit --html`` shows it); frames without joints3d stay empty."""
    doc = read_motion(path)
    frames = doc.get("frames", [])
    joints = np.full((len(frames), len(body.JOINTS), 3), np.nan)
    origin = np.asarray(doc.get("origin", np.zeros(3)), float)
    for i, frame in enumerate(frames):
        if "joints3d" in frame:
            joints[i] = frame["joints3d"] + np.asarray(frame.get("root", np.zeros(3)), float) - origin
    video = doc.get("video", {})
    name = Path(str(video.get("path") or path)).stem
    if name.endswith(".motion"):
        name = name[: -len(".motion")]
    try:
        return playback_html(name, float(video.get("fps") or 0), joints)
    except MocapError as exc:  # no frames, or no frame rate: say which file
        raise MocapError(f"{path}: {exc}") from None


def write_html(path: str | os.PathLike, page: str) -> Path:
    """Write a playback page atomically."""
    return write_export(path, page.encode("utf-8"), "HTML")
