"""The whole pipeline in 3D: `mocap fit --annotations ... --bvh --glb --csv`, the
Session whose edits are constraints of the clip's 3D and re-solve only windows around
what they change, and frames without a person."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import render_walk, render_walk_with_exit

from mocap.body import BODY_HEIGHT, BODY_HEIGHT_M, JOINT_INDEX, SEGMENT_JOINTS, SEGMENT_NAMES, segment_label
from mocap.cli import main
from mocap.io.annotations import Annotations, save_annotations
from mocap.io.export.motion_json import read_motion
from mocap.lift import solve
from mocap.lift import taylor as lift
from mocap.lift.orientation import NEGLIGIBLE
from mocap.lift.signpath import WALL
from mocap.lift.solve import WINDOW_S
from mocap.pipeline import fit_video
from mocap.session import SilhouetteSession as Session
from mocap.session import review
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


@pytest.fixture
def solved_frames(monkeypatch) -> list[int]:
    """The number of frames each of the clip solve's problems (mocap.lift.solve.Problem) solves, from here on."""
    solved: list[int] = []

    class Counted(solve.Problem):
        def __init__(self, clip, frames, base, free, *args):
            solved.append(int(free.sum()))
            super().__init__(clip, frames, base, free, *args)

    monkeypatch.setattr(solve, "Problem", Counted)
    return solved


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


def flip_deepest(session: Session, frame: int) -> tuple[int, int]:
    """Click the sign of the segment most out of the image plane on ``frame``; (segment, new sign)."""
    k = int(np.argmax(lift.depth_fractions(session.pose3d(frame))))
    sign = -int(session.inputs.signs[frame, k])
    session.annotate(session.annotations.with_foreshortening(frame, SEGMENT_NAMES[k], TOWARD_AWAY[sign]))
    return k, sign


TOWARD_AWAY = {1: "toward", -1: "away"}


def test_a_sign_click_holds_on_its_frame_and_leaves_frames_beyond_its_windows(walk):
    """The clicked sign is a hard constraint of the 3D on its frame, the page shows the 3D's
    signs, and frames further than WINDOW_S from every frame the edit asks to solve keep their pose."""
    _, _, info, fits = walk
    session = Session(info, fits)
    before = np.array([session.pose3d(i) for i in range(len(fits))])
    clip_before, solution = session.clip_arrays(), session.solution()
    frame = 12
    k, sign = flip_deepest(session, frame)
    after = np.array([session.pose3d(i) for i in range(len(fits))])
    assert lift.signs_of(after[frame])[k] == sign == session.inputs.signs[frame, k]
    assert (session.inputs.signs == lift.signs_of(after)).all()
    distal = SEGMENT_JOINTS[k][1]
    assert abs(after[frame, distal, 2] - before[frame, distal, 2]) > 0.02  # metres
    changed = solve.frames_to_solve(session.clip_arrays(), clip_before, solution)
    reach = int(round(WINDOW_S * info.fps))
    far = np.abs(np.arange(len(fits))[:, None] - np.flatnonzero(changed)[None]).min(axis=1) > reach
    assert changed[frame] and far.any() and np.array_equal(after[far], before[far])


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


def test_a_sign_click_resolves_a_window_not_the_clip(walk, solved_frames):
    """A sign click solves again the frames within WINDOW_S of those whose inputs it changed
    (its own, and those whose first guess changed where the 3D does not keep it), not the clip."""
    _, _, info, fits = walk
    session = Session(info, fits)
    session.lifted()
    solved = solved_frames
    solved.clear()  # what the edit below solves, not the first lift above
    clip_before, solution = session.clip_arrays(), session.solution()
    frame = 12
    flip_deepest(session, frame)
    session.lifted()
    changed = solve.frames_to_solve(session.clip_arrays(), clip_before, solution)
    reach = int(round(WINDOW_S * info.fps))
    near = np.abs(np.arange(len(fits))[:, None] - np.flatnonzero(changed)[None]).min(axis=1) <= reach
    assert changed[frame] and sum(solved) == near.sum() < len(fits)  # 23 of 30 here


def test_a_placed_joint_is_where_the_user_put_it(walk):
    """A joint override is a constraint of the 3D: its frame's pose projects it within
    1 % of the body's height of the click, wherever the fit had it."""
    _, truth, info, fits = walk
    session = Session(info, fits)
    frame, wrist, pelvis = 20, JOINT_INDEX["wrist_l"], JOINT_INDEX["pelvis"]
    click = session.inputs.joints2d[frame, wrist] + np.array([0.06, -0.04]) * truth.body_height_px
    session.annotate(session.annotations.with_joint(frame, "wrist_l", tuple(click)))
    inputs, pose = session.inputs, session.pose3d(frame)
    metres_per_px = BODY_HEIGHT_M / (inputs.px_per_unit[frame] * BODY_HEIGHT)
    seen = (click - inputs.joints2d[frame, pelvis]) * metres_per_px * np.array([1, -1])
    assert np.linalg.norm(pose[wrist, :2] - seen) < 0.01 * BODY_HEIGHT_M


def test_the_3d_keeps_every_held_sign(walk):
    """A sign holds from its frame until the user's next entry for it (held_user_signs, CONTRACT.md):
    on every frame it holds, the 3D has it, whatever the first guess and the clip's sign path say."""
    _, _, info, fits = walk
    session = Session(info, fits)
    k, sign = flip_deepest(session, 2)
    held = session.held_signs()
    assert (held[:, k] == sign).sum() > 1
    ends = np.array([session.pose3d(i) for i in range(len(fits))])[:, SEGMENT_JOINTS[:, :], 2]
    depth = ends[..., 1] - ends[..., 0]
    assert (depth * held > 0)[held != 0].all()


def test_an_undone_sign_gives_the_3d_back(walk):
    """Taking a click back finds the earlier solution again: the same 3D to the bit, nothing solved."""
    _, _, info, fits = walk
    session = Session(info, fits)
    before, notes = session.lifted().copy(), session.annotations
    flip_deepest(session, 12)
    assert not np.array_equal(session.lifted(), before)
    session.annotate(notes)
    np.testing.assert_array_equal(session.lifted(), before)


def test_a_fit_that_sees_no_hip_or_shoulder_width_still_lifts(walk):
    """A fit seen from the front with its hips and shoulders on one spot (a silhouette
    that shows no width, as over a moving background): the solve takes the widths no
    narrower than half the body model's and answers every frame with finite joints."""
    _, _, info, fits = walk
    session = Session(info, fits, Annotations())
    joints = session.inputs.joints2d.copy()
    for a, b in (("hip_l", "hip_r"), ("shoulder_l", "shoulder_r")):
        middle = joints[:, [JOINT_INDEX[a], JOINT_INDEX[b]], 0].mean(axis=1)
        joints[:, JOINT_INDEX[a], 0] = joints[:, JOINT_INDEX[b], 0] = middle
    clip = solve.ClipArrays(
        joints,
        session.inputs.px_per_unit,
        np.zeros(len(joints)),
        session.inputs.signs,
        session.inputs.lengths,
        fps=info.fps,
    )
    assert np.isfinite(solve.lift_clip(clip).joints3d).all()


def test_close_sign_calls_are_reviewed_and_a_sign_the_user_holds_is_none(walk, monkeypatch):
    """The review names a segment whose two signs the clip solve finds nearly as good (its cost
    margin, signpath.sign_margins, under CLOSE_CALL, here the clip's median); once the user holds
    that sign the margin is a wall and the reason goes."""
    _, _, info, fits = walk
    session = Session(info, fits)
    margins, person = session.sign_margins(), session.person
    assert np.isfinite(margins[person]).all() and (margins[person] >= 0).all()
    monkeypatch.setattr(review, "CLOSE_CALL", float(np.median(margins[person])))
    inputs = session.inputs
    close = review.close_calls(margins, review.seen_fractions(inputs.joints2d, inputs.px_per_unit, inputs.lengths))
    frame, k = (int(v) for v in np.argwhere(close)[len(np.argwhere(close)) // 2])
    words = f"{segment_label(SEGMENT_NAMES[k])}: toward or away, a close call"
    assert words in next(d.reasons for d in session.review_queue() if d.frame == frame)
    sign = TOWARD_AWAY[int(session.inputs.signs[frame, k])]
    session.annotate(session.annotations.with_foreshortening(frame, SEGMENT_NAMES[k], sign))
    assert session.sign_margins()[frame, k] >= WALL
    assert not any(words in d.reasons for d in session.review_queue() if d.frame == frame)


def test_an_edit_solves_around_its_frame_first_and_the_rest_when_settled(walk, solved_frames):
    """With the frame the user looks at (annotate's focus), a sign held from frame 5 on is solved within
    WINDOW_S of that frame at once, the frames beyond when the session settles (the app does it on a thread, a
    piece of LATER_FRAMES at a time): then the 3D keeps the sign on every frame it holds, and nothing is left."""
    _, _, info, fits = walk
    session = Session(info, fits)
    session.lifted()
    solved = solved_frames
    solved.clear()  # what the edit below solves, not the first lift above
    frame = 5
    k = int(np.argmax(lift.depth_fractions(session.pose3d(frame))))
    sign = -int(session.inputs.signs[frame, k])
    notes = session.annotations.with_foreshortening(frame, SEGMENT_NAMES[k], TOWARD_AWAY[sign])
    session.annotate(notes, focus=frame)
    assert lift.signs_of(session.pose3d(frame))[k] == sign
    reach = int(round(WINDOW_S * info.fps))
    assert 0 < sum(solved) <= 2 * reach + 1
    solved.clear()
    assert session.settle(most=1) and 0 < sum(solved) <= solve.LATER_FRAMES  # the app's piece at a time
    session.settle()
    assert not session.settle()
    held = session.held_signs()
    assert (held[:, k] == sign).sum() > 2 * reach + 1
    ends = session.lifted()[:, SEGMENT_JOINTS, 2]
    assert ((ends[..., 1] - ends[..., 0]) * held > 0)[held != 0].all()
