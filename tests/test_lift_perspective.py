"""The clip solve through a known camera (mocap.lift.problem.Perspective, `mocap fit --focal`): exact
pinhole projections of the model's walk seen from close by are lifted nearer the truth than scaled
orthography lifts them, and the option reaches the solve and the root's depth."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import render_walk
from helpers import run_cli as run

from mocap.body import SEGMENT_JOINTS
from mocap.camera import Focal, Pinhole
from mocap.io.export.motion_json import read_motion
from mocap.lift.clipdata import ClipArrays, clip_bone_lengths
from mocap.lift.inputs import FIT_LENGTH_PERCENTILE
from mocap.lift.problem import Perspective
from mocap.lift.solve import lift_clip, solve_clip
from mocap.lift.taylor import UNIT_M, clip_lengths, signs_of, yaw_of
from mocap.synth import RenderOptions, render_motion
from mocap.synth.metrics import pa_mpjpe

FOCAL = 300.0  # pixels, 320 wide: a wide lens, the walker 3.6 m away


def close_walk(tmp_path, view: str):
    """The model's walk on the spot through a FOCAL pinhole: its truth, and the solve's inputs from it (exact
    2D, the true yaw, signs and scale, the segments' true |dZ| as a person model gives them)."""
    t = render_motion(
        "walk-cycle",
        tmp_path / f"{view}.mp4",
        RenderOptions(view=view, size=(320, 240), fps=25, perspective=FOCAL),
        seconds=2,
        in_place=True,
    )
    ppu = FOCAL * UNIT_M / np.abs(t.pelvis_camera[:, 2])
    lengths = clip_lengths(t.joints2d, ppu, FIT_LENGTH_PERCENTILE, pool=True)
    v = t.joints3d[:, SEGMENT_JOINTS[:, 1]] - t.joints3d[:, SEGMENT_JOINTS[:, 0]]
    depths = np.abs(v[..., 2]) / np.linalg.norm(v, axis=-1) * lengths
    yaw = np.array([yaw_of(p) for p in t.joints3d])
    signs = np.array([signs_of(p) for p in t.joints3d])
    return t, ClipArrays(t.joints2d, ppu, yaw, signs, lengths, depths=depths, fps=25.0)


def test_the_pinhole_rows_see_the_true_pose_where_it_was_filmed(tmp_path):
    t, clip = close_walk(tmp_path, "three-quarter")
    clip = ClipArrays(**{**clip.__dict__, "camera": Pinhole(FOCAL, 160.0, 120.0)})
    rel = (t.joints2d - t.joints2d[:, [3]]) / clip.px_per_unit[:, None, None]
    seen = np.stack([rel[..., 0], -rel[..., 1]], axis=-1)
    view = Perspective.of(clip, np.arange(len(t.joints2d)), seen, np.ones(rel.shape[:2]))
    residuals, _ = view.residuals(t.joints3d / UNIT_M)
    flat = np.abs(t.joints3d[..., :2] / UNIT_M - view.seen).max()
    assert np.abs(residuals).max() < 1e-6 < 1.0 < flat  # orthography is a unit and more off; the pinhole, not


@pytest.mark.parametrize("view", ["side", "three-quarter", "front"])
def test_a_close_camera_known_lifts_nearer_the_truth_than_orthography(tmp_path, view):
    t, clip = close_walk(tmp_path, view)
    flat = pa_mpjpe(lift_clip(clip).joints3d, t.joints3d)
    pinhole = pa_mpjpe(
        lift_clip(ClipArrays(**{**clip.__dict__, "camera": Pinhole(FOCAL, 160.0, 120.0)})).joints3d, t.joints3d
    )
    assert pinhole < 0.8 * flat, (view, pinhole, flat)


def test_the_lengths_are_held_under_orthography_and_solved_through_the_pinhole(tmp_path):
    """A person model's depths do not measure bones well enough to move the lengths the 2D shows under scaled
    orthography; through a known camera, where a near limb reads long, the solve finds them."""
    _, clip = close_walk(tmp_path, "three-quarter")
    measured = clip_bone_lengths(clip)
    np.testing.assert_array_equal(solve_clip(clip).lengths, measured)
    pinhole = ClipArrays(**{**clip.__dict__, "camera": Pinhole(FOCAL, 160.0, 120.0)})
    assert np.abs(solve_clip(pinhole).lengths / measured - 1).max() > 0.01


def test_fit_takes_the_focal_length_for_the_root_depth_and_refuses_a_bad_one(tmp_path, capsys):
    video = tmp_path / "walk.avi"
    render_walk(video, seconds=1.0)
    depths = []
    for focal in ("320", "640"):
        out = tmp_path / f"{focal}.json"
        code, _ = run(capsys, "fit", video, "--out", out, "--quiet", "--person-model", "none", "--focal", focal)
        assert code == 0
        depths.append(np.nanmedian([f["root"][2] for f in read_motion(out)["frames"] if f.get("root") is not None]))
    assert depths[1] == pytest.approx(2 * depths[0], rel=1e-6) and depths[0] < 0
    for bad, why in (("-5", "a focal length is a number above 0, got '-5'"), ("wide", "expected pixels")):
        code, err = run(capsys, "fit", video, "--out", tmp_path / "bad.json", "--quiet", "--focal", bad)
        assert code == 2 and len(err) == 1 and err[0].startswith(f"mocap: error: --focal: {why}"), err


def test_a_35mm_equivalent_focal_length_is_read_in_the_videos_pixels():
    """26 mm on a 35 mm frame's 43.3 mm diagonal is 26 / 43.27 of a video's diagonal in pixels (1920x1080:
    about 1324 px)."""
    assert Focal.parse("26mm").pixels(1920, 1080) == pytest.approx(26 * np.hypot(1920, 1080) / np.hypot(36, 24))
    assert Focal.parse(" 1390 ").pixels(1920, 1080) == 1390.0
    for bad in ("0", "nan", "inf", "mm", "26 cm"):
        with pytest.raises(ValueError):
            Focal.parse(bad)


def test_without_the_person_models_depths_the_solve_keeps_orthography(tmp_path):
    t, clip = close_walk(tmp_path, "side")
    flat = ClipArrays(**{**clip.__dict__, "depths": None})
    through = ClipArrays(**{**flat.__dict__, "camera": Pinhole(FOCAL, 160.0, 120.0)})
    assert np.array_equal(lift_clip(flat).joints3d, lift_clip(through).joints3d)
