"""What the silhouette method takes from a person model's view (mocap.silhouette.eyes): the head's top and the
ankles read off the silhouette along the landmarks' neck -> head top and knee -> ankle lines."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from mocap.body import FOOT_LENGTH, JOINT_INDEX, LENGTH, SEGMENT_INDEX
from mocap.person import Landmarks
from mocap.silhouette.eyes import crowned, fit_targets, soled

_HEAD_TOP, _NECK = JOINT_INDEX["head_top"], JOINT_INDEX["neck"]


def head_landmarks(neck: tuple[float, float], top: tuple[float, float]) -> Landmarks:
    """Landmarks whose neck and head top are as given (the other joints play no part)."""
    joints = np.zeros((16, 2))
    joints[_NECK], joints[_HEAD_TOP] = neck, top
    return Landmarks(joints, np.ones(16), np.zeros((16, 3)))


def head_mask(centre: tuple[int, int], radius: int) -> np.ndarray:
    """A 200x200 silhouette: a round head over a neck and trunk below it."""
    mask = np.zeros((200, 200), np.uint8)
    cv2.circle(mask, centre, radius, 255, -1)
    cv2.rectangle(mask, (centre[0] - 30, centre[1] + radius - 5), (centre[0] + 30, 199), 255, -1)
    return mask


def test_the_head_top_is_where_the_silhouette_ends_along_the_head():
    mask = head_mask((100, 60), 20)  # the crown at row 40
    for given in (20.0, 52.0):  # the proportions' head top above the crown, or below it
        top = crowned(head_landmarks((100, 85), (100, given)), mask).joints2d[_HEAD_TOP]
        assert np.allclose(top, (100, 40), atol=1.0), (given, top)


def test_a_tilted_head_is_read_along_its_own_line():
    mask = head_mask((100, 60), 20)
    top = crowned(head_landmarks((80, 85), (94, 30)), mask).joints2d[_HEAD_TOP]
    assert np.hypot(*(top - (100, 60))) == pytest.approx(20, abs=1.5)
    assert top[0] > 88  # on the line, not straight above the neck


def test_the_head_top_is_kept_where_the_silhouette_cannot_tell():
    mask = head_mask((100, 60), 20)
    raised = mask.copy()
    raised[:40, 95:106] = 255  # a hand held over the head, up out of the frame
    elsewhere = crowned(head_landmarks((160, 85), (160, 30)), mask)  # the line's middle off the silhouette
    for landmarks, silhouette in ((head_landmarks((100, 85), (100, 30)), raised), (elsewhere, mask)):
        assert np.array_equal(crowned(landmarks, silhouette).joints2d, landmarks.joints2d)


def standing_landmarks(ankle_y: float, scale: float) -> Landmarks:
    """Upright landmarks, ``scale`` pixels per model unit, pelvis at (100, 100), both ankles at row ``ankle_y``."""
    joints = np.zeros((16, 2))
    leg = LENGTH[SEGMENT_INDEX["upper_leg_l"]] * scale
    for side, x in (("l", 110.0), ("r", 90.0)):
        joints[JOINT_INDEX[f"hip_{side}"]] = (x, 100.0)
        joints[JOINT_INDEX[f"knee_{side}"]] = (x, 100.0 + leg)
        joints[JOINT_INDEX[f"ankle_{side}"]] = (x, ankle_y)
    joints[JOINT_INDEX["pelvis"]] = (100.0, 100.0)
    joints[_NECK] = (100.0, 100.0 - LENGTH[SEGMENT_INDEX["torso"]] * scale)
    return Landmarks(joints, np.ones(16), np.zeros((16, 3)))


def test_each_ankle_is_a_foot_height_above_its_sole():
    scale = 1.0  # pixels per model unit: the trunk and thighs at full length, the knees at row 146, soles at 205
    mask = np.zeros((260, 200), np.uint8)
    mask[95:206, 80:121] = 255
    for given in (190.0, 200.0):  # a shoe's outline made the ankle high, or a low one
        ankles = soled(standing_landmarks(given, scale), mask).joints2d[
            [JOINT_INDEX["ankle_l"], JOINT_INDEX["ankle_r"]]
        ]
        assert np.allclose(ankles[:, 1], 205 - FOOT_LENGTH * scale, atol=1.0), (given, ankles)
        assert np.allclose(ankles[:, 0], (110, 90))


def test_an_ankle_is_kept_where_the_silhouette_runs_on_below_it():
    mask = np.zeros((260, 200), np.uint8)
    mask[95:260, 80:121] = 255  # the legs go on out of the frame
    landmarks = standing_landmarks(190.0, 1.0)
    assert np.array_equal(soled(landmarks, mask).joints2d, landmarks.joints2d)


def test_a_joint_the_two_looks_place_apart_does_not_draw_the_fit():
    """The fit's searches are drawn to each landmark by its confidence, but not to one the person model's two
    looks (the frame's and its mirror image's) place apart: the silhouette answers there."""
    joints = np.column_stack([np.linspace(10, 160, 16), np.linspace(20, 180, 16)])
    doubtful = np.zeros(16, bool)
    doubtful[JOINT_INDEX["ankle_l"]] = True
    marks = Landmarks(joints, np.full(16, 0.9), np.zeros((16, 3)), doubtful)
    weight = fit_targets(marks, np.zeros(2), 1.0, 1.0, None).weight
    assert weight[JOINT_INDEX["ankle_l"]] == 0.0 and weight[JOINT_INDEX["ankle_r"]] == pytest.approx(0.9)
    assert (
        fit_targets(Landmarks(joints, np.full(16, 0.9), np.zeros((16, 3))), np.zeros(2), 1.0, 1.0, None).weight.min()
        > 0
    )
