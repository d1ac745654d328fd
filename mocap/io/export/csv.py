"""CSV export: one row per frame, a header naming each column with its unit and axes: ``frame``,
``time_s``, ``keyframe`` (1 fitted, 0 interpolated), ``score`` (empty on interpolated frames), per
joint ``_u_right_px``, ``_v_down_px`` (from the top-left corner; empty where nobody is) and
``_x_right_m``, ``_y_up_m``, ``_z_toward_camera_m`` (the exports' world: right-handed, camera axes,
floor at y = 0, first pelvis above the origin), then ``ankle_l_contact``, ``ankle_r_contact`` (1: planted)."""

from __future__ import annotations

import csv
import io

import numpy as np

from mocap.body import JOINTS
from mocap.lift.contacts import FEET
from mocap.lift.motion import Motion

HEADER = (
    ["frame", "time_s", "keyframe", "score"]
    + [f"{j}_{axis}" for j in JOINTS for axis in ("u_right_px", "v_down_px")]
    + [f"{j}_{axis}" for j in JOINTS for axis in ("x_right_m", "y_up_m", "z_toward_camera_m")]
    + [f"{foot}_contact" for foot in FEET]
)


def _cells(values, fmt: str) -> list[str]:
    """Numbers as text, NaN as an empty cell, never "-0.000000"."""
    return ["" if not np.isfinite(v) else format(v + 0.0, fmt) for v in values]


def csv_text(motion: Motion, frames: list[dict]) -> str:
    """A motion and its motion-file frames (for the 2D joints and scores) as CSV text."""
    n = motion.n_frames
    joints2d = np.full((n, len(JOINTS), 2), np.nan)
    score = np.full(n, np.nan)
    for i, frame in enumerate(frames[:n]):
        if "joints2d" in frame:
            joints2d[i] = frame["joints2d"]
        score[i] = frame.get("score", np.nan)
    world, contacts = motion.world_joints.reshape(n, -1), motion.contacts.astype(int)
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(HEADER)
    for i in range(n):
        writer.writerow(
            [i, f"{motion.times[i]:.6f}", int(motion.keyframes[i])]
            + _cells([score[i]], ".4f")
            + _cells(joints2d[i].ravel(), ".3f")
            + _cells(world[i], ".6f")
            + contacts[i].tolist()
        )
    return out.getvalue()
