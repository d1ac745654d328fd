"""The skeleton declared once (body.JOINT_PARENT) and the views the methods derive from it."""

from __future__ import annotations

import numpy as np

from mocap import body


def test_tree_has_one_root_and_mirrors():
    parents = body.JOINT_PARENTS
    assert (parents == -1).sum() == 1 and body.JOINTS[int(np.flatnonzero(parents == -1)[0])] == "pelvis"
    assert body.JOINT_PARENT["chest"] == "pelvis" and body.JOINT_PARENT["shoulder_l"] == "chest"
    mirror = body.MIRROR_JOINTS
    for j, p in enumerate(parents):
        if p >= 0:
            assert parents[mirror[j]] == mirror[p]
    assert (mirror[mirror] == np.arange(len(body.JOINTS))).all()


def test_limbs_are_chains_of_the_tree_along_their_segments():
    assert [(one.kind, one.side) for one in body.LIMBS] == [("arm", "l"), ("leg", "l"), ("arm", "r"), ("leg", "r")]
    for one in body.LIMBS:
        root, middle, end = one.joints
        assert body.JOINT_PARENT[middle] == root and body.JOINT_PARENT[end] == middle
        assert one.segments == (body.SEGMENT_OF_BONE[root, middle], body.SEGMENT_OF_BONE[middle, end])
    assert body.LIMB_JOINTS == {"arm": ("shoulder", "elbow", "wrist"), "leg": ("hip", "knee", "ankle")}


def test_bones_from_the_key_triangle_place_every_joint_once_after_its_known_end():
    known = ("shoulder_l", "shoulder_r", "chest")
    bones = body.bones_from(known)
    placed = [b for _, b in bones]
    assert sorted(placed + list(known)) == sorted(body.JOINTS)
    for n, (a, b) in enumerate(bones):
        assert a in known or a in placed[:n]
        assert body.JOINT_PARENT[b] == a or body.JOINT_PARENT[a] == b


def test_left_direction_points_to_the_performers_left():
    standing = np.zeros((len(body.JOINTS), 3))
    for side, sign in body.SIDE_SIGN.items():
        for kind in ("shoulder", "hip"):
            standing[body.JOINT_INDEX[f"{kind}_{side}"], 0] = sign
    assert np.allclose(body.left_direction(standing), [4.0, 0.0, 0.0])
