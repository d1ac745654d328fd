"""Keyframes -> every frame: rotations, slerp, constant bones, root, smoothing."""

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from mocap import body
from mocap.errors import MocapError
from mocap.io.bvh_reader import contract_joints, read_bvh
from mocap.lift.motion import build_motion
from mocap.lift.skeleton import BONES, JOINT_BONES, PARENTS, forward_kinematics, rest_positions
from mocap.synth import resample_indices
from mocap.synth.walk import walk_cycle

CMU_WALK = Path(__file__).resolve().parents[2] / "shared" / "data" / "bvh" / "cmu_walk.bvh"
FPS = 30.0


def segment_lengths(joints: np.ndarray) -> np.ndarray:
    """(F, 10) lengths of the 10 segments."""
    ends = body.segment_endpoints(joints)
    return np.linalg.norm(ends[..., 1, :] - ends[..., 0, :], axis=-1)


def bone_lengths(motion) -> np.ndarray:
    """(F, bones) every bone's length on every frame, from the posed skeleton."""
    positions = forward_kinematics(motion.offsets, motion.rotations)
    return np.linalg.norm(positions[:, 1:] - positions[:, PARENTS[1:]], axis=-1)


def keyframes_of(joints: np.ndarray, step: int) -> dict[int, np.ndarray]:
    """Every step-th frame of (F, 16, 3) joints as a keyframe dict."""
    return {i: joints[i] for i in range(0, len(joints), step)}


@pytest.fixture(scope="module")
def walk():
    """Two seconds of the procedural walk (world joints, moving forward)."""
    return walk_cycle(2.0, FPS)


def test_bones_are_depth_first_tree():
    assert PARENTS[0] == -1 and all(0 <= p < b for b, p in enumerate(PARENTS) if b)
    assert len(set(JOINT_BONES)) == len(body.JOINTS)
    assert {
        "Hips",
        "Spine",
        "Spine1",
        "Neck",
        "Head",
        "LeftShoulder",
        "RightShoulder",
        "LeftArm",
        "LeftForeArm",
        "LeftHand",
        "LeftUpLeg",
        "LeftLeg",
        "LeftFoot",
        "LeftToeBase",
    } <= set(BONES)


def test_one_symmetric_body_in_a_t_pose():
    """Left and right bones are mirror images; at rest the arms stretch out sideways."""
    joints = walk_cycle(1.0, FPS)
    joints[:, body.JOINT_INDEX["elbow_l"]] *= 1.1  # a longer left arm in the input
    motion = build_motion(keyframes_of(joints, 2), len(joints), FPS)
    lengths = np.linalg.norm(motion.offsets, axis=-1)
    for b, name in enumerate(BONES):
        if name.startswith("Left"):
            twin = BONES.index("Right" + name[4:])
            assert motion.offsets[b] == pytest.approx(motion.offsets[twin] * [-1, 1, 1]), name
    rest = rest_positions(motion.offsets)
    arm = rest[[BONES.index(b) for b in ("LeftArm", "LeftForeArm", "LeftHand", "LeftHand_End")]]
    assert np.abs(np.diff(arm[:, 1:], axis=0)).max() < 1e-12 and (np.diff(arm[:, 0]) > 0).all()
    assert lengths[BONES.index("LeftForeArm")] > 0.2


def test_every_frame_a_keyframe_reproduces_the_input(walk):
    pelvis = walk[:, body.JOINT_INDEX["pelvis"]]
    motion = build_motion(keyframes_of(walk - pelvis[:, None], 1), len(walk), FPS, root=pelvis)
    assert motion.keyframes.all()
    assert np.abs(motion.rooted_joints - walk).max() < 1e-9
    assert np.abs(motion.joints3d[:, body.JOINT_INDEX["pelvis"]]).max() < 1e-12


def test_random_contract_poses_are_reproduced():
    """Any pose of the body (hips, chest and limbs turned anyhow, the shoulder line
    tilted against the chest) comes back exactly from its joints."""
    rng = np.random.default_rng(0)
    base = build_motion({0: walk_cycle(0.1, FPS)[0]}, 1, FPS)
    rot = Rotation.random(40 * len(BONES), random_state=1).as_quat().reshape(40, len(BONES), 4)
    # the lower spine only twists (the contract body's pelvis, Spine and chest lie on
    # one line); the clavicles tilt together in the chest's frontal plane; the head
    # continues the neck (the contract's head is one segment)
    rot[:, BONES.index("Spine")] = Rotation.from_euler("y", rng.uniform(-90, 90, (40, 1)), degrees=True).as_quat()
    tilt = Rotation.from_euler("z", rng.uniform(-30, 30, (40, 1)), degrees=True).as_quat()
    rot[:, BONES.index("LeftShoulder")] = rot[:, BONES.index("RightShoulder")] = tilt
    rot[:, BONES.index("Head")] = [0.0, 0.0, 0.0, 1.0]
    joints = forward_kinematics(base.offsets, rot)[:, JOINT_BONES]
    motion = build_motion(keyframes_of(joints, 1), len(joints), FPS)
    assert np.abs(motion.joints3d - joints).max() < 1e-9


def test_sparse_keyframes(walk):
    keys = keyframes_of(walk, 3)
    motion = build_motion(keys, len(walk), FPS)
    err = np.linalg.norm(motion.rooted_joints - walk, axis=-1)[: max(keys) + 1]
    assert motion.keyframes.sum() == len(keys) and err[list(keys)].max() < 1e-9
    lengths = segment_lengths(motion.joints3d)
    assert np.ptp(lengths, axis=0).max() < 1e-9  # interpolated bones keep length
    assert err.mean() < 0.005 and err.max() < 0.06  # slerp follows the walk
    assert np.allclose(np.linalg.norm(motion.rotations, axis=-1), 1.0)
    assert (np.sum(motion.rotations[1:] * motion.rotations[:-1], axis=-1) >= 0).all()


def test_hold_outside_the_keyframes(walk):
    motion = build_motion({5: walk[5], 9: walk[9]}, 15, FPS)
    assert np.allclose(motion.rooted_joints[:5], walk[5], atol=1e-9)
    assert np.allclose(motion.rooted_joints[9:], walk[9], atol=1e-9)


def test_single_keyframe_holds_everywhere(walk):
    motion = build_motion({3: walk[3]}, 8, FPS)
    assert np.allclose(motion.rooted_joints, walk[3], atol=1e-9)
    assert motion.keyframes.tolist() == [i == 3 for i in range(8)]


def test_root_track_fills_gaps(walk):
    root = np.full((len(walk), 3), np.nan)
    root[[0, 10]] = [[0.0, 1.0, 0.0], [1.0, 1.0, 2.0]]
    motion = build_motion({0: walk[0]}, len(walk), FPS, root=root)
    assert np.allclose(motion.root[5], [0.5, 1.0, 1.0]) and np.allclose(motion.root[20], root[10])
    assert np.abs(motion.joints3d[:, body.JOINT_INDEX["pelvis"]]).max() < 1e-12


def test_smoothing_keeps_keyframes_and_smooths(walk):
    """Slerp turns at every keyframe; smoothing takes out those corners (less
    squared acceleration) and so also comes closer to the true walk."""
    keys = keyframes_of(walk, 4)
    plain = build_motion(keys, len(walk), FPS)
    smooth = build_motion(keys, len(walk), FPS, smooth=2.0)
    assert np.abs(smooth.rooted_joints[list(keys)] - walk[list(keys)]).max() < 1e-9
    assert np.ptp(segment_lengths(smooth.joints3d), axis=0).max() < 1e-9

    def acceleration(m):
        return np.sum(np.diff(m.joints3d, 2, axis=0) ** 2)

    def error(m):
        return np.linalg.norm(m.rooted_joints - walk, axis=-1)[: max(keys) + 1].mean()

    assert acceleration(smooth) < 0.6 * acceleration(plain)
    assert error(smooth) < 0.8 * error(plain)


def test_degenerate_bones():
    pose = walk_cycle(0.1, FPS)[0]
    flat = pose.copy()
    flat[body.JOINT_INDEX["wrist_l"]] = flat[body.JOINT_INDEX["elbow_l"]]  # zero length
    up = pose.copy()  # an arm straight up: opposite its rest direction
    shoulder = up[body.JOINT_INDEX["shoulder_r"]]
    upper, lower = (body.LENGTH[body.SEGMENT_INDEX[s]] / 100.0 for s in ("upper_arm_r", "lower_arm_r"))
    up[body.JOINT_INDEX["elbow_r"]] = shoulder + [0.0, upper, 0.0]
    up[body.JOINT_INDEX["wrist_r"]] = shoulder + [0.0, upper + lower, 0.0]
    motion = build_motion({0: pose, 2: flat, 4: up, 6: np.zeros((16, 3))}, 7, FPS)
    assert np.isfinite(motion.joints3d).all() and np.isfinite(motion.rotations).all()
    assert np.abs(motion.rooted_joints[4] - up).max() < 1e-9


@pytest.mark.parametrize(
    "keys, n, fps, kwargs",
    [
        ({}, 5, FPS, {}),
        ({7: np.zeros((16, 3))}, 5, FPS, {}),
        ({0: np.zeros((15, 3))}, 5, FPS, {}),
        ({0: np.full((16, 3), np.nan)}, 5, FPS, {}),
        ({0: np.zeros((16, 3))}, 5, 0.0, {}),
        ({0: np.zeros((16, 3))}, 5, FPS, {"root": np.zeros((4, 3))}),
        ({0: np.zeros((16, 3))}, 5, FPS, {"smooth": -1.0}),
    ],
)
def test_bad_requests_are_refused(keys, n, fps, kwargs):
    with pytest.raises(MocapError):
        build_motion(keys, n, fps, **kwargs)


def test_real_motion_capture():
    """CMU walk at 30 fps: keyframes come back within the spread of the capture's
    own segment lengths (its spine bends), every frame keeps constant bones."""
    if not CMU_WALK.exists():
        pytest.skip(f"{CMU_WALK} absent")
    capture = read_bvh(CMU_WALK)
    joints = contract_joints(capture)
    joints = joints[resample_indices(len(joints), capture.frame_time, FPS, None, None)]
    pelvis = joints[:, body.JOINT_INDEX["pelvis"]]
    keys = keyframes_of(joints - pelvis[:, None], 3)
    motion = build_motion(keys, len(joints), FPS, root=pelvis, smooth=1.0)
    err = np.linalg.norm(motion.rooted_joints - joints, axis=-1)[list(keys)]
    assert err.max() < 0.01
    assert np.ptp(bone_lengths(motion), axis=0).max() < 1e-9
