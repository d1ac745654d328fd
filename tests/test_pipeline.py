"""End to end: `mocap fit` on rendered walks (exact truth) and on the real dog_walker
clip (skipped when ../shared/data is absent)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import DOG_WALKER, dog_walker_marks, frame_joints, render_walk_with_exit

from mocap.body import JOINT_INDEX, JOINTS
from mocap.cli import main
from mocap.io.export.motion_json import read_motion
from mocap.synth.metrics import labelled_body_height, labelled_errors, side_matched_errors

MAX_MEDIAN_ERROR = 0.035  # of the body height


def percent_errors(motion: dict, truth) -> np.ndarray:
    """(F, 16) 2D errors in % of the body height. The motion file's sides are a
    left/right reading of the fit's image sides (session.anatomical); matching each
    limb pair to the truth by image side makes the comparison independent of it."""
    return side_matched_errors(frame_joints(motion), truth.joints2d) / truth.body_height_px * 100


@pytest.mark.parametrize("view", ["side", "three-quarter"])
def test_motion_file_of_a_rendered_walk(fitted_walk, view):
    clip = fitted_walk(view)
    raw = json.loads(clip.motion.read_text())
    assert (raw["format"], raw["version"], raw["joints"]) == ("mocap-motion", 1, list(JOINTS))
    video = raw["video"]
    assert (video["width"], video["height"], video["fps"]) == (320, 240, 15.0)
    assert video["frame_count"] == len(clip.truth.joints2d) == 30
    frames = raw["frames"]
    assert [f["index"] for f in frames] == list(range(30))
    for f in frames:
        assert f["person"] and f["keyframe"] and 0.0 <= f["score"] <= 1.0
        joints = np.asarray(f["joints2d"], dtype=float)
        assert joints.shape == (16, 2) and np.isfinite(joints).all()
    err = percent_errors(read_motion(clip.motion), clip.truth)
    assert np.median(err) < 100 * MAX_MEDIAN_ERROR, f"median 2D error {np.median(err):.1f}%"


def test_frames_without_the_performer_say_so(tmp_path):
    video, out = tmp_path / "exit.avi", tmp_path / "exit.motion.json"
    truth = render_walk_with_exit(video, gone=slice(12, 18))
    assert main(["fit", str(video), "--out", str(out), "--quiet"]) == 0
    frames = read_motion(out)["frames"]
    person = [f["person"] for f in frames]
    assert person == [not 12 <= i < 18 for i in range(30)]
    for f in frames:
        assert f["keyframe"] == f["person"]
        assert ("joints2d" in f) == ("score" in f) == f["person"]
    err = percent_errors(read_motion(out), truth)
    assert np.nanmedian(err) < 100 * MAX_MEDIAN_ERROR


def test_dog_walker_is_fitted_upright_on_every_frame(tmp_path):
    if not DOG_WALKER.exists():
        pytest.skip(f"real data absent: {DOG_WALKER} (../shared/data beside the checkout)")
    out = tmp_path / "dog.motion.json"
    assert main(["fit", str(DOG_WALKER), "--out", str(out), "--quiet"]) == 0
    frames = read_motion(out)["frames"]
    assert len(frames) == 54
    missing = [f["index"] for f in frames if not f["person"]]
    assert missing == [], f"no person found on frames {missing}"
    y = frame_joints({"frames": frames})[..., 1]
    j = JOINT_INDEX
    upright = (
        (y[:, j["head_top"]] < y[:, j["pelvis"]])
        & (y[:, j["pelvis"]] < y[:, j["ankle_l"]])
        & (y[:, j["pelvis"]] < y[:, j["ankle_r"]])
    )
    assert upright.mean() >= 0.9, f"not upright on frames {np.flatnonzero(~upright).tolist()}"


def test_dog_walker_is_fitted_near_the_joints_marked_by_hand(tmp_path):
    """Against the joints marked by hand on every third frame (18 frames, 154 marks;
    benchmarks/bench_track.py's second table): median 3.7% of the body height over all
    marks, 90th percentile 7.6%; the head, neck and pelvis within 5%. The ankles sit
    4.4% off (8.7% when the model's lower leg ended at the sole: the foot piece puts
    the ankle above it), the wrists 2.3% (7.1% when the model's forearm ended in the
    hand: the hand piece puts the wrist before it)."""
    if not DOG_WALKER.exists():
        pytest.skip(f"real data absent: {DOG_WALKER} (../shared/data beside the checkout)")
    out = tmp_path / "dog.motion.json"
    assert main(["fit", str(DOG_WALKER), "--out", str(out), "--quiet"]) == 0
    marks = dog_walker_marks()
    errors = labelled_errors(frame_joints(read_motion(out)), marks)
    percent = {kind: e / labelled_body_height(marks) * 100 for kind, e in errors.items()}
    every = np.concatenate(list(percent.values()))
    assert np.median(every) < 6.5 and np.percentile(every, 90) < 13.0
    assert max(np.median(percent[k]) for k in ("head_top", "neck", "pelvis", "knee")) < 6.0
    assert np.median(percent["ankle"]) < 6.5
    assert np.median(percent["wrist"]) < 4.0
