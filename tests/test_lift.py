"""Scaled orthographic lifting (section 3.4, Eq. 4-5) against exact truth: the model's
own walk, and real motion capture from ../shared/data (skipped when absent)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import SHARED_DATA
from scipy.spatial.transform import Rotation

from mocap import synth
from mocap.body import BODY_HEIGHT, JOINT_INDEX, LENGTH, SEGMENT_INDEX, SEGMENT_JOINTS
from mocap.io.bvh_reader import contract_joints, read_bvh
from mocap.lift import taylor as lift
from mocap.lift.cues import Cues, with_landmarks
from mocap.lift.inputs import segment_lengths
from mocap.synth.metrics import facing_error, pa_mpjpe
from mocap.synth.walk import walk_cycle

CMU_WALK = SHARED_DATA / "bvh" / "cmu_walk.bvh"


def seen(joints_world: np.ndarray, view: str, fps: float = 30.0):
    """The truth of a clip as the renderer would film it, without drawing it."""
    scene = synth.plan_scene(joints_world, synth.RenderOptions(view=view, size=(640, 480), fps=fps))
    return synth.scene_truth(scene, "test", np.arange(len(joints_world)))


def lift_truth(truth, lengths=LENGTH, use_orientation: bool = True) -> np.ndarray:
    """Lift every frame of a truth from its 2D joints and its true inputs."""
    ppu = truth.body_height_px / BODY_HEIGHT
    out = []
    for j2, j3 in zip(truth.joints2d, truth.joints3d):
        yaw = lift.yaw_of(j3)
        if use_orientation:
            yaw = lift.facing_yaw(lift.orientation_of_yaw(yaw), abs(np.cos(np.radians(yaw))))
        out.append(lift.lift_pose(j2, ppu, yaw, lift.signs_of(j3), lengths))
    return np.array(out)


@pytest.mark.parametrize("view", ["side", "three-quarter", "front"])
def test_lifting_the_models_own_walk_is_exact(view):
    truth = seen(walk_cycle(1.2, 15.0), view)
    pred = lift_truth(truth, use_orientation=False)
    assert np.abs(pred - truth.joints3d).max() < 1e-3  # metres


def test_eq5_depth_and_sign():
    joints = np.zeros((16, 2))
    joints[JOINT_INDEX["hip_l"]] = [0, 0]
    joints[JOINT_INDEX["knee_l"]] = [30, 0]  # 30 px at 1 px/unit; thigh is 46 long
    dz = lift.relative_depths(joints, 1.0, np.array([1] * 6 + [-1] + [1] * 3))
    assert dz[SEGMENT_INDEX["upper_leg_l"]] == pytest.approx(-np.sqrt(46**2 - 30**2))
    longer = joints.copy()
    longer[JOINT_INDEX["knee_l"]] = [60, 0]  # longer than the model: in the image plane
    assert lift.relative_depths(longer, 1.0, np.ones(10))[SEGMENT_INDEX["upper_leg_l"]] == 0.0


@pytest.mark.parametrize(
    "name, yaw",
    [
        ("forward_right", 30.0),
        ("forward_left", -50.0),
        ("right", 90.0),
        ("left", -90.0),
        ("backward_right", 135.0),
        ("backward_left", -170.0),
    ],
)
def test_the_six_orientations(name, yaw):
    assert lift.orientation_of_yaw(yaw) == name
    spread = abs(np.cos(np.radians(yaw)))
    expected = yaw if name not in ("left", "right") else 90.0 * np.sign(yaw)
    assert lift.facing_yaw(name, spread) == pytest.approx(expected)
    # facing the camera the performer's left is image right; turned away, image left
    left_x = lift.lateral_axis(lift.facing_yaw(name, spread))[0]
    rule = lift.image_left_is_right(name)
    assert rule is None if name in ("left", "right") else rule == (left_x > 0)


def test_facing_error_is_the_turn_about_the_vertical_that_pa_forgives():
    poses = walk_cycle(1.2, 30.0)[:5]
    for turn in (30.0, 170.0):
        turned = Rotation.from_euler("y", turn, degrees=True).apply(poses.reshape(-1, 3)).reshape(poses.shape)
        assert facing_error(turned, poses) == pytest.approx(turn, abs=1e-6)
        assert pa_mpjpe(turned, poses) < 1e-9
    assert facing_error(poses, poses) == 0.0


def test_the_performers_left_in_a_profile_is_away_from_the_camera_when_facing_right():
    assert lift.lateral_axis(90.0) == pytest.approx([0.0, 0.0, -1.0])
    pose = lift.lift_pose(np.zeros((16, 2)), 1.0, 90.0, np.ones(10))
    assert pose[JOINT_INDEX["hip_l"], 2] < 0 < pose[JOINT_INDEX["hip_r"], 2]


def test_clip_lengths_are_what_the_clip_shows():
    truth = seen(walk_cycle(2.0, 15.0), "side")
    lengths = lift.clip_lengths(truth.joints2d, np.full(len(truth.joints2d), truth.body_height_px / BODY_HEIGHT))
    assert lengths == pytest.approx(LENGTH, rel=0.03)


def test_the_landmarks_legs_are_as_long_as_a_leg_in_the_image_plane_shows_them():
    """Where the person model's landmarks give most frames, a leg's length is the 90th percentile of its image
    lengths (a walk seen from the front foreshortens the legs on most frames); the fit's 2D keeps the median,
    which its scatter would otherwise lengthen."""
    truth = seen(walk_cycle(2.0, 15.0), "front")
    ppu = np.full(len(truth.joints2d), truth.body_height_px / BODY_HEIGHT)
    person = np.ones(len(ppu), bool)
    legs = [SEGMENT_INDEX[s] for s in ("upper_leg_l", "lower_leg_l")]
    landmarks = segment_lengths(truth.joints2d, ppu, person, person)[legs]
    fit = segment_lengths(truth.joints2d, ppu, person, None)[legs]
    assert landmarks == pytest.approx(LENGTH[legs], rel=0.03)
    assert (fit < landmarks).all()
    few = segment_lengths(truth.joints2d, ppu, person, np.arange(len(ppu)) < len(ppu) // 3)[legs]
    np.testing.assert_array_equal(few, fit)


def test_signs_and_depths_read_back_from_a_pose():
    pose = seen(walk_cycle(0.5, 15.0), "three-quarter").joints3d[3]
    ends = pose[SEGMENT_JOINTS]
    assert (lift.signs_of(pose) == np.where(ends[:, 1, 2] >= ends[:, 0, 2], 1, -1)).all()
    assert ((lift.depth_fractions(pose) >= 0) & (lift.depth_fractions(pose) <= 1)).all()


@pytest.mark.parametrize("view", ["side", "three-quarter"])
def test_lifting_real_motion_capture_from_true_2d_within_30_mm(view):
    if not CMU_WALK.exists():
        pytest.skip(f"real data absent: {CMU_WALK} (../shared/data beside the checkout)")
    motion = read_bvh(CMU_WALK)
    truth = seen(contract_joints(motion)[::4], view)
    lengths = lift.clip_lengths(truth.joints2d, np.full(len(truth.joints2d), truth.body_height_px / BODY_HEIGHT))
    assert pa_mpjpe(lift_truth(truth, lengths), truth.joints3d) < 0.030


def test_a_wrist_or_ankle_that_slips_on_one_frame_is_steadied_and_a_swing_is_kept():
    from mocap.lift.inputs import steadied_limbs

    n, fps = 30, 30.0
    joints = np.zeros((n, 16, 2))
    swing = np.linspace(100.0, 160.0, n)
    for joint in ("wrist_l", "ankle_r"):
        joints[:, JOINT_INDEX[joint], 0] = swing  # a steady swing
        joints[12, JOINT_INDEX[joint]] = (40.0, 300.0)  # one frame's slip
    joints[20:, JOINT_INDEX["knee_l"], 1] = 50.0  # a step is kept
    joints[:, JOINT_INDEX["neck"], 0] = np.where(np.arange(n) == 12, 90.0, 0.0)  # the trunk is left alone
    person = np.ones(n, bool)
    person[25] = False  # nobody on one frame
    joints[25] = np.nan
    out = steadied_limbs(joints, person, fps)
    keep = np.r_[3:9, 16:22]  # windows clear of the slip, the gap and the ends
    for joint in ("wrist_l", "ankle_r"):
        steadied = out[:, JOINT_INDEX[joint]]
        assert np.abs(steadied[12] - [swing[12], 0.0]).max() < 5.0
        assert np.abs(steadied[keep, 0] - swing[keep]).max() < 1e-9
    knee = out[:, JOINT_INDEX["knee_l"], 1]
    assert np.array_equal(knee[:25], joints[:25, JOINT_INDEX["knee_l"], 1])
    assert np.array_equal(out[:, JOINT_INDEX["neck"]], joints[:, JOINT_INDEX["neck"]], equal_nan=True)
    assert np.isnan(out[25]).all()


def test_landmarks_smoothed_both_ways_keep_a_steady_motion_and_halve_jitter():
    """The person model's landmarks over a clip (lift.cues.smoothed): a joint moving steadily keeps its
    place on every frame, the runs' ends included (no lag); a jittered one comes closer to its path; a frame
    where nobody was seen stays unseen and the runs either side do not mix."""
    from mocap.lift.cues import smoothed

    path = np.arange(40.0)[:, None, None] * np.array([3.0, -1.5])
    steady = path.copy()
    steady[15:18] = np.nan
    out = smoothed(steady, fps=25.0)
    assert np.isnan(out[15:18]).all()
    assert np.nanmax(np.abs(out - steady)) < 1e-9
    jitter = path + np.random.default_rng(1).normal(0.0, 2.0, path.shape)
    before = np.abs(jitter - path).mean()
    assert np.abs(smoothed(jitter, fps=25.0) - path).mean() < 0.7 * before
    slipped = path.copy()
    slipped[25] += 60.0  # a wrist put on the other hand for one frame
    # dropped, not spread over its neighbours: off by less than a frame's step (3.4 px), not 40 % of the slip
    assert np.abs(smoothed(slipped, fps=25.0) - path).max() < 3.4


@pytest.mark.skipif(not CMU_WALK.exists(), reason="needs ../shared/data/bvh (real motion capture)")
@pytest.mark.parametrize("view", ["front", "three-quarter", "side"])
def test_a_stretch_the_person_model_saw_as_its_mirror_image_is_put_right(view):
    """A person model that takes a back for a front gives the depth mirror image (left and right exchanged,
    depths negated) for a stretch of frames (lift.cues.Cues.unmirrored): a real walk's landmarks with a third
    of a second so read come back as they were, and the walk as seen is left alone."""
    from mocap.body import MIRROR_JOINTS
    from mocap.lift.cues import Cues

    fps = 30.0
    truth = seen(contract_joints(read_bvh(CMU_WALK))[::4], view, fps)
    given = Cues(truth.joints2d, np.ones(truth.joints2d.shape[:2]), truth.joints3d)
    assert given.unmirrored(fps) is given
    stretch = slice(40, 50)
    joints, world = truth.joints2d.copy(), truth.joints3d.copy()
    joints[stretch] = joints[stretch][:, MIRROR_JOINTS]
    world[stretch] = world[stretch][:, MIRROR_JOINTS] * [1.0, 1.0, -1.0]
    put_right = Cues(joints, given.confidence, world).unmirrored(fps)
    assert np.allclose(put_right.joints2d, truth.joints2d)
    assert np.allclose(put_right.world, truth.joints3d)


@pytest.mark.skipif(not CMU_WALK.exists(), reason="needs ../shared/data/bvh (real motion capture)")
@pytest.mark.parametrize("view", ["front", "three-quarter", "side"])
def test_a_stretch_whose_legs_the_person_model_named_the_other_way_round_is_put_right(view):
    """A person model that names a profile's legs the other way round for a stretch of frames, the rest of the body
    right (lift.cues.Cues.limbs_unswapped): a real walk's landmarks with a third of a second of exchanged legs come
    back as they were, and the walk as seen is left alone."""
    from mocap.body import MIRROR_JOINTS
    from mocap.lift.cues import Cues

    fps = 30.0
    truth = seen(contract_joints(read_bvh(CMU_WALK))[::4], view, fps)
    given = Cues(truth.joints2d, np.ones(truth.joints2d.shape[:2]), truth.joints3d)
    assert given.limbs_unswapped(fps) is given
    legs = [JOINT_INDEX[f"{j}_{s}"] for j in ("knee", "ankle") for s in "lr"]
    joints, world = truth.joints2d.copy(), truth.joints3d.copy()
    for array in (joints, world):
        array[40:50, legs] = array[40:50][:, MIRROR_JOINTS[legs]]
    put_right = Cues(joints, given.confidence, world).limbs_unswapped(fps)
    assert np.allclose(put_right.joints2d, truth.joints2d)
    assert np.allclose(put_right.world, truth.joints3d)


@pytest.mark.skipif(not CMU_WALK.exists(), reason="needs ../shared/data/bvh (real motion capture)")
@pytest.mark.parametrize("view", ["front", "three-quarter"])
def test_a_walk_seen_whole_as_its_mirror_image_is_put_right_by_the_heads_look(view):
    """Read as its mirror image from start to end, a walk is as smooth as it was: the head's look (a face toward
    the camera: ``away`` below 0) tells which reading is right (lift.cues.Cues.unmirrored), and where the head
    tells nothing the reading is left as given."""
    from mocap.body import MIRROR_JOINTS
    from mocap.lift.cues import Cues

    fps = 30.0
    truth = seen(contract_joints(read_bvh(CMU_WALK))[::4], view, fps)
    mirrored = Cues(
        truth.joints2d[:, MIRROR_JOINTS],
        np.ones(truth.joints2d.shape[:2]),
        truth.joints3d[:, MIRROR_JOINTS] * [1.0, 1.0, -1.0],
    )
    n = len(truth.joints2d)
    assert mirrored.unmirrored(fps, np.zeros(n)) is mirrored
    put_right = mirrored.unmirrored(fps, np.full(n, -1.0))
    assert np.allclose(put_right.joints2d, truth.joints2d)
    assert np.allclose(put_right.world, truth.joints3d)


def test_a_leg_joint_the_person_models_two_looks_place_apart_is_the_fits():
    """Where the person model's two looks (the frame's and its mirror image's) place a leg joint apart, the 2D is
    the silhouette fit's joint there; a doubtful wrist keeps its landmark, and so does every joint not doubted."""
    fit, marks = np.zeros((2, 16, 2)), np.ones((2, 16, 2))
    doubtful = np.zeros((2, 16), bool)
    doubtful[1, [JOINT_INDEX["knee_l"], JOINT_INDEX["wrist_r"]]] = True
    cues = Cues(marks, np.ones((2, 16)), np.zeros((2, 16, 3)), doubtful)
    joints = with_landmarks(fit, cues)
    from_fit = np.all(joints == 0.0, axis=-1)
    assert np.argwhere(from_fit).tolist() == [[1, JOINT_INDEX["knee_l"]]]


def test_the_world_landmarks_sign_every_segment_but_the_torso():
    """The person model's depths give each segment's first sign (lift.cues.world_signs), toward where the far joint
    is nearer the camera; the torso's lean they do not give (UNSIGNED: it leans the wrong way as often as not)."""
    from mocap.body import SEGMENT_NAMES, SEGMENTS
    from mocap.lift.cues import Cues, world_signs

    world = np.zeros((1, 16, 3))
    for name, (_, far) in SEGMENTS.items():
        world[0, JOINT_INDEX[far], 2] += 0.1 if name.endswith("_l") else -0.1
    world[0, JOINT_INDEX["neck"], 2] = 0.2  # the torso leans toward the camera
    signs = world_signs(Cues(np.zeros((1, 16, 2)), np.ones((1, 16)), world))[0]
    named = dict(zip(SEGMENT_NAMES, signs))
    assert named["torso"] == 0
    assert named["upper_arm_l"] == 1 and named["upper_arm_r"] == -1
