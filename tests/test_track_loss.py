"""The tracking method noticing that it lost the body: per-joint confidence, lost
frames in the motion file (no joints there), short losses bridged; the body found
again by itself after an occluder passed or the performer came back, and by a
re-mark where its colours changed."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import SHARED_DATA, render_walk_with_exit, render_walk_with_occluder

from mocap.body import JOINTS
from mocap.cli import main
from mocap.io.annotations import parse_annotations
from mocap.io.export.motion_json import read_motion
from mocap.io.video import open_video
from mocap.pipeline import open_session
from mocap.synth import render_motion
from mocap.track import blocks
from mocap.track.loss import DISTINCT, bridged, ramp, stretches
from mocap.track.reacquire import distinctness
from mocap.track.tracking import track_clip

GONE = slice(10, 24)  # frames the performer is out of the picture
HIDDEN = slice(10, 18)  # frames a board hides the performer whole
RENDER = dict(seed=3, yaw=45.0, perspective=400.0, moving_background=True)


@pytest.fixture(scope="module")
def exit_clip(tmp_path_factory):
    folder = tmp_path_factory.mktemp("loss")
    video = folder / "exit.avi"
    truth = render_walk_with_exit(video, GONE, regraded=True, **RENDER)
    return video, truth


def write_notes(path, truth, frames=(0,)):
    entries = {str(f): {"joints2d": {j: truth.joints2d[f, i].tolist() for i, j in enumerate(JOINTS)}} for f in frames}
    entries["0"]["orientation"] = "forward_right"
    path.write_text(json.dumps({"format": "mocap-annotations", "version": 1, "frames": entries}))
    return path


def fit(video, notes, out):
    assert (
        main(["fit", "--method", "track", str(video), "--annotations", str(notes), "--out", str(out), "--quiet"]) == 0
    )
    return read_motion(out)["frames"]


def errors(frames, truth):
    """(F,) mean 2D error in % of body height, NaN on frames without joints."""
    out = np.full(len(frames), np.nan)
    for i, f in enumerate(frames):
        if "joints2d" in f:
            out[i] = np.linalg.norm(np.asarray(f["joints2d"]) - truth.joints2d[i], axis=-1).mean()
    return out / truth.body_height_px * 100


def test_a_body_that_leaves_is_reported_lost_not_answered(exit_clip, tmp_path):
    video, truth = exit_clip
    frames = fit(video, write_notes(tmp_path / "marks.json", truth), tmp_path / "exit.json")
    lost = np.array([bool(f.get("lost")) for f in frames])
    assert lost[GONE].mean() >= 0.8  # the tracker knows it has no body
    assert not lost[: GONE.start].any()  # ... and had it before
    for f in frames:
        assert ("joints2d" in f) == (not f.get("lost")) and ("joints3d" in f) == (not f.get("lost"))
        if "joints2d" in f:
            assert len(f["confidence"]) == 16 and all(0.0 <= c <= 1.0 for c in f["confidence"])
    err = errors(frames, truth)
    assert np.nanmax(err[: GONE.start]) < 5.0
    conf = np.array([f["confidence"] for f in frames[: GONE.start]])
    assert conf[1:3].mean() > 0.5


@pytest.mark.parametrize("case", ["occluder", "comeback"])
def test_the_body_is_found_again_without_a_remark(case, tmp_path):
    """A board passes in front of the performer, or the performer leaves the frame
    and comes back: the frames without them are reported lost, and the tracker finds
    the body again by itself (mocap.track.reacquire) once it shows."""
    video = tmp_path / f"{case}.avi"
    if case == "occluder":
        truth, gone = render_walk_with_occluder(video, HIDDEN, **RENDER), HIDDEN
    else:
        truth, gone = render_walk_with_exit(video, GONE, **RENDER), GONE
    frames = fit(video, write_notes(tmp_path / "marks.json", truth), tmp_path / "out.json")
    lost = np.array([bool(f.get("lost")) for f in frames])
    assert lost[gone.start + 2 : gone.stop - 1].all()
    assert not lost[: gone.start].any() and not lost[gone.stop + 1 :].any()
    err = errors(frames, truth)
    assert np.nanmax(err[gone.stop + 1 :]) < 5.0 and np.nanmax(err[: gone.start]) < 5.0


JUMPS = SHARED_DATA / "bvh" / "cmu_01_01_jumps.bvh"


@pytest.mark.skipif(not JUMPS.exists(), reason=f"{JUMPS} is absent")
def test_a_body_whose_match_falls_where_it_stands_out_is_held(tmp_path):
    """The first 39 frames of CMU 01_01 (jumps) over a panning, cluttered background:
    from frame 10 on a pale board behind the head halves the head's and the trunk's
    match against their usual level from the frames before. The body still stands
    out of the frame (mocap.track.reacquire.distinctness), and is held where it
    stands out enough: frames 10-26 (before: every frame from 10 on was lost, the
    joints held where they were); from 27 on the trunk stands out less and those
    frames are lost."""
    video = tmp_path / "jumps.mp4"
    truth = render_motion(
        JUMPS, video, frames=(1, 161), fps=30.0, yaw=45.0, size=(320, 240), perspective=400.0, moving_background=True
    )
    result = track_clip(video, truth.joints2d[0], orientation="forward_right")
    err = np.linalg.norm(result.joints2d - truth.joints2d, axis=-1) / truth.body_height_px
    assert not result.lost[:20].any() and result.lost.mean() < 0.4
    assert np.median(err[~result.lost], axis=1).max() < 0.03


def test_a_block_stands_out_where_the_frame_shows_its_colours_once():
    """distinctness: a block's S where it lies over its best S a length or more away,
    on a noisy frame (sensor noise after the colour model was taken)."""
    rng = np.random.default_rng(0)
    frame = rng.integers(0, 256, (120, 160, 3)).astype(np.uint8)
    frame[38:72, 48:62] = (30, 140, 220)  # the part, wider than its block
    block = np.array([55.0, 40.0, np.pi / 2, 30.0, 10.0])
    grid = blocks.make_grid(30.0, 10.0)
    model = blocks.sample_blocks(frame, block, grid)[0]

    def noisy(image):
        return np.clip(image + rng.normal(0.0, 4.0, image.shape), 0, 255).astype(np.uint8)

    assert distinctness(noisy(frame), model, grid, block) > 3 * DISTINCT
    frame[38:72, 105:119] = (30, 140, 220)  # its colours again, elsewhere
    assert distinctness(noisy(frame), model, grid, block) == pytest.approx(1.0, abs=0.2)


def test_short_losses_are_bridged_long_ones_stay_lost():
    joints = np.zeros((12, 16, 2))
    joints[:, :, 0] = np.arange(12)[:, None] * 10.0
    joints[0] = joints[3:5] = 999.0
    joints[7:] = -999.0
    lost = np.zeros(12, bool)
    lost[0] = lost[3:5] = lost[7:] = True
    out, left = bridged(joints, lost, gap=2)
    assert np.allclose(out[3:5, :, 0], [[30.0], [40.0]])  # between frames 2 and 5
    assert left.tolist() == [True] + [False] * 6 + [True] * 5  # neither end is made up
    assert stretches(left) == [(0, 1), (7, 12)]


def test_ramp_is_full_then_none():
    assert ramp(np.array([0.5, 1.0, 1.5, 2.0, 3.0]), 1.0, 2.0).tolist() == [1.0, 1.0, 0.5, 0.0, 0.0]


def test_a_remark_after_the_loss_recovers_the_body(exit_clip, tmp_path):
    video, truth = exit_clip
    back = GONE.stop + 2
    notes = write_notes(tmp_path / "remarked.json", truth, frames=(0, back))
    frames = fit(video, notes, tmp_path / "remarked.json.out")
    lost = np.array([bool(f.get("lost")) for f in frames])
    err = errors(frames, truth)
    assert not lost[GONE.stop :].any()
    assert np.nanmax(err[GONE.stop :]) < 5.0  # tracked forward and backward from the mark
    assert lost[GONE].mean() >= 0.8  # nobody to see there still
    assert np.nanmax(err[: GONE.start]) < 5.0


def test_the_review_lists_lost_stretches_first_and_a_remark_mends_them(exit_clip):
    video, truth = exit_clip
    info = open_video(video)
    notes = parse_annotations(
        {
            "format": "mocap-annotations",
            "version": 1,
            "frames": {
                "0": {"orientation": "forward_right", "joints2d": dict(zip(JOINTS, truth.joints2d[0].tolist()))}
            },
        },
        info.frame_count,
    )
    session = open_session(info, notes, method="track")
    stops = session.review_stops()
    first, stop = stretches(session.lost)[-1]
    assert stops[0].frame == first and "mark the body here" in stops[0].reasons[0]
    assert first <= GONE.start + 2 and stop == info.frame_count
    entries = notes.to_dict()
    back = GONE.stop + 2
    entries["frames"][str(back)] = {"joints2d": dict(zip(JOINTS, truth.joints2d[back].tolist()))}
    session = open_session(info, parse_annotations(entries, info.frame_count), method="track")
    assert not session.lost[GONE.stop :].any()
    assert all(d.frame < GONE.stop for d in session.review_stops() if d.reasons[0].startswith("body lost"))
    err = np.linalg.norm(session.inputs.joints2d - truth.joints2d, axis=-1).mean(-1) / truth.body_height_px
    assert err[GONE.stop :].max() < 0.05
