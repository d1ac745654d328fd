"""The tracking method looking through the person model (mocap.track.landmarks, reseed, opinion): frame 0's marks
proposed by it, a body the colours lose seeded anew from its landmarks (forward and backward), a held orientation
released where it sees the body turn, every limb given its second opinion. Most tests stand a fake person model
(the truth's joints as landmarks) in for MediaPipe; the comeback test runs MediaPipe itself."""

from __future__ import annotations

import dataclasses
import json

import cv2
import numpy as np
import pytest
from browser_helpers import SKIP_WITHOUT_CHROMIUM, browser  # noqa: F401 (the browser fixture)
from helpers import SHARED_DATA, render_walk

from mocap import synth
from mocap.body import JOINTS
from mocap.cli import main
from mocap.errors import MocapError
from mocap.io.bvh_reader import contract_joints, read_bvh
from mocap.io.export.motion_json import read_motion
from mocap.io.video import iter_frames, write_video
from mocap.person import Landmarks, PersonView, available
from mocap.track.landmarks import facing_yaw, proposed, released, seed_marks, side_of
from mocap.track.reseed import NOBODY, STRANGER_S, merged, seed_row, track_seeded
from mocap.track.tracking import AGREE_BODY, AGREE_SHARE, averaged_with_landmarks, track_clip

SALSA = SHARED_DATA / "bvh" / "cmu_60_05_salsa.bvh"
GONE = slice(15, 30)  # frames the performer is out of the picture


class FakeModel:
    """A person model that sees the truth's joints on the frames of ``seen`` (sure of all 16), nobody elsewhere."""

    name, filtered = "fake", True

    def __init__(self, truth, seen):
        self.truth, self.seen, self.frame = truth, set(seen), 0

    def observe(self, frame):
        f, self.frame = self.frame, self.frame + 1
        if f not in self.seen:
            return None
        landmarks = Landmarks(self.truth.joints2d[f], np.ones(len(JOINTS)), self.truth.joints3d[f])
        return PersonView(np.zeros(frame.shape[:2], np.float32), landmarks)

    def close(self):
        pass


def errors(joints2d, truth):
    """(F,) mean 2D error of the first F frames, % of body height."""
    off = np.linalg.norm(joints2d - truth.joints2d[: len(joints2d)], axis=-1)
    return off.mean(axis=-1) / truth.body_height_px * 100


@pytest.fixture(scope="module")
def walk(tmp_path_factory):
    video = tmp_path_factory.mktemp("person") / "walk.avi"
    return video, render_walk(video, view="three-quarter", seed=4, moving_background=True)


def test_without_marks_the_person_model_seeds_the_tracking_forward_and_back(walk):
    """No marks: the first frame the model is sure of the body on it and the frame before seeds the tracker,
    which tracks from there back to frame 0 and on to the end."""
    video, truth = walk
    result = track_clip(video, None, person=FakeModel(truth, range(5, 30)))
    err = errors(result.joints2d, truth)
    assert not result.lost.any()
    assert err[6] < 0.5  # the seed: frame 6, the model sure on 5 and 6
    assert err[:6].max() < 5.0 and np.median(err) < 3.0


def test_a_clip_the_person_model_sees_nobody_in_is_refused_in_one_line(walk):
    video, truth = walk
    with pytest.raises(MocapError) as caught:
        track_clip(video, None, person=FakeModel(truth, ()))
    assert str(caught.value) == NOBODY and "\n" not in NOBODY


def test_sure_landmarks_guide_the_limbs_without_harm(walk):
    """The truth's joints as landmarks on every frame: the second opinion leaves the 2D no worse than the colours
    alone, and never lost."""
    video, truth = walk
    alone = errors(track_clip(video, truth.joints2d[0]).joints2d, truth)
    guided = track_clip(video, truth.joints2d[0], person=FakeModel(truth, range(30)))
    assert not guided.lost.any()
    assert errors(guided.joints2d, truth).mean() <= alone.mean() + 0.1


def test_tracked_joints_meet_the_landmarks_that_read_the_same_body(walk):
    """A joint and its landmark within AGREE_SHARE of the body's height are averaged: two reads of the joint with
    errors of their own. A landmark farther off, a frame whose landmarks read another body, a missing landmark and
    the head top (which the person model extrapolates) leave the tracked joint alone."""
    _, truth = walk
    tracked = truth.joints2d.astype(float).copy()
    height = truth.body_height_px
    landmarks = tracked + [0.0, 0.4 * AGREE_BODY * height]  # every landmark a little low
    knee = JOINTS.index("knee_l")
    landmarks[3, knee] += [2 * AGREE_SHARE * height, 0.0]  # one landmark elsewhere
    landmarks[4] += [0.0, 2 * AGREE_BODY * height]  # a frame read on another body
    landmarks[5, knee] = np.nan
    fused = averaged_with_landmarks(tracked, landmarks, 25.0)
    moved = np.linalg.norm(fused - tracked, axis=-1) / height
    head = JOINTS.index("head_top")
    others = [j for j in range(len(JOINTS)) if j != head]
    np.testing.assert_allclose(moved[0, others], 0.2 * AGREE_BODY)  # halfway to the landmark
    assert moved[3, knee] == 0 and moved[3, others].sum() > 0
    assert not moved[4].any()
    assert moved[5, knee] == 0
    assert not moved[:, head].any()


def test_seed_marks_need_the_trunk_sure_and_inside_the_frame():
    marks = np.column_stack([np.linspace(100, 140, 16), np.linspace(20, 200, 16)])
    marks[[4, 7]] = [[90, 60], [150, 60]]  # shoulders
    marks[2] = [120, 80]  # chest below them: a sound key triangle
    sure = np.ones(16)
    seen = Landmarks(marks, sure, np.zeros((16, 3)))
    assert np.array_equal(seed_marks(seen, (240, 320, 3)), marks)
    assert seed_marks(None, (240, 320, 3)) is None
    unsure = sure.copy()
    unsure[JOINTS.index("neck")] = 0.2
    assert seed_marks(Landmarks(marks, unsure, np.zeros((16, 3))), (240, 320, 3)) is None
    hand_unsure = sure.copy()
    hand_unsure[JOINTS.index("wrist_l")] = 0.2  # a limb joint at the model's guess
    assert seed_marks(Landmarks(marks, hand_unsure, np.zeros((16, 3))), (240, 320, 3)) is not None
    assert seed_marks(seen, (150, 320, 3)) is None  # the ankles below the frame


def test_proposed_marks_take_the_head_top_off_the_models_mask():
    """landmarks.proposed: the model's head top, 10 px past the crown of the head its mask shows, moved onto the
    crown along the neck -> head top line; left where the mask shows nobody there."""
    mask = np.zeros((240, 320), np.float32)
    cv2.circle(mask, (120, 50), 15, 1.0, -1)  # the head, its crown at y = 35
    mask[65:200, 100:140] = 1.0  # the trunk and legs
    joints = np.column_stack([np.full(16, 120.0), np.linspace(25, 200, 16)])
    joints[JOINTS.index("neck")] = (120, 65)
    seen = Landmarks(joints, np.ones(16), np.zeros((16, 3)))
    top = proposed(PersonView(mask, seen)).joints2d[JOINTS.index("head_top")]
    assert abs(top[0] - 120) < 1 and abs(top[1] - 35) <= 1
    kept = proposed(PersonView(np.zeros_like(mask), seen)).joints2d
    assert np.array_equal(kept, joints) and proposed(None) is None


def test_the_facing_of_a_turned_body_and_its_side():
    yaw = np.radians(60.0)
    left = np.array([np.cos(yaw), 0.0, -np.sin(yaw)])  # the performer's left facing yaw 60 (lift.taylor)
    world = np.zeros((16, 3))
    world[JOINTS.index("shoulder_l")], world[JOINTS.index("shoulder_r")] = 0.2 * left, -0.2 * left
    world[JOINTS.index("chest")] = [0.0, -0.15, 0.0]
    seen = Landmarks(np.zeros((16, 2)), np.ones(16), world)
    assert facing_yaw(seen) == pytest.approx(60.0, abs=1.0)
    assert side_of(60.0) == "right" and side_of(-120.0) == "left"
    assert side_of(5.0) is None and side_of(175.0) is None and side_of(float("nan")) is None


def test_a_held_orientation_is_released_where_the_body_turns():
    facing = np.array([10.0, 40.0, 20.0, -50.0, -80.0, 170.0, -60.0, 50.0])
    turns = ["right"] * 6 + ["left"] * 2  # held from frame 0, said again on frame 6
    assert released(turns, [0, 6], facing) == ["right"] * 3 + [None] * 3 + ["left", None]
    assert released(turns, [0, 6], np.full(8, np.nan)) == turns


def test_merged_rows_take_the_track_that_holds_the_body():
    def row(tag, lost=False):
        return np.full((16, 2), tag), np.ones(10), np.ones(10), lost

    forward = [row(0), row(0, True), row(0), row(0), None]
    backward = [row(1), row(1), row(1, True), row(1), row(1)]
    tags = [r[0][0, 0] for r in merged(forward, backward)]
    assert tags == [0, 1, 0, 1, 1]  # lost forward, lost backward, the nearer seed's, the later seed's own
    assert seed_row(np.zeros((16, 2)))[3] is False


def test_seeds_are_tracked_back_to_the_seed_before(walk):
    """A second seed (a re-mark) on frame 20: the frames between are each taken from the nearer seed's track."""
    video, truth = walk
    frames = [frame for _, frame in iter_frames(video)]
    seeds = {0: truth.joints2d[0], 20: truth.joints2d[20]}
    track = track_seeded(frames, seeds, None, None, None, 15.0)
    assert len(track.joints) == len(frames) and np.isnan(track.facing).all()
    assert np.array_equal(track.joints[20], truth.joints2d[20]) and not track.lost.any()
    assert errors(track.joints, truth)[11:20].max() < 5.0


def render_comeback(path, regraded=True, gone=GONE, frames=(600, 720)):
    """CMU 60_05 (salsa steps; source ``frames`` at 120 fps) from the performer's side, perspective, panning
    background, at 25 fps: the performer steps 20 m aside on the frames of ``gone``, and after them the frames are
    graded otherwise (``regraded``: red and blue swapped), where the marked colours are not found."""
    opts = synth.RenderOptions(yaw=90.0, size=(480, 360), fps=25.0, perspective=600.0, moving_background=True, seed=5)
    motion = read_bvh(SALSA)
    joints = contract_joints(motion)
    picks = synth.resample_indices(len(joints), motion.frame_time, opts.fps, frames, None)
    scene = synth.plan_scene(joints[picks], opts)
    moved = scene.joints_cam.copy()
    moved[gone, :, 0] += 20.0
    scene = dataclasses.replace(scene, joints_cam=moved)

    def frame(i):
        image = synth.draw_frame(scene, i)
        return np.ascontiguousarray(image[..., ::-1]) if regraded and i >= gone.stop else image

    write_video(path, (frame(i) for i in range(len(moved))), opts.fps, opts.size)
    return synth.scene_truth(scene, "salsa with an exit", np.arange(len(moved)))


@pytest.mark.skipif(not SALSA.exists(), reason=f"{SALSA} is absent")
@pytest.mark.skipif(not available("mediapipe"), reason="mediapipe is not installed")
@pytest.mark.parametrize("regraded", [False, True])
def test_a_performer_who_leaves_and_comes_back_is_found_again_without_a_remark(tmp_path, regraded):
    """MediaPipe looks on: the frames without the performer are reported lost, and once they are back its
    landmarks seed the tracker anew, forward and backward: at once in the marked clothes, after STRANGER_S in
    colours the marks never saw (``regraded``); the colours alone lose the turning performer for good."""
    video = tmp_path / "comeback.avi"
    truth = render_comeback(video, regraded)
    notes = tmp_path / "marks.json"
    marks = {"0": {"joints2d": dict(zip(JOINTS, truth.joints2d[0].tolist()))}}
    notes.write_text(json.dumps({"format": "mocap-annotations", "version": 1, "frames": marks}))
    out = tmp_path / "out.json"
    args = ["fit", "--method", "track", str(video), "--annotations", str(notes), "--out", str(out), "--quiet"]
    assert main([*args, "--person-model", "mediapipe"]) == 0
    frames = read_motion(out)["frames"]
    lost = np.array([bool(f.get("lost")) for f in frames])
    back = GONE.stop + (int(np.ceil(STRANGER_S * 25.0)) if regraded else 0)
    assert lost[GONE].all() and not lost[: GONE.start].any() and not lost[back:].any()
    tracked = np.array([f["joints2d"] if "joints2d" in f else np.full((16, 2), np.nan) for f in frames])
    err = errors(tracked, truth)[~lost]
    assert err[: GONE.start].max() < 5.0 and err[GONE.start :].max() < 10.0 and np.median(err[GONE.start :]) < 7.0
    assert main([*args, "--person-model", "none"]) == 0
    assert all(f.get("lost") for f in read_motion(out)["frames"][GONE.stop :])


@pytest.mark.skipif(not SALSA.exists(), reason=f"{SALSA} is absent")
@pytest.mark.skipif(not available("mediapipe"), reason="mediapipe is not installed")
def test_mocap_fit_track_without_marks_takes_the_person_models(tmp_path, capsys):
    """`mocap fit --method track VIDEO` with no annotations: MediaPipe's landmarks mark the body; without a person
    model, one line says marks are needed."""
    video = tmp_path / "salsa.avi"
    truth = render_comeback(video, regraded=False)
    out = tmp_path / "out.json"
    assert (
        main(["fit", "--method", "track", str(video), "--out", str(out), "--quiet", "--person-model", "mediapipe"]) == 0
    )
    frames = read_motion(out)["frames"]
    tracked = np.array([f["joints2d"] for f in frames[: GONE.start]])
    assert np.median(errors(tracked, truth)[: GONE.start]) < 6.0
    capsys.readouterr()
    assert main(["fit", "--method", "track", str(video), "--out", str(out), "--person-model", "none"]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "needs the 16 joints marked" in error


@pytest.mark.browser
@SKIP_WITHOUT_CHROMIUM
@pytest.mark.skipif(not SALSA.exists(), reason=f"{SALSA} is absent")
@pytest.mark.skipif(not available("mediapipe"), reason="mediapipe is not installed")
def test_the_app_proposes_the_marks_the_user_corrects_one_and_tracks_from_them(browser, tmp_path):
    """In the browser: choosing the tracking method shows the person model's marks on frame 0; the user places the
    right wrist again by a click (Joints: Place) and presses Track, which tracks from the confirmed marks."""
    from browser_helpers import open_page, screen_point, shot, wait_until
    from test_browser import to_tracking, video_point

    from app.serve import create

    video = tmp_path / "salsa.mp4"
    truth = render_comeback(video, regraded=False, gone=slice(0, 0), frames=(600, 672))
    app = create(video, port=0, person="mediapipe")
    app.state.start()
    try:
        assert app.state.ready.wait(120) and app.state.progress.error is None
        page = open_page(browser, app.server.get_port())
        to_tracking(page, "all 16 joints are marked on frame 0")
        proposed = np.array([app.state.annotations.frames[0].joints2d[j] for j in JOINTS])
        assert np.median(errors(proposed[None], truth)) < 6.0
        shot(page, "proposed_marks")
        page.get_by_role("tab", name="Joints").click()
        page.get_by_label("Place").click()
        page.get_by_role("option", name="right wrist", exact=True).click()
        wait_until(lambda: app.placing == "wrist_r")
        wrist = truth.joints2d[0, JOINTS.index("wrist_r")]
        page.mouse.click(*screen_point(page, app, video_point(app, wrist)))
        wait_until(lambda: np.hypot(*np.subtract(app.state.annotations.frames[0].joints2d["wrist_r"], wrist)) < 2.0)
        page.get_by_role("tab", name="Tracking").click()
        page.get_by_role("button", name="Track", exact=True).click()
        wait_until(lambda: app.state.progress.ready and not app.state.tracking and not app.state.marks_changed, 120)
        page.get_by_text(f"{len(truth.joints2d)} frames tracked.").first.wait_for()
        confirmed = np.array([app.state.annotations.frames[0].joints2d[j] for j in JOINTS])
        np.testing.assert_allclose(app.state.view(0).joints2d, confirmed, atol=0.5)
        tracked = np.array([app.state.view(f).joints2d for f in range(len(truth.joints2d))])
        assert np.median(errors(tracked, truth)) < 6.0
        shot(page, "proposed_marks_tracked")
    finally:
        app.server.stop()
