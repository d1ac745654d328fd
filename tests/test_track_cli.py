"""`mocap fit --method track`: marks from the annotations' frame 0, the motion file
and exports, and the messages for missing marks."""

from __future__ import annotations

import json

import numpy as np
import pytest

from mocap import synth
from mocap.body import JOINTS
from mocap.cli import main
from mocap.export.motion_json import read_motion
from mocap.walk import walk_cycle


@pytest.fixture(scope="module")
def clip(tmp_path_factory):
    folder = tmp_path_factory.mktemp("track")
    video = folder / "walk.avi"
    truth = synth.render_clip(walk_cycle(1.6, 15.0), video, size=(320, 240), fps=15.0, yaw=45.0,
                              perspective=400.0, moving_background=True, seed=3)
    return video, truth


def write_marks(path, truth, drop: str | None = None):
    marks = {j: truth.joints2d[0, i].tolist() for i, j in enumerate(JOINTS) if j != drop}
    path.write_text(json.dumps({"format": "mocap-annotations", "version": 1,
                                "frames": {"0": {"orientation": "forward_right", "joints2d": marks}}}))
    return path


def test_tracking_writes_motion_and_bvh(clip, tmp_path):
    video, truth = clip
    notes = write_marks(tmp_path / "marks.json", truth)
    out, bvh = tmp_path / "walk.motion.json", tmp_path / "walk.bvh"
    assert main(["fit", "--method", "track", str(video), "--annotations", str(notes),
                 "--out", str(out), "--bvh", str(bvh), "--quiet"]) == 0
    frames = read_motion(out)["frames"]
    assert len(frames) == len(truth.joints2d)
    joints2d = np.array([f["joints2d"] for f in frames])
    err = np.linalg.norm(joints2d - truth.joints2d, axis=-1) / truth.body_height_px
    assert np.median(err) < 0.05
    assert all(f["joints3d"].shape == (16, 3) and 0.0 <= f["score"] <= 1.0 for f in frames)
    assert bvh.read_text().startswith("HIERARCHY")


def test_tracking_needs_the_marks(clip, tmp_path, capsys):
    video, truth = clip
    assert main(["fit", "--method", "track", str(video), "--quiet"]) == 2
    assert "needs --annotations" in capsys.readouterr().err
    notes = write_marks(tmp_path / "marks.json", truth, drop="wrist_r")
    assert main(["fit", "--method", "track", str(video), "--annotations", str(notes), "--quiet"]) == 2
    assert "wrist_r" in capsys.readouterr().err
