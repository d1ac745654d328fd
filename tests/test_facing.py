"""The facing marks (mocap.facing): a nose and a chest mark in front of the body."""

from __future__ import annotations

import numpy as np

from mocap import body
from mocap.facing import FACING_MARKS, facing_marks
from mocap.walk import walk_cycle


def test_facing_marks_stand_out_of_the_front_and_turn_with_the_body():
    pose = walk_cycle(0.5, 30.0, in_place=True)[0]            # faces +z, the camera
    marks = facing_marks(pose)
    for (segment, *_), (base, out, size) in zip(FACING_MARKS.values(), marks):
        assert out[2] > 0.9, segment                               # toward the camera
        start, end = pose[[body.JOINT_INDEX[j] for j in body.SEGMENTS[segment]]]
        axis = (end - start) / np.linalg.norm(end - start)
        off = base - start - ((base - start) @ axis) * axis
        front = body.semi_axes(body.BODY_HEIGHT_M)[body.SEGMENT_INDEX[segment], 1]
        assert abs(np.linalg.norm(off) - front) < 1e-9 and off @ out > 0   # on the front surface
        assert 0.02 < size[0] < 0.2 and 0.02 < size[1] < 0.2                 # metres
    turned = pose * [-1.0, 1.0, -1.0]                          # half a turn about y: faces away
    np.testing.assert_allclose(facing_marks(turned)[:, :2], marks[:, :2] * [-1.0, 1.0, -1.0], atol=1e-9)
