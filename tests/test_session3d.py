"""The whole pipeline in 3D: `mocap fit --annotations ... --bvh --glb --csv`, the
Session that re-lifts only what an edit changes, and frames without a person."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import render_walk, render_walk_with_exit

from mocap.body import SEGMENT_JOINTS, SEGMENT_NAMES
from mocap.cli import main
from mocap.io.annotations import Annotations, save_annotations
from mocap.io.export.motion_json import read_motion
from mocap.lift import inputs as mocap_inputs
from mocap.lift import taylor as lift
from mocap.lift.orientation import NEGLIGIBLE
from mocap.pipeline import fit_video
from mocap.session import SilhouetteSession as Session
from mocap.smoothest import DEPTH_SMOOTH_S
from mocap.synth.metrics import pa_mpjpe
from mocap.synth.oracle import annotations_for_poses


@pytest.fixture(scope="module")
def walk(tmp_path_factory):
    """The three-quarter walk of helpers.render_walk, rendered and fitted once."""
    folder = tmp_path_factory.mktemp("walk3d")
    video = folder / "walk.mp4"
    truth = render_walk(video, view="three-quarter")
    info, fits = fit_video(video)
    return video, truth, info, fits


def test_fit_with_annotations_writes_3d_and_every_export(walk, tmp_path):
    video, truth, _, _ = walk
    notes = tmp_path / "a.json"
    save_annotations(notes, annotations_for_poses(truth.joints3d, truth.joints2d))
    out = {k: tmp_path / f"m.{k}" for k in ("json", "bvh", "glb", "csv")}
    assert (
        main(
            [
                "fit",
                str(video),
                "--annotations",
                str(notes),
                "--out",
                str(out["json"]),
                "--bvh",
                str(out["bvh"]),
                "--glb",
                str(out["glb"]),
                "--csv",
                str(out["csv"]),
                "--quiet",
            ]
        )
        == 0
    )
    assert all(p.stat().st_size > 0 for p in out.values())
    frames = read_motion(out["json"])["frames"]
    joints3d = np.array([f["joints3d"] for f in frames])
    assert joints3d.shape == (30, 16, 3)
    assert {f["orientation"] for f in frames} == {"forward_right"}
    assert pa_mpjpe(joints3d, truth.joints3d) < 0.110
    # joints2d are anatomical now: matched side by side to the truth, not mirrored
    joints2d = np.array([f["joints2d"] for f in frames])
    assert np.median(np.linalg.norm(joints2d - truth.joints2d, axis=-1)) < 0.05 * truth.body_height_px


def test_without_annotations_the_first_guess_is_used(walk):
    _, truth, info, fits = walk
    session = Session(info, fits)
    inputs = session.inputs
    assert set(inputs.orientation) == {"forward_right"}
    assert inputs.swap.all()  # facing the camera: image-left is their right
    visible = np.array([lift.depth_fractions(p) for p in truth.joints3d]) > NEGLIGIBLE
    signs = np.array([lift.signs_of(p) for p in truth.joints3d])
    assert (inputs.signs == signs)[visible].mean() >= 0.6
    assert pa_mpjpe(session.motion().joints3d, truth.joints3d) < 0.150


def test_a_sign_click_moves_its_frame_and_leaves_frames_beyond_the_smoothing(walk):
    """A sign holds from its frame on (and the first guess may re-solve around it);
    the lifted depths are smoothed over DEPTH_SMOOTH_S, so frames more than a few
    sigmas from every frame whose signs changed keep their pose."""
    _, truth, info, fits = walk
    session = Session(info, fits)
    before = np.array([session.pose3d(i) for i in range(len(fits))])
    signs_before = session.inputs.signs.copy()
    frame = 12
    k = int(np.argmax(lift.depth_fractions(before[frame])))  # the segment most out of the image plane
    segment = SEGMENT_NAMES[k]
    flipped = "away" if session.inputs.signs[frame, k] > 0 else "toward"
    session.annotate(session.annotations.with_foreshortening(frame, segment, flipped))
    after = np.array([session.pose3d(i) for i in range(len(fits))])
    assert session.inputs.signs[frame, k] == (1 if flipped == "toward" else -1)
    distal = SEGMENT_JOINTS[k][1]
    assert abs(after[frame, distal, 2] - before[frame, distal, 2]) > 0.02  # metres
    reach = int(np.ceil(4 * DEPTH_SMOOTH_S * info.fps))
    resigned = np.flatnonzero((session.inputs.signs != signs_before).any(axis=1))
    far = np.abs(np.arange(len(fits))[:, None] - resigned[None]).min(axis=1) > reach
    assert far.any() and np.allclose(after[far], before[far])


def test_keyframes_from_annotations_and_the_rest_interpolated(walk):
    _, truth, info, fits = walk
    session = Session(info, fits, Annotations(keyframes=(0, 10, 20, 29)))
    frames = session.motion_frames(session.motion())
    assert [f["index"] for f in frames if f["keyframe"]] == [0, 10, 20, 29]
    for f in frames:
        assert f["person"] and "joints3d" in f and "joints2d" in f
        assert ("score" in f) == f["keyframe"]


def test_frames_without_a_person_are_interpolated_between_keyframes(tmp_path):
    video = tmp_path / "exit.avi"
    render_walk_with_exit(video, gone=slice(12, 18))
    info, fits = fit_video(video)
    session = Session(info, fits)
    motion = session.motion()
    frames = session.motion_frames(motion)
    for f in frames:
        gone = 12 <= f["index"] < 18
        assert f["person"] == (not gone) and f["keyframe"] == (not gone)
        assert "joints3d" in f and (("joints2d" in f) == (not gone))
    assert np.isfinite(motion.joints3d).all() and np.isfinite(motion.root).all()


def test_bad_annotations_stop_the_fit_before_it_starts(walk, tmp_path, capsys):
    video = walk[0]
    notes, out = tmp_path / "bad.json", tmp_path / "m.json"
    notes.write_text(
        json.dumps({"format": "mocap-annotations", "version": 1, "frames": {"99": {"orientation": "left"}}})
    )
    assert main(["fit", str(video), "--annotations", str(notes), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f'mocap: error: {notes}: frames["99"]: frame 99 is out of range') and err.count("\n") == 1
    assert not out.exists()


def test_a_sign_click_lifts_only_the_frames_it_changes(walk, monkeypatch):
    """A sign click re-lifts (Eq. 4-5) the frames whose lifting inputs it changed, its
    own and those the sign guess re-solves around it, not the clip; the depths are
    smoothed again, and the poses equal those of a session lifted afresh."""
    _, _, info, fits = walk
    session = Session(info, fits)
    session.lifted()
    calls = []
    real = mocap_inputs.lift_pose

    def counted(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(mocap_inputs, "lift_pose", counted)
    before = session.inputs
    frame = 12
    k = int(np.argmax(lift.depth_fractions(session.pose3d(frame))))
    flipped = "away" if before.signs[frame, k] > 0 else "toward"
    session.annotate(session.annotations.with_foreshortening(frame, SEGMENT_NAMES[k], flipped))
    after = session.lifted()
    touched = session.inputs.changed_frames(before)
    assert touched[frame] and len(calls) == touched.sum() < len(fits)  # here 17 of 30
    assert (
        np.flatnonzero(touched).tolist() == np.flatnonzero((session.inputs.signs != before.signs).any(axis=1)).tolist()
    )
    calls.clear()
    fresh = Session(info, fits, session.annotations).lifted()
    assert len(calls) == len(fits)
    np.testing.assert_allclose(after, fresh, atol=1e-12)
