"""The app without a browser: its streamed preprocessing equals the command line's,
edits are saved before they are shown and survive a reopening, undo and redo,
keyframes, the review queue, concurrent edits, the scene geometry, and the views a
running server pushes after an edit."""

from __future__ import annotations

import json
import threading
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from app_helpers import TINY_FRAMES, app, deepest_segment, fresh_copy, hold_fitting, tiny_video  # noqa: F401
from helpers import render_walk, write_empty_scene

from app.edits import toggled_keyframe
from app.layout import Layout
from app.saving import annotations_path
from app.scene import segment_transforms
from app.state import AppState
from app.texts import REVIEW_LINES, frame_text, review_text
from app.views import DISPLAY_HEIGHT, video_image
from mocap.body import JOINT_INDEX, JOINTS, SEGMENT_INDEX, SEGMENT_JOINTS
from mocap.cli import main
from mocap.errors import MocapError
from mocap.io.annotations import Annotations, load_annotations
from mocap.io.video import open_video, processing_scale
from mocap.pipeline import fit_video
from mocap.session import review
from mocap.session.review import Doubt, broken_limits, covering, likely_swaps, review_queue
from mocap.silhouette.passes import body_heights, iter_fits, iter_silhouettes


def saved(state: AppState) -> Annotations:
    return load_annotations(state.path, state.n_frames)


# -- preprocessing --------------------------------------------------------------------


def test_streamed_preprocessing_equals_fit_video(tiny_video):
    info, fits = fit_video(tiny_video)
    scale = processing_scale(info)
    silhouettes = list(iter_silhouettes(open_video(tiny_video), scale))
    streamed = list(iter_fits(silhouettes, scale, info.fps))
    assert len(streamed) == len(fits) == TINY_FRAMES
    for a, b in zip(streamed, fits):
        assert a.index == b.index and a.score == b.score
        np.testing.assert_array_equal(a.joints2d, b.joints2d)


def test_fits_stream_out_while_silhouettes_are_found_and_equal_the_whole_clips(tmp_path):
    """On a clip longer than a fit's windows, each frame's fit is reported while later
    silhouettes are still to be found, as soon as the windows it needs are in (a first
    look, then the fit with its legs chosen LAG_S later), and every fit equals the
    one fitted after every silhouette."""
    from mocap.pipeline import FITTING, SILHOUETTES, silhouette_passes
    from mocap.silhouette.legchain import LAG_S
    from mocap.silhouette.passes import SCALE_WINDOW_S, SPREAD_WINDOW_S

    render_walk(tmp_path / "walk.mp4", seconds=4.0)
    info = open_video(tmp_path / "walk.mp4")
    reports = []
    silhouettes, fits = silhouette_passes(info, reports.append)
    final = [p for p in reports if p.final]
    assert [p.done for p in final] == list(range(1, 2 * info.frame_count + 1))
    # the torso spread's window, its frames' body heights', theirs' rough heights'
    windows = sum(round(s * info.fps) for s in (SPREAD_WINDOW_S, SCALE_WINDOW_S, SCALE_WINDOW_S))
    for kind, needed in ((reports, windows + 1), (final, windows + round(LAG_S * info.fps) + 1)):
        first_fit = [p.stage for p in kind].index(FITTING)
        assert kind[first_fit].frame == 0
        found = [p.stage for p in kind[:first_fit]].count(SILHOUETTES)
        assert found == needed < info.frame_count, (found, needed)
    first_looks = [p.frame for p in reports if not p.final]
    assert first_looks == list(range(info.frame_count - windows))  # the frames fitted before the end
    whole = whole_clip_fits(silhouettes, processing_scale(info), info.fps)
    assert [f.index for f in fits] == [f.index for f in whole] == list(range(info.frame_count))
    for a, b in zip(fits, whole):
        assert a.score == b.score and a.spread == b.spread
        np.testing.assert_array_equal(a.joints2d, b.joints2d)


def whole_clip_fits(silhouettes: list, scale: float, fps: float) -> list:
    """Pass two with every window taken over the whole clip at once: the body heights
    (passes.body_heights), the low percentile of the per-frame torso spreads around
    each frame and the lift's spread from its own per-frame ones (passes.torso_reads)."""
    from mocap.silhouette.passes import (
        SPREAD_PERCENTILE,
        SPREAD_WINDOW_S,
        Fitter,
        half_window,
        lift_spread,
        rolling_percentile,
        torso_reads,
    )

    heights = body_heights(silhouettes, fps)
    reads = [(np.nan, np.nan, False) if s is None else torso_reads(s, h) for s, h in zip(silhouettes, heights)]
    raw, lift_raw, readable = (np.array(values) for values in zip(*reads))
    half = half_window(SPREAD_WINDOW_S, fps)
    spreads = rolling_percentile(raw, half, SPREAD_PERCENTILE)
    lifts = [np.nan if s is None else lift_spread(lift_raw, readable, i, half) for i, s in enumerate(silhouettes)]
    fitter = Fitter(scale, fps)
    fits = [f for i, s in enumerate(silhouettes) for f in fitter.fit(i, s, heights[i], spreads[i], lifts[i])]
    return fits + fitter.flush()


def test_page_state_while_preprocessing(tiny_video, tmp_path, monkeypatch):
    """Frames fitted so far can be looked at; later ones say they are not; edits that
    need the 3D pose are refused until it exists."""
    gate, held = threading.Event(), threading.Event()
    hold_fitting(monkeypatch, 5, gate, held)
    state = AppState(fresh_copy(tiny_video, tmp_path))
    state.start()
    assert held.wait(30)
    first, later = state.view(0), state.view(10)
    assert first.fitted and first.joints2d is not None and first.pose3d is None
    assert later.silhouette_ready and not later.fitted
    assert not state.progress.ready and 0 < state.progress.done < state.progress.total
    with pytest.raises(MocapError, match="still being fitted"):
        state.flip_sign(0, "torso")
    assert state.set_orientation(0, "right")  # saved now, lifted when ready
    gate.set()
    assert state.ready.wait(30) and state.progress.ready
    assert state.view(0).orientation == "right" and state.view(0).pose3d is not None


# -- edits ----------------------------------------------------------------------------


def test_flip_changes_the_pose_and_is_saved_and_restored(app):
    state = app.state
    segment = deepest_segment(state, 4)
    k = SEGMENT_INDEX[segment]
    before = state.view(4)
    assert state.flip_sign(4, segment)
    after = state.view(4)
    assert after.signs[k] == -before.signs[k] and after.sign_notes[k] == "set here"
    assert np.abs(after.pose3d - before.pose3d).max() > 0.05
    value = "toward" if after.signs[k] > 0 else "away"
    assert saved(state).frames[4].foreshortening == {segment: value}
    reopened = AppState(state.info.path)
    assert reopened.annotations == state.annotations


def test_an_edit_is_shown_before_the_review_is_ranked_again(app, monkeypatch):
    """A click's page does not wait for the clip's review queue: it shows the last one at once, and the settling
    ranks the edited clip and shows the page again."""
    state = app.state
    before = state.review_stops(at_once=True)
    monkeypatch.setattr(AppState, "_settle_soon", lambda self: None)  # the settling held, then run below
    shown = []
    state.on_change(lambda: shown.append(state.view().doubts))
    assert state.flip_sign(4, deepest_segment(state, 4))
    session = state._session
    assert session.queue_stale and state.review_stops(at_once=True) == before and len(shown) == 1
    state._settle()
    assert not session.queue_stale and len(shown) == 2
    assert state.review_stops(at_once=True) == session.review_stops() == state.review_stops()


def test_a_limb_pair_is_swapped_in_one_edit(app):
    """Swap legs pins each leg joint on the frame where the other side's was shown (a pair named the wrong way
    round): the 2D and the 3D exchange the legs, the frame is keyed, and one undo takes it all back."""
    state = app.state
    frame, opened = 4, state.annotations
    before = state.view(frame)
    assert state.swap_sides(frame, "leg")
    after = state.view(frame)
    legs = {side: [JOINT_INDEX[f"{j}_{side}"] for j in ("hip", "knee", "ankle")] for side in "lr"}
    for a, b in (("l", "r"), ("r", "l")):
        np.testing.assert_allclose(after.joints2d[legs[a]], before.joints2d[legs[b]], atol=0.06)
        assert np.abs(after.pose3d[legs[a], :2] - before.pose3d[legs[b], :2]).max() < 0.03  # metres
    assert set(saved(state).frames[frame].joints2d) == {JOINTS[k] for k in legs["l"] + legs["r"]}
    assert after.keyframe
    assert state.undo() == frame and saved(state) == opened


def test_a_swap_doubt_names_its_fix(app):
    """The frame's text points a doubt that one click answers at its control."""
    view = replace(app.state.view(4), doubts=("feet may have swapped sides", "left lower leg seen end-on"))
    text = frame_text(view)
    assert "⚠ feet may have swapped sides (Joints: Swap legs)" in text
    assert "⚠ left lower leg seen end-on  \n" in text or text.endswith("⚠ left lower leg seen end-on")


def test_edits_undo_redo_and_the_file_follows(app):
    state = app.state
    opened = state.annotations  # the keyframes the fit proposed
    assert state.set_override(3, "wrist_r", (100.0, 120.0))
    assert state.set_orientation(6, "left")
    assert not state.set_orientation(6, "left")  # no change, no history entry
    assert state.undo() == 6 and state.frame == 6
    assert saved(state).frames[3].joints2d == {"wrist_r": (100.0, 120.0)} and 6 not in saved(state).frames
    assert state.undo() == 3 and saved(state) == opened
    assert state.undo() is None
    assert state.redo() == 3 and saved(state).frames[3].joints2d["wrist_r"] == (100.0, 120.0)
    assert state.toggle_keyframe(2)  # a new edit drops the redo stack
    assert state.redo() is None
    np.testing.assert_allclose(state.view(3).joints2d[JOINT_INDEX["wrist_r"]], (100.0, 120.0))


def test_clearing_every_override_of_a_frame_is_one_edit(app):
    state = app.state
    state.set_override(2, "wrist_r", (1.0, 2.0))
    state.set_override(2, "ankle_l", (3.0, 4.0))
    with pytest.raises(MocapError, match="no override of knee_l"):
        state.clear_overrides(2, "knee_l")
    assert state.clear_overrides(2) and 2 not in saved(state).frames
    assert state.undo() == 2 and set(saved(state).frames[2].joints2d) == {"wrist_r", "ankle_l"}


def test_keyframes_marked_and_unmarked():
    notes = toggled_keyframe(Annotations(), 2, 4)
    assert notes.keyframes == (0, 1, 3)
    assert toggled_keyframe(notes, 2, 4).keyframes is None
    single = Annotations(keyframes=(1,))
    with pytest.raises(MocapError, match="last keyframe"):
        toggled_keyframe(single, 1, 4)


def test_unsaveable_edit_is_refused_and_not_applied(app, monkeypatch):
    def refuse(*_args):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr("app.saving.save_annotations", refuse)
    opened = app.state.annotations  # the fit's keyframes, saved
    with pytest.raises(MocapError, match="cannot save annotations"):
        app.state.set_orientation(0, "left")
    assert app.state.annotations == opened == saved(app.state)


def test_concurrent_edits_never_corrupt_the_state(app):
    state = app.state
    opened = state.annotations
    barrier = threading.Barrier(8)

    def work(t: int) -> None:
        barrier.wait()
        for i in range(6):
            frame = (t + i) % TINY_FRAMES
            state.set_override(frame, "ankle_l", (float(t), float(i)))
            state.flip_sign(frame, "torso")
            state.go_to(frame)

    threads = [threading.Thread(target=work, args=(t,)) for t in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert saved(state) == state.annotations
    assert json.loads(state.path.read_text())["format"] == "mocap-annotations"
    while state.undo() is not None:
        pass
    assert saved(state) == opened


def test_annotation_file_lives_beside_the_video():
    assert annotations_path("/videos/walk.mp4") == Path("/videos/walk.annotations.json")


# -- review ---------------------------------------------------------------------------


def test_doubt_signs_on_made_up_joints():
    joints = np.zeros((3, 16, 2))
    joints[:, JOINT_INDEX["neck"]] = (0.0, -50.0)  # torso and head upright
    joints[:, JOINT_INDEX["head_top"]] = (0.0, -75.0)
    joints[:, JOINT_INDEX["knee_l"]] = joints[:, JOINT_INDEX["knee_r"]] = (0.0, 40.0)
    joints[2, JOINT_INDEX["knee_l"]] = (40.0, 0.0)  # a thigh sideways
    assert broken_limits(joints).tolist() == [[False] * 4, [False] * 4, [False, False, True, False]]
    hands = np.zeros((3, 16, 2))
    hands[:, JOINT_INDEX["wrist_l"]] = [(0, 0), (10, 0), (100, 0)]
    hands[:, JOINT_INDEX["wrist_r"]] = [(100, 0), (90, 0), (10, 0)]  # frame 2: swapped
    swaps = likely_swaps(hands, np.ones(3))
    assert swaps[:, 0].tolist() == [False, False, True]


def test_doubts_name_segments_as_the_body_tab_does():
    end_on, close = np.zeros(10, bool), np.zeros(10, bool)
    end_on[SEGMENT_INDEX["upper_arm_l"]] = True
    close[SEGMENT_INDEX["lower_leg_r"]] = True
    limits = np.array([True, False, False, True])  # waist, and the right hip
    assert review._reasons("S 0.9", False, end_on, close, limits, np.zeros(2, bool)) == (
        "left upper arm seen end-on",
        "right lower leg: toward or away, a close call",
        "torso outside its joint limit",
        "right upper leg outside its joint limit",
    )


def test_a_covering_review_stops_in_the_middle_of_every_stretch_worst_first():
    """Stretches of 6 frames (pins carry 3 to either side) over 20 frames: stops on
    3, 9, 15 and 19 (the short last stretch's last frame), the stretch of the most
    doubtful frame first, each saying its worst frame's reasons."""
    queue = [Doubt(f, v, ("low",)) for f, v in ((10, 0.9), (12, 0.8), (15, 0.7), (8, 0.6))]
    stops = covering(queue, 20, 3)
    assert [(d.frame, d.value) for d in stops] == [(9, 0.9), (15, 0.8), (3, 0.0), (19, 0.0)]
    assert stops[0].reasons == ("low (frame 10)",) and stops[1].reasons == ("low (frame 12)",)
    assert stops[2].reasons == ("nothing doubtful nearby",)
    assert all(any(abs(f - d.frame) <= 3 for d in stops) for f in range(20))


@pytest.fixture
def every_fit_doubtful(monkeypatch):
    """The bar for a doubtful score above every fit's (the tiny walk fits well), so
    that every frame is in the review queue, ranked by score."""
    monkeypatch.setattr(review, "LOW_SCORE", 1.0)


def test_review_queue_ranks_and_cycles(every_fit_doubtful, app):
    queue = review_queue(app.state._session)
    assert queue == app.state.review_queue()
    assert [d.value for d in queue] == sorted((d.value for d in queue), reverse=True)
    frames = [d.frame for d in queue]
    assert len(frames) == TINY_FRAMES
    visits = [app.state.next_doubtful() for _ in range(len(frames) + 1)]
    assert visits == frames + frames[:1]
    assert app.controls.status.content.endswith("Next: check the doubtful frames (Review tab, key N), then Export.")
    text = review_text(app.state)  # the page lists the head of the queue, and says so
    assert f"{TINY_FRAMES} frames to review; the {REVIEW_LINES} most doubtful" in text
    assert text.count("\n- **") == REVIEW_LINES


# -- scene geometry and the views a server pushes ---------------------------------------


def test_click_ray_to_video_pixel():
    layout = Layout.for_video(320, 240)
    x = layout.video[0] + (100 / 320 - 0.5) * layout.width
    y = layout.video[1] - (60 / 240 - 0.5) * layout.height
    origin = np.array([0.3, -0.2, 9.0])
    at = layout.video_pixel(origin, np.array([x, y, 0.0]) - origin, (320, 240))
    np.testing.assert_allclose(at, (100, 60), atol=1e-9)
    assert layout.video_pixel(origin, (0.0, 0.0, -1.0), (320, 240)) is None  # between panels


def test_a_small_frame_is_shown_enlarged_with_its_marks_in_place():
    frame = np.full((144, 180, 3), 90, np.uint8)
    image = video_image(frame, {"wrist_l": (60.0, 100.0)}, 1.0)
    factor = DISPLAY_HEIGHT / 144
    assert image.shape == (DISPLAY_HEIGHT, round(180 * factor), 3)
    drawn = np.argwhere((image != 90).any(axis=-1))  # the ring and its name
    ring = drawn[np.hypot(*(drawn - (100 * factor, 60 * factor)).T) < 0.03 * DISPLAY_HEIGHT]
    assert len(ring) and np.abs(ring.mean(axis=0) - (100 * factor, 60 * factor)).max() < 1
    assert np.ptp(ring, axis=0).max() < 0.05 * DISPLAY_HEIGHT  # small against the frame
    big = np.full((480, 640, 3), 90, np.uint8)
    assert video_image(big, {}, 1.0).shape == big.shape


def test_cylinders_join_the_joints(app):
    from scipy.spatial.transform import Rotation

    pose = app.state.view(5).pose3d
    centres, wxyz, lengths = segment_transforms(pose)
    axis = Rotation.from_quat(wxyz, scalar_first=True).apply([0.0, 0.0, 1.0])
    ends = pose[SEGMENT_JOINTS]
    np.testing.assert_allclose(centres - axis * lengths[:, None] / 2, ends[:, 0], atol=1e-9)
    np.testing.assert_allclose(centres + axis * lengths[:, None] / 2, ends[:, 1], atol=1e-9)


def test_server_views_follow_edits_and_frames(app):
    state, body = app.state, app.scene.bodies[0]
    state.go_to(7)
    assert app.controls.frame.value == 7
    image = app.scene.video.image.copy()
    segment = deepest_segment(state, 7)
    handle = body[SEGMENT_INDEX[segment]]
    before = np.array(handle.position), np.array(handle.wxyz)
    state.flip_sign(7, segment)
    assert not np.allclose(np.concatenate(before), np.concatenate([handle.position, handle.wxyz]))
    button = app.controls.segments[segment]
    assert "set here" in button.label
    np.testing.assert_array_equal(app.scene.video.image, image)  # untouched by a flip
    state.go_to(8)
    assert not np.array_equal(app.scene.video.image, image)
    assert "set here" not in button.label


def test_exports_parse(app):
    name, data = app.state.export("json")
    doc = json.loads(data)
    assert name == "walk.motion.json" and doc["format"] == "mocap-motion"
    assert len(doc["frames"]) == TINY_FRAMES
    assert app.state.export("bvh")[1].startswith(b"HIERARCHY")
    assert app.state.export("glb")[1][:4] == b"glTF"


def test_serve_command_line(capsys):
    assert main(["serve", "/no/such/video.mp4"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mocap: error: ") and "video.mp4" in err[0]


def test_a_failed_preprocessing_stops_the_bar_and_says_why(tmp_path):
    """Nobody in the video: the progress bar stops animating, turns red and the status
    line names the problem (the bar no longer pretends to work)."""
    from app.serve import create

    write_empty_scene(tmp_path / "empty.mp4")
    app = create(tmp_path / "empty.mp4", port=0)
    try:
        assert app.controls.progress.animated
        app.state.start()
        assert app.state.ready.wait(60)
        bar, status = app.controls.progress, app.controls.status.content
        assert not bar.animated and bar.color == "red" and bar.visible
        assert status.startswith("**Stopped:**") and "no person found" in status, status
        assert "not fitted" in app.controls.frame_info.content.lower()
    finally:
        app.server.stop()


def test_controls_enabled_only_when_they_can_act(app):
    c, state = app.controls, app.state
    assert c.clear_override.disabled  # no override on the frame
    state.set_override(3, "wrist_r", (100.0, 100.0))
    assert not c.clear_override.disabled
    c.joint.value = "elbow_l"  # chosen, but not placed here
    app.refresh()
    assert c.clear_override.disabled
    c.joint.value = "wrist_r"
    app.refresh()
    assert not c.clear_override.disabled
    assert not c.mark.disabled and c.track.disabled  # marks missing: nothing to track
    state.marks_from_fit()
    assert c.mark.disabled and not c.track.disabled  # all 16 marked
    state.set_method("track")
    assert all(b.disabled for b in c.downloads.values())  # nothing tracked yet
    assert all(b.disabled for b in c.segments.values()) and c.keyframe.disabled


def test_play_follows_the_clock_from_a_moved_frame_and_stops_at_the_end(app):
    """Play moves the current frame (so every view and the slider) at the video's rate,
    the 3D bodies posed as the animation; a frame chosen while playing plays on from
    there; playing stops at the last frame, and Play there starts from the first."""
    fps, state = app.state.info.fps, app.state

    def on_the_clock(origin: int, since: tuple[float, float]) -> None:
        """The frame is where the clock says, never ahead of it (a loaded machine may
        show it up to half a second late)."""
        before, frame, after = time.monotonic(), state.frame, time.monotonic()
        assert origin + (before - since[1]) * fps - 0.5 * fps <= frame, (frame, origin)
        assert frame <= origin + (after - since[0]) * fps + 1, (frame, origin)

    started = time.monotonic()
    app.player.toggle()
    since = (started, time.monotonic())
    assert app.player.playing
    time.sleep(0.4)
    on_the_clock(0, since)
    slider = app.controls.frame.value  # read first: the player may step in between
    assert 0 < slider <= state.frame, (slider, state.frame)
    shown = np.array([h.position for h in app.scene.bodies[0]])  # the 3D: the animation's
    now = state.frame
    poses = [app.player.pose(f) for f in range(max(now - 2, 0), now + 1)]
    assert any(np.allclose(shown, segment_transforms(p - p[JOINT_INDEX["pelvis"]])[0], atol=1e-6) for p in poses)
    moved = time.monotonic()
    state.go_to(2)
    since = (moved, time.monotonic())
    time.sleep(0.3)
    on_the_clock(2, since)
    deadline = time.monotonic() + 10
    while app.controls.play.label != "Play" and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not app.player.playing and state.frame == TINY_FRAMES - 1
    restarted = time.monotonic()
    app.player.toggle()
    assert app.player.playing
    on_the_clock(0, (restarted, time.monotonic()))
    app.player.toggle()
    stopped = state.frame
    time.sleep(0.3)
    assert not app.player.playing and state.frame == stopped == app.controls.frame.value


def test_the_empty_stage_in_use_is_not_refitted(app):
    """ "Use as the empty stage" with the stage in use refuses, and keeps every fit shown."""
    with pytest.raises(MocapError, match="already estimated from the clip: nothing to refit"):
        app.state.set_background("")
    app.state.set_background("0-3")
    assert app.state.ready.wait(60) and app.state.progress.error is None
    with pytest.raises(MocapError, match="already frames 0-3"):
        app.state.set_background(" 0 - 3 ")
    assert app.state.ready.is_set() and app.state.view().pose3d is not None


def test_a_new_empty_stage_while_playing_stops_playing(app):
    """Refitting takes the animation away: playing stops, the page shows the refit."""
    app.player.toggle()
    app.state.set_background("0-3")
    deadline = time.monotonic() + 10
    while app.player.playing and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not app.player.playing
    assert app.state.ready.wait(60) and app.state.progress.ready
    assert app.state.view().pose3d is not None
