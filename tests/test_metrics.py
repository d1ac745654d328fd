"""Error measures against hand marks, whose pairs name no anatomical side."""

from __future__ import annotations

import numpy as np
import pytest

from mocap.body import JOINT_INDEX, JOINTS
from mocap.synth.metrics import labelled_body_height, labelled_errors


def standing(x: float) -> np.ndarray:
    """(16, 2) joints of a figure standing at image x, left side to the image right."""
    joints = np.zeros((len(JOINTS), 2))
    for name, (dx, y) in {
        "head_top": (0, 0),
        "neck": (0, 12),
        "chest": (0, 20),
        "pelvis": (0, 38),
        "shoulder": (6, 15),
        "elbow": (7, 27),
        "wrist": (8, 37),
        "hip": (3, 38),
        "knee": (3, 54),
        "ankle": (3, 70),
    }.items():
        for side, sign in (("_l", 1), ("_r", -1), ("", 0)):
            if name + side in JOINT_INDEX:
                joints[JOINT_INDEX[name + side]] = (x + sign * dx, y)
    return joints


def test_marks_of_either_side_match_the_joints_they_mark():
    joints = standing(50.0)[None]
    marks = {
        "0": {"head_top": [50, 0], "knee_a": [47, 54], "knee_b": [53, 54], "ankle_a": [53, 70], "wrist_a": [42, 37]}
    }
    errors = labelled_errors(joints, marks)
    assert set(errors) == {"head_top", "knee", "ankle", "wrist"}
    assert all(np.allclose(e, 0.0) for e in errors.values())
    assert len(errors["knee"]) == 2 and len(errors["wrist"]) == 1


def test_a_joint_off_its_mark_is_off_by_its_distance_and_pairs_are_not_swapped_to_hide_it():
    joints = np.stack([standing(50.0), standing(60.0)])
    joints[1, JOINT_INDEX["ankle_l"]] += (3.0, -4.0)
    marks = {"1": {"pelvis": [60, 38], "ankle_a": [57, 70], "ankle_b": [63, 70]}}
    errors = labelled_errors(joints, marks)
    assert errors["pelvis"] == pytest.approx([0.0])
    assert sorted(errors["ankle"]) == pytest.approx([0.0, 5.0])
    assert labelled_body_height(
        {
            "0": {"head_top": [0, 10], "ankle_a": [0, 80], "ankle_b": [0, 84]},
            "3": {"head_top": [0, 12], "ankle_a": [0, 86]},
        }
    ) == pytest.approx(74.0)
