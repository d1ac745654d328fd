"""CSV export of a Motion: one row per frame of world joint positions in metres.

Columns: ``frame``, ``time`` (seconds), then ``<joint>_x``, ``<joint>_y``,
``<joint>_z`` for the 16 contract joints in canonical order (joints3d + root).
"""

from __future__ import annotations

import csv
import io

from mocap.body import JOINTS
from mocap.lift.motion import Motion

HEADER = ["frame", "time"] + [f"{j}_{axis}" for j in JOINTS for axis in "xyz"]


def csv_text(motion: Motion) -> str:
    """The motion's world joint positions as CSV text."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(HEADER)
    world = motion.world_joints.reshape(motion.n_frames, -1) + 0.0   # no "-0.000000"
    for i, (time, row) in enumerate(zip(motion.times, world)):
        writer.writerow([i, f"{time:.6f}"] + [f"{v:.6f}" for v in row])
    return out.getvalue()
