"""The synthetic renderer: framing, drawing, videos and their ground truth."""

import json

import cv2
import numpy as np
import pytest

from mocap import body, synth
from mocap.cli import main
from mocap.errors import MocapError
from mocap.synth.truth import load_truth
from mocap.synth.walk import walk_cycle

J = body.JOINT_INDEX


def standing(height_m: float = 1.75) -> np.ndarray:
    """(1, 16, 3) upright pose with the model's proportions, facing +z."""
    u = height_m / body.BODY_HEIGHT
    seg = dict(zip(body.SEGMENT_NAMES, body.LENGTH * u))
    leg = seg["upper_leg_l"] + seg["lower_leg_l"]
    p = np.zeros((16, 3))
    p[J["pelvis"]] = [0, leg, 0]
    p[J["neck"]] = [0, leg + seg["torso"], 0]
    p[J["chest"]] = [0, leg + body.CHEST_FRACTION * seg["torso"], 0]
    p[J["head_top"]] = [0, leg + seg["torso"] + seg["head"], 0]
    for side, s in (("l", 1), ("r", -1)):
        x_arm, x_leg = s * body.SHOULDER_HALF_SPAN * u, s * body.HIP_HALF_SPAN * u
        p[J[f"shoulder_{side}"]] = [x_arm, leg + seg["torso"], 0]
        p[J[f"elbow_{side}"]] = p[J[f"shoulder_{side}"]] - [0, seg["upper_arm_l"], 0]
        p[J[f"wrist_{side}"]] = p[J[f"elbow_{side}"]] - [0, seg["lower_arm_l"], 0]
        p[J[f"hip_{side}"]] = [x_leg, leg, 0]
        p[J[f"knee_{side}"]] = [x_leg, seg["lower_leg_l"], 0]
        p[J[f"ankle_{side}"]] = [x_leg, 0, 0]
    return p[None]


def body_mask(scene: synth.Scene, i: int) -> np.ndarray:
    """Pixels of frame i that differ from the background (noise-free scenes)."""
    diff = cv2.absdiff(synth.draw_frame(scene, i), synth.background(scene, i))
    return diff.max(axis=2) > 12


def test_walk_cycle_has_model_proportions():
    joints = walk_cycle(2.0, 30.0)
    assert joints.shape == (60, 16, 3)
    assert body.body_height(joints[0]) == pytest.approx(1.75)
    assert joints[:, [J["ankle_l"], J["ankle_r"]], 1].min(axis=1) == pytest.approx(np.zeros(60))
    assert joints[-1, J["pelvis"], 2] > 2.0  # walks forward along +z
    in_place = walk_cycle(2.0, 30.0, in_place=True)
    assert np.ptp(in_place[:, J["pelvis"], 2]) == pytest.approx(0.0)


@pytest.mark.parametrize("view", ["side", "three-quarter", "front"])
def test_orthographic_body_height_in_pixels(view):
    opts = synth.RenderOptions(view=view, noise=0.0, antialias=False)
    scene = synth.plan_scene(standing(1.6), opts)
    truth = synth.scene_truth(scene, "standing", np.arange(1))
    assert truth.body_height_px == pytest.approx(0.6 * 480)
    rows = np.flatnonzero(body_mask(scene, 0).any(axis=1))
    feet = 1 + body.FOOT_LENGTH / body.BODY_HEIGHT  # the silhouette reaches the soles
    assert rows[-1] - rows[0] + 1 == pytest.approx(feet * truth.body_height_px, abs=2.0)
    head, ankle = truth.joints2d[0, J["head_top"], 1], truth.joints2d[0, J["ankle_l"], 1]
    assert ankle - head == pytest.approx(truth.body_height_px)


@pytest.mark.parametrize("yaw", [0.0, 180.0])
def test_feet_point_the_way_the_body_faces(yaw):
    scene = synth.plan_scene(standing(), synth.RenderOptions(yaw=yaw, noise=0.0, antialias=False))
    truth = synth.scene_truth(scene, "standing", np.arange(1))
    unit = truth.body_height_px / body.BODY_HEIGHT
    ankle = truth.joints2d[0, J["ankle_l"]]
    mask = body_mask(scene, 0)
    sole = mask[int(ankle[1] + 5 * unit)]  # a row through the feet
    cols = np.flatnonzero(sole) - ankle[0]
    ahead, behind = (cols.max(), -cols.min()) if yaw == 0.0 else (-cols.min(), cols.max())
    assert ahead == pytest.approx(22 * unit, abs=2.0)  # toes: 22 units ahead of the ankle
    assert behind == pytest.approx(6 * unit, abs=2.0)  # heel: 6 behind
    assert not mask[int(ankle[1] + 8 * unit)].any()  # nothing under the soles


@pytest.mark.parametrize("perspective", [None, 700.0])
def test_every_segment_is_drawn_where_the_truth_says(perspective):
    opts = synth.RenderOptions(view="three-quarter", noise=0.0, perspective=perspective)
    scene = synth.plan_scene(walk_cycle(1.0, 15.0), opts)
    truth = synth.scene_truth(scene, "walk", np.arange(15))
    ends = body.segment_endpoints(truth.joints2d)  # (F, 10, 2, 2)
    for i in range(0, 15, 3):
        mask = body_mask(scene, i)
        for w in (0.1, 0.5, 0.9):  # along each segment's axis, inside its cylinder
            x, y = np.round((1 - w) * ends[i, :, 0] + w * ends[i, :, 1]).astype(int).T
            assert mask[y, x].all(), (i, w)
        # the top of the head lies on the silhouette's edge; just inside it is body
        x, y = np.round(0.95 * truth.joints2d[i, J["head_top"]] + 0.05 * truth.joints2d[i, J["neck"]]).astype(int)
        assert mask[y, x]
        assert (truth.joints2d[i] > 0).all() and (truth.joints2d[i] < [640, 480]).all()


def test_body_shapes_change_the_widths_not_the_joints():
    """A slim or broad body (--shape) covers fewer or more pixels around the same
    joints, filmed by the same camera: each silhouette lies within the next wider one."""
    joints = walk_cycle(1.0, 10.0)[:3]
    masks, joints2d = {}, None
    for shape in ("slim", "model", "broad"):
        scene = synth.plan_scene(
            joints, synth.RenderOptions(view="three-quarter", noise=0.0, antialias=False, shape=shape)
        )
        truth = synth.scene_truth(scene, "walk-cycle", np.arange(3))
        masks[shape] = np.array([body_mask(scene, i) for i in range(3)])
        joints2d = truth.joints2d if joints2d is None else joints2d
        assert np.allclose(truth.joints2d, joints2d)
    for thin, wide in (("slim", "model"), ("model", "broad")):
        assert not (masks[thin] & ~masks[wide]).any()
        assert masks[thin].sum() < 0.9 * masks[wide].sum()
    with pytest.raises(MocapError, match="unknown body shape"):
        synth.plan_scene(joints, synth.RenderOptions(shape="round"))


def test_video_and_truth_files(tmp_path):
    out = tmp_path / "clip.avi"
    truth = synth.render_clip(walk_cycle(0.5, 30.0, in_place=True), out, size=(320, 240), view="side", seed=3)
    cap = cv2.VideoCapture(str(out))
    frames = [cap.read()[1] for _ in range(int(cap.get(cv2.CAP_PROP_FRAME_COUNT)))]
    assert len(frames) == 15 and frames[-1].shape == (240, 320, 3)
    doc = json.loads((tmp_path / "clip.truth.json").read_text())
    assert doc["format"] == "mocap-truth" and doc["joints"] == list(body.JOINTS)
    assert doc["camera"]["kind"] == "orthographic" and len(doc["frames"]) == 15
    loaded = load_truth(tmp_path / "clip.truth.json")
    np.testing.assert_allclose(loaded.joints2d, truth.joints2d, atol=1e-3)


@pytest.mark.parametrize("perspective", [None, 900.0])
def test_truth_reprojects(perspective, tmp_path):
    joints = walk_cycle(1.0, 10.0)
    truth = synth.render_clip(joints, tmp_path / "a.mp4", view="three-quarter", pitch=10.0, perspective=perspective)
    cam = load_truth(tmp_path / "a.truth.json").camera
    reproj = cam.project_camera(truth.joints3d + truth.pelvis_camera[:, None])
    np.testing.assert_allclose(reproj, truth.joints2d, atol=1e-6)
    np.testing.assert_allclose(cam.project_camera(cam.to_camera(joints)), truth.joints2d, atol=1e-6)


def test_camera_frame_and_anatomical_sides():
    scene = synth.plan_scene(walk_cycle(1.0, 10.0), synth.RenderOptions(view="side"))
    truth = synth.scene_truth(scene, "w", np.arange(10))
    j3 = truth.joints3d[0]
    assert np.allclose(j3[J["pelvis"]], 0.0)
    assert j3[J["head_top"], 1] > 1.0 - 0.5  # y up
    assert j3[J["hip_r"], 2] > j3[J["hip_l"], 2]  # side view from the performer's right
    assert truth.joints2d[-1, J["pelvis"], 0] > truth.joints2d[0, J["pelvis"], 0]  # walks right
    front = synth.scene_truth(synth.plan_scene(walk_cycle(1.0, 10.0), synth.RenderOptions(view="front")), "w", [0])
    assert front.joints2d[0, J["hip_l"], 0] > front.joints2d[0, J["hip_r"], 0]  # mirror view


def test_background_static_or_moving():
    joints = walk_cycle(1.0, 10.0)
    still = synth.plan_scene(joints, synth.RenderOptions(seed=5))
    assert np.array_equal(synth.background(still, 0), synth.background(still, 9))
    assert not np.array_equal(synth.draw_frame(still, 0)[:40], synth.draw_frame(still, 1)[:40])
    moving = synth.plan_scene(joints, synth.RenderOptions(seed=5, moving_background=True))
    assert not np.array_equal(synth.background(moving, 0), synth.background(moving, 5))


def test_resample_indices():
    picks = synth.resample_indices(299, 1 / 120, 30.0)
    assert len(picks) == 74 and list(picks[:3]) == [0, 4, 8] and picks[-1] == 292
    assert list(synth.resample_indices(299, 1 / 120, 30.0, (100, 120))) == [100, 104, 108, 112, 116]
    assert len(synth.resample_indices(299, 1 / 120, 30.0, seconds=1.0)) == 30
    with pytest.raises(MocapError, match="empty"):
        synth.resample_indices(10, 0.1, 30.0, (8, 3))


def test_cli(tmp_path, capsys):
    out = tmp_path / "w.mp4"
    assert (
        main(
            [
                "synth",
                "walk-cycle",
                str(out),
                "--seconds",
                "0.4",
                "--size",
                "160x120",
                "--view",
                "three-quarter",
                "--truth",
                str(tmp_path / "t.json"),
                "--shape",
                "slim",
            ]
        )
        == 0
    )
    assert out.exists() and (tmp_path / "t.json").exists()
    assert main(["synth", str(tmp_path / "absent.bvh"), str(out)]) == 2
    assert main(["synth", "walk-cycle", str(tmp_path / "w.mkv")]) == 2
    assert "mocap: error:" in capsys.readouterr().err
