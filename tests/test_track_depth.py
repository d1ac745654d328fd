"""The tracking method's root in depth (the motion file's `root`, the perspective
reconstruction's pelvis) on real motion capture walking toward a perspective camera."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from helpers import assert_root_comes_nearer

from mocap.body import JOINTS
from mocap.cli import main
from mocap.io.export.motion_json import read_motion
from mocap.lift.taylor import orientation_of_yaw, yaw_of
from mocap.synth import RenderOptions, render_motion

CMU_WALK = Path(__file__).resolve().parents[2] / "shared" / "data" / "bvh" / "cmu_walk.bvh"
SIZE = (320, 240)
FOCAL = 250.0  # px at 320 wide: the performer walks from 6.6 to 3.6 m


def test_a_walk_toward_the_camera_comes_nearer_in_the_tracked_root(tmp_path):
    if not CMU_WALK.exists():
        pytest.skip(f"{CMU_WALK} absent")
    video = tmp_path / "walk45.mp4"
    truth = render_motion(
        CMU_WALK, video, RenderOptions(yaw=45.0, perspective=FOCAL, size=SIZE, moving_background=True, seed=5)
    )
    marks = tmp_path / "marks.json"
    marks.write_text(
        json.dumps(
            {
                "format": "mocap-annotations",
                "version": 1,
                "frames": {
                    "0": {
                        "orientation": orientation_of_yaw(yaw_of(truth.joints3d[0])),
                        "joints2d": dict(zip(JOINTS, truth.joints2d[0].tolist())),
                    }
                },
            }
        )
    )
    out = tmp_path / "walk45.json"
    assert (
        main(["fit", "--method", "track", str(video), "--annotations", str(marks), "--out", str(out), "--quiet"]) == 0
    )
    assert_root_comes_nearer(read_motion(out)["frames"], truth)
