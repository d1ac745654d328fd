"""The root trajectory's depth and the foot contacts, on walks rendered from real motion
capture with a perspective camera against their exact truth; the foot lock."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers import assert_root_comes_nearer

from mocap.body import JOINT_INDEX
from mocap.lift.contacts import FEET, foot_contacts
from mocap.lift.motion import build_motion
from mocap.lift.skeleton import PARENTS, forward_kinematics
from mocap.pipeline import open_session
from mocap.synth import RenderOptions, render_motion
from mocap.synth.walk import walk_cycle

CMU_WALK = Path(__file__).resolve().parents[2] / "shared" / "data" / "bvh" / "cmu_walk.bvh"
SIZE = (320, 240)
FOCAL = 250.0  # px at 320 wide: the performer walks from 6.6 to 3.6 m


def fitted(tmp_path: Path, yaw: float):
    """(truth, motion-file frames) of the CMU walk seen from ``yaw`` (0: from the right
    side; 45: walking toward the camera at 45 degrees), fitted by the silhouette method."""
    if not CMU_WALK.exists():
        pytest.skip(f"{CMU_WALK} absent")
    video = tmp_path / f"walk{int(yaw)}.mp4"
    truth = render_motion(CMU_WALK, video, RenderOptions(yaw=yaw, perspective=FOCAL, size=SIZE))
    return truth, open_session(video).clip().frames


def test_a_walk_toward_the_camera_comes_nearer(tmp_path):
    truth, frames = fitted(tmp_path, 45.0)
    assert_root_comes_nearer(frames, truth)


def test_foot_contacts_agree_with_the_true_ankles(tmp_path):
    truth, frames = fitted(tmp_path, 0.0)
    have = np.array(["contacts" in f for f in frames])
    found = np.array([[f["contacts"][foot] for foot in FEET] for f in frames if "contacts" in f])
    true = foot_contacts(truth.joints3d + truth.pelvis_camera[:, None], truth.fps)[have]
    assert have.mean() > 0.9 and 0.3 < true.mean() < 0.7  # a walk: feet take turns
    assert (found == true).mean() >= 0.9


def test_foot_lock_keeps_planted_feet_still_and_bones_whole():
    """The procedural walk's planted feet slide (up to 0.9 m in a contact); locked, no
    planted ankle moves more than 2 cm in its contact (the body moved where a leg cannot
    reach its pin), the locked motion says the contacts it held, the bones unchanged."""
    joints = walk_cycle(3.0, 30.0)
    pelvis = joints[:, JOINT_INDEX["pelvis"]]
    wobble = 0.01 * np.sin(np.arange(len(joints)) * 2.1)[:, None]  # a fit's jitter
    motion = build_motion(dict(enumerate(joints - pelvis[:, None] + wobble[:, None])), len(joints), 30.0, root=pelvis)
    locked = motion.foot_locked()
    contacts = motion.contacts
    assert contacts.mean() > 0.3 and np.array_equal(locked.contacts, contacts)
    slides = {"before": [], "after": []}
    for k, foot in enumerate(FEET):
        ankle = JOINT_INDEX[foot]
        for start, stop in _runs(contacts[:, k]):
            slides["before"].append(np.ptp(motion.world_joints[start:stop, ankle], axis=0).max())
            slides["after"].append(np.ptp(locked.world_joints[start:stop, ankle], axis=0).max())
    assert max(slides["before"]) > 0.5 and max(slides["after"]) <= 0.02
    for m in (motion, locked):
        positions = forward_kinematics(m.offsets, m.rotations)
        lengths = np.linalg.norm(positions[:, 1:] - positions[:, PARENTS[1:]], axis=-1)
        assert np.ptp(lengths, axis=0).max() < 1e-9
    assert np.abs(locked.offsets - motion.offsets).max() == 0


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    edges = np.diff(np.concatenate([[0], flags.astype(int), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def test_a_body_standing_still_is_moved_back_under_its_planted_feet():
    """A performer standing on both feet whose root's depth wavers (read off the image height): the foot lock
    moves the body back where its feet are (lift.contacts.planted_shift) and leaves the pose alone."""
    from mocap.lift.contacts import foot_lock, planted_shift

    standing = walk_cycle(0.1, 30.0)[:1].repeat(60, axis=0)
    standing[..., 1] -= standing[:, [JOINT_INDEX[f] for f in FEET], 1].min()  # the soles' joints on the floor
    waver = np.zeros((60, 3))
    waver[:, 2] = 0.2 * np.sin(np.arange(60) / 5.0)  # 20 cm to and fro in depth
    world = standing + waver[:, None]
    contacts = np.ones((60, 2), bool)
    shift = planted_shift(world, contacts, 30.0)
    assert np.abs(world + shift[:, None] - (standing + waver.mean(axis=0))).max() < 1e-9
    locked, _ = foot_lock(world, contacts, 30.0)
    assert np.abs(locked - locked[:1]).max() < 1e-6  # nothing moves: no leg was bent to a pin
    contacts[30:] = False  # the feet lift: the body's move fades out with the pins, it does not jump
    shift = planted_shift(world, contacts, 30.0)
    assert np.abs(shift[34:]).max() == 0 and np.abs(np.diff(shift, axis=0)).max() < 0.06
