"""Which way the body faces (mocap.silhouette.facing): a nose and a chest mark in front of the 3D
body, hair on the back of the rendered head, and the head's look in the video."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import SHARED_DATA

from mocap import body
from mocap.body import JOINT_INDEX
from mocap.io.export.marks import FACING_MARKS, facing_marks
from mocap.lift import taylor as lift
from mocap.pipeline import open_session
from mocap.silhouette.facing import arm_over_head, facing_away, near_limbs
from mocap.silhouette.passes import fit_arrays
from mocap.synth import RenderOptions, render_clip, render_motion
from mocap.synth.walk import walk_cycle

CMU_WALK = SHARED_DATA / "bvh" / "cmu_walk.bvh"


def test_facing_marks_stand_out_of_the_front_and_turn_with_the_body():
    pose = walk_cycle(0.5, 30.0, in_place=True)[0]  # faces +z, the camera
    marks = facing_marks(pose)
    for (segment, *_), (base, out, size) in zip(FACING_MARKS.values(), marks):
        assert out[2] > 0.9, segment  # toward the camera
        start, end = pose[[body.JOINT_INDEX[j] for j in body.SEGMENTS[segment]]]
        axis = (end - start) / np.linalg.norm(end - start)
        off = base - start - ((base - start) @ axis) * axis
        front = body.semi_axes(body.BODY_HEIGHT_M)[body.SEGMENT_INDEX[segment], 1]
        assert abs(np.linalg.norm(off) - front) < 1e-9 and off @ out > 0  # on the front surface
        assert 0.02 < size[0] < 0.2 and 0.02 < size[1] < 0.2  # metres
    turned = pose * [-1.0, 1.0, -1.0]  # half a turn about y: faces away
    np.testing.assert_allclose(facing_marks(turned)[:, :2], marks[:, :2] * [-1.0, 1.0, -1.0], atol=1e-9)


@pytest.mark.skipif(not CMU_WALK.is_file(), reason=f"{CMU_WALK} is absent (real motion capture)")
@pytest.mark.parametrize("yaw, away", [(-45.0, True), (-135.0, True), (45.0, False)])
def test_a_performer_seen_from_behind_is_named_facing_away(tmp_path, yaw, away):
    """A CMU walk seen three-quarter from behind has the silhouette (and the 2D joints)
    of the mirror-image walk seen from the front; the back of the head (rendered with
    hair, as people have) tells them apart: the guessed orientation is backward on
    (almost) every frame, and forward from the front."""
    video = tmp_path / "walk.mp4"
    options = RenderOptions(yaw=yaw, size=(480, 360), fps=15.0, hair=True)
    truth = render_motion(CMU_WALK, video, options, seconds=2.0)
    assert all((abs(lift.yaw_of(p)) > 90) == away for p in truth.joints3d)
    session = open_session(video)
    evidence = facing_away(session.silhouettes, fit_arrays(session.fits)[0], 1.0)
    assert np.mean(evidence > 0 if away else evidence < 0) >= 0.7  # frame by frame
    names = session.inputs.orientation
    assert sum(str(n).startswith("backward" if away else "forward") for n in names) >= 0.9 * len(names)


@pytest.mark.parametrize("yaw", [0.0, 180.0])
def test_the_near_limbs_outlines_name_the_limbs_of_a_profile_walk(tmp_path, yaw):
    """A walk across the frame in profile (facing image right, then left), with no
    input: the near arm's outline shows over the trunk and the near leg's over the far
    leg, while the far ones' are hidden (near_limbs, pooled over the clip, says which
    of the fit's arms and legs is near), and the limbs are named by them: the knees
    and ankles, elbows and wrists of each side lie nearer that side's truth than the
    other's wherever the limbs are apart."""
    video = tmp_path / "walk.mp4"
    truth = render_clip(walk_cycle(1.5, 15.0), video, RenderOptions(yaw=yaw, size=(480, 360), fps=15.0))
    session = open_session(video)
    joints, body_px, _ = fit_arrays(session.fits)
    near_side = "r" if lift.yaw_of(truth.joints3d[0]) > 0 else "l"  # facing image right: the right
    evidence = near_limbs(session.silhouettes, joints, body_px, 1.0)
    for k, tip in enumerate(("wrist", "ankle")):
        ends = [JOINT_INDEX[f"{tip}_{s}"] for s in ("l", "r", near_side)]
        image_left_near = np.linalg.norm(joints[:, ends[0]] - truth.joints2d[:, ends[2]], axis=-1) < np.linalg.norm(
            joints[:, ends[1]] - truth.joints2d[:, ends[2]], axis=-1
        )
        assert np.sum(evidence[:, k] * np.where(image_left_near, 1.0, -1.0)) > 0, tip
    named, true = session.inputs.joints2d, truth.joints2d
    for kind in (("knee", "ankle"), ("elbow", "wrist")):
        sides = [[JOINT_INDEX[f"{n}_{s}"] for n in kind] for s in "lr"]
        own = sum(np.linalg.norm(named[:, j] - true[:, j], axis=-1).sum(1) for j in sides)
        other = sum(np.linalg.norm(named[:, j] - true[:, k], axis=-1).sum(1) for j, k in zip(sides, sides[::-1]))
        apart = np.linalg.norm(true[:, sides[0][-1]] - true[:, sides[1][-1]], axis=-1) > 0.05 * truth.body_height_px
        assert np.mean(own[apart] < other[apart]) >= 0.7, kind


def test_the_heads_look_is_not_read_where_an_arm_lies_over_the_head():
    """A hand raised to the head shows skin or sleeve where hair or face would be:
    arm_over_head says so for an arm reaching over the head's upper part (the band
    hair_share reads), not for arms hanging down or stretched out to the sides, nor
    for a hand held beside the neck, below the band."""
    stand = walk_cycle(0.5, 30.0, in_place=True)[0]
    joints = stand[:, :2] * [1.0, -1.0] * 200 + [320.0, 240.0]  # image pixels, y down
    j = {name: JOINT_INDEX[name] for name in ("neck", "head_top", "shoulder_r", "elbow_r", "wrist_r")}
    assert not arm_over_head(joints)
    head = joints[j["head_top"]] - joints[j["neck"]]
    raised = joints.copy()
    raised[j["elbow_r"]] = joints[j["neck"]] + [-0.6 * np.linalg.norm(head), 0.0] + 0.5 * head
    raised[j["wrist_r"]] = joints[j["neck"]] + 0.8 * head  # the hand on the crown's side
    assert arm_over_head(raised)
    out = joints.copy()
    out[j["elbow_r"]] = joints[j["shoulder_r"]] + [-40.0, 0.0]
    out[j["wrist_r"]] = joints[j["shoulder_r"]] + [-80.0, 0.0]
    assert not arm_over_head(out)
    beside = joints.copy()
    beside[j["wrist_r"]] = joints[j["neck"]] + [-0.3 * np.linalg.norm(head), 0.1 * np.linalg.norm(head)]
    assert not arm_over_head(beside)
