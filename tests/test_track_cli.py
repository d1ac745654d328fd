"""`mocap fit --method track`: marks from the annotations' frame 0, the motion file
and exports, the messages for missing marks; the tracking session following the
user's foreshortening and joint overrides."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import render_tracked_walk

from mocap import pipeline
from mocap.body import JOINTS, SEGMENT_INDEX
from mocap.cli import main
from mocap.io.annotations import Annotations
from mocap.io.export.motion_json import read_motion
from mocap.io.video import open_video
from mocap.lift import taylor as lift
from mocap.lift.orientation import NEGLIGIBLE
from mocap.session import TrackSession
from mocap.track.tracking import guessed_turn, track_clip

IN_PLANE = 0.1  # |dZ| / length: a segment this flat shows no sign


@pytest.fixture(scope="module")
def clip(tmp_path_factory):
    folder = tmp_path_factory.mktemp("track")
    video = folder / "walk.avi"
    truth = render_tracked_walk(video)
    return video, truth


def write_marks(path, truth, drop: str | None = None):
    marks = {j: truth.joints2d[0, i].tolist() for i, j in enumerate(JOINTS) if j != drop}
    path.write_text(
        json.dumps(
            {
                "format": "mocap-annotations",
                "version": 1,
                "frames": {"0": {"orientation": "forward_right", "joints2d": marks}},
            }
        )
    )
    return path


def test_tracking_writes_motion_and_bvh(clip, tmp_path):
    video, truth = clip
    notes = write_marks(tmp_path / "marks.json", truth)
    out, bvh = tmp_path / "walk.motion.json", tmp_path / "walk.bvh"
    assert (
        main(
            [
                "fit",
                "--method",
                "track",
                str(video),
                "--annotations",
                str(notes),
                "--out",
                str(out),
                "--bvh",
                str(bvh),
                "--quiet",
            ]
        )
        == 0
    )
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
    assert "needs the 16 joints marked on frame 0 (--annotations" in capsys.readouterr().err
    notes = write_marks(tmp_path / "marks.json", truth, drop="wrist_r")
    assert main(["fit", "--method", "track", str(video), "--annotations", str(notes), "--quiet"]) == 2
    assert "wrist_r" in capsys.readouterr().err


@pytest.fixture(scope="module")
def session(clip):
    video, truth = clip
    info = open_video(video)
    notes = Annotations().with_method("track").with_orientation(0, "forward_right")
    for j, xy in zip(JOINTS, truth.joints2d[0]):
        notes = notes.with_joint(0, j, tuple(xy))
    return TrackSession(info, pipeline.tracked(info, notes), notes), truth


def test_the_annotations_method_chooses_tracking(clip, tmp_path):
    """`mocap fit` without --method follows the method the annotations name."""
    video, truth = clip
    notes = write_marks(tmp_path / "marks.json", truth)
    doc = json.loads(notes.read_text())
    notes.write_text(json.dumps({**doc, "method": "track"}))
    out = tmp_path / "walk.motion.json"
    assert main(["fit", str(video), "--annotations", str(notes), "--out", str(out), "--quiet"]) == 0
    joints2d = np.array([f["joints2d"] for f in read_motion(out)["frames"]])
    assert np.allclose(joints2d[0], truth.joints2d[0])  # the marks, not a silhouette fit


def test_a_held_foreshortening_fixes_the_limb_depths(session):
    """A user's sign on a frame holds on the frames after it, until the segment
    passes through the image plane; the 3D follows it, nothing else changes in 2D."""
    tracked, _ = session
    before = tracked.inputs
    pose_before = np.array([tracked.pose3d(i) for i in range(tracked.n_frames)])
    k = SEGMENT_INDEX["lower_leg_r"]
    depth = lift.depth_fractions(pose_before)[:, k]
    frame = int(np.argmax(depth))
    wanted = -int(before.signs[frame, k])
    tracked.annotate(tracked.annotations.with_foreshortening(frame, "lower_leg_r", "toward" if wanted > 0 else "away"))
    after = tracked.inputs
    assert after.signs[frame, k] == wanted
    assert np.array_equal(after.joints2d, before.joints2d)
    # held while the segment stays out of the image plane; where the held sign's
    # best placement lies in the plane, its sign no longer shows
    poses = np.array([tracked.pose3d(i) for i in range(len(depth))])
    in_plane = lift.depth_fractions(poses)[:, k] < IN_PLANE
    held = frame + 1
    while held < len(depth) and depth[held] > NEGLIGIBLE:
        assert after.signs[held, k] == wanted or in_plane[held]
        held += 1
    others = [s for s in range(10) if s not in (k, SEGMENT_INDEX["upper_leg_r"])]
    assert np.array_equal(after.signs[:, others], before.signs[:, others])
    tracked.annotate(tracked.annotations.with_foreshortening(frame, "lower_leg_r", None))
    assert np.array_equal(tracked.inputs.signs, before.signs)


def test_a_joint_override_moves_the_tracked_joint(session):
    """An override wins on its frame and carries, fading, to the frames around it
    (0.2 s: 3 frames at 15 frames/s)."""
    tracked, truth = session
    notes = tracked.annotations
    frame, joint = 7, JOINTS.index("knee_l")
    offset = np.array([24.0, -9.0])
    moved = tuple(tracked.tracked.joints2d[frame, joint] + offset)
    tracked.annotate(notes.with_joint(frame, "knee_l", moved))
    assert np.allclose(tracked.inputs.joints2d[frame, joint], moved)
    shift = tracked.inputs.joints2d[:, joint] - tracked.tracked.joints2d[:, joint]
    assert np.allclose(shift[frame - 3 : frame + 4], np.outer([0, 1, 2, 3, 2, 1, 0], offset) / 3)
    assert not shift[: frame - 3].any() and not shift[frame + 4 :].any()
    assert not np.allclose(tracked.pose3d(frame)[joint], tracked.tracked.joints3d[frame, joint])
    tracked.annotate(notes)
    assert np.allclose(tracked.inputs.joints2d, tracked.tracked.joints2d)


def test_an_orientation_entry_turns_the_trunk_from_its_frame_on(session):
    """The key triangle shows two mirror-image turns alike; an orientation said on a
    later frame picks the other one from there on, the frames before it keep theirs."""
    tracked, _ = session
    before = tracked.inputs
    frame = 9
    assert all(o.endswith("right") for o in before.orientation)
    tracked.annotate(tracked.annotations.with_orientation(frame, "forward_left"))
    after = tracked.inputs
    assert all(o.endswith("left") for o in after.orientation[frame:])
    assert after.orientation[:frame] == before.orientation[:frame]
    assert np.array_equal(after.joints2d, before.joints2d)
    tracked.annotate(tracked.annotations.with_orientation(frame, None))
    assert tracked.inputs.orientation == before.orientation


def test_an_unsaid_turn_is_read_from_the_knees(clip):
    """The calibration's two mirror-image fits are told apart by the way the knees
    bend when the user gives no orientation: the clip turns to the image right, its
    mirror image to the left."""
    _, truth = clip
    assert guessed_turn(truth.joints2d, 15.0) == "right"
    mirrored = truth.joints2d * [-1.0, 1.0] + [truth.width, 0.0]
    assert guessed_turn(mirrored, 15.0) == "left"


def test_the_root_keeps_the_perspective_depth(clip, session, tmp_path):
    """The tracking's pelvis in the camera's frame (the motion file's `root`: x right,
    y up, z toward the camera) follows the true one; with the true focal length its
    distance too, while the default focal length (the frame width, 320 px against the
    true 400) scales the distance by their ratio and leaves x and y."""
    video, truth = clip
    tracked, _ = session
    info = open_video(video)
    exact = TrackSession(
        info, track_clip(info, truth.joints2d[0], focal_px=400.0, orientation="forward_right"), tracked.annotations
    )
    for s, depth_scale in ((exact, 1.0), (tracked, 320.0 / 400.0)):
        root = s.root()
        assert np.abs(root[:, :2] - truth.pelvis_camera[:, :2]).max() < 0.06
        ratio = root[:, 2] / (depth_scale * truth.pelvis_camera[:, 2])
        assert np.abs(ratio - 1.0).max() < 0.05
    frames = s.motion_frames(s.motion())
    np.testing.assert_allclose([f["root"] for f in frames], tracked.root(), atol=1e-9)
