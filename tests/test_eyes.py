"""What the silhouette method takes from a person model's view (mocap.silhouette.eyes): the head's top read off
the silhouette along the landmarks' neck -> head top line."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from mocap.body import JOINT_INDEX
from mocap.person import Landmarks
from mocap.silhouette.eyes import crowned

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
