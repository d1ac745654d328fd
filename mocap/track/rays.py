"""Joints on their viewing rays, centre to fringe: the second step of the tracking
paper's reconstruction (Pan, Zhuang and Liu 2000, section "Reconstruction of 3D human
motion skeleton": "we begin with a known neighboring point and use the knowledge of
human skeleton length to find a point" on the joint's ray).

A joint at bone length l from a known joint K lies where its ray meets the sphere of
radius l around K: two points, mirror images in depth. The trunk's joints take the
root nearer the rigid trunk carried by the key triangle. The paper settles the limbs'
choice by continuity from frame to frame; here the choice for each limb (two bones,
four combinations per frame) is made for the whole clip at once by dynamic
programming: the sequence that leaves the joints' ranges least (the same joint limits
as the silhouette method's sign guess: knees and elbows bent the wrong way, an upper
arm or thigh pointing through the trunk, limbs out of the sagittal plane), ties
broken by the smallest sum of squared accelerations of the middle and end joints.
A greedy frame-to-frame choice cannot tell, where a bone passes through the image
plane (the two roots meet), whether it goes on or turns back; acceleration can. The
limits come first (LIMIT_WEIGHT): tracked 2D joints jitter, and the jitter's depth
makes the smoothest sequence a poor judge of which root a limb takes (PA-MPJPE 81.5
mm with acceleration first, 77.1 with the limits first, benchmarks/bench_track.py).
Where a whole limb's mirror image is as smooth and as possible as the limb (a limb
that never crosses the image plane, within its ranges), the choice stays a guess:
the user's foreshortening directions (CONTRACT.md), where given, settle it.
"""

from __future__ import annotations

import numpy as np

from mocap import body
from mocap.body import JOINT_INDEX, SIDE_SIGN
from mocap.body import limb_penalty as joint_limits
from mocap.smoothest import smoothest_states

# (root, middle, end, leg, side): side +1 left, -1 right
LIMBS = tuple((*(JOINT_INDEX[j] for j in one.joints), one.kind == "leg", SIDE_SIGN[one.side])
              for one in body.LIMBS)
LIMIT_WEIGHT = 3.0      # m^2 of squared acceleration that a unit of joint-limit penalty costs


def ray_roots(known: np.ndarray, rays: np.ndarray, length: float) -> np.ndarray:
    """(..., 2, 3) the two points on each ray (..., 3) through the optical centre at
    ``length`` from ``known`` (..., 3), the nearer first; where the ray passes
    farther than ``length`` (2D tracking error) both are its point nearest ``known``."""
    u = rays / np.linalg.norm(rays, axis=-1, keepdims=True)
    along = (u * known).sum(-1)
    half = np.sqrt(np.maximum(along ** 2 - (known * known).sum(-1) + length ** 2, 0.0))
    return np.stack([(along - half)[..., None] * u, (along + half)[..., None] * u], axis=-2)


def toward_signs(depths: np.ndarray) -> np.ndarray:
    """(..., n-1) foreshortening of the segments of a chain of joints from the depths
    (pinhole Z) of its joints (..., n), proximal first: +1 toward (the distal joint
    nearer the camera), -1 away (CONTRACT.md's words)."""
    return np.where(depths[..., 1:] < depths[..., :-1], 1, -1)


def signs_allowed(signs: np.ndarray, fixed: np.ndarray) -> np.ndarray:
    """(F, C) bool: the candidates whose segments' signs (F, C, S) are the user's
    ``fixed`` (F, S) (+1, -1; 0 where the user said nothing). A frame where no
    candidate has them (the roots coincide: the segment crosses the image plane)
    allows all."""
    ok = ((fixed[:, None, :] == 0) | (signs == fixed[:, None, :])).all(axis=-1)
    return ok | ~ok.any(axis=1, keepdims=True)


def limb_candidates(root: np.ndarray, rays: np.ndarray, lengths: tuple[float, float]) -> np.ndarray:
    """(F, 4, 2, 3) the middle and end joint of a limb for each of the four root
    choices (middle near/far x end near/far) on every frame; ``root`` (F, 3), ``rays``
    (F, 2, 3) of the middle and end joints."""
    middle = ray_roots(root, rays[:, 0], lengths[0])                      # (F, 2, 3)
    end = ray_roots(middle, rays[:, 1, None, :], lengths[1])              # (F, 2, 2, 3)
    return np.stack([np.repeat(middle, 2, axis=1), end.reshape(-1, 4, 3)], axis=2)


def limb_penalty(root: np.ndarray, cands: np.ndarray, axes: np.ndarray, leg: bool,
                 side: float) -> np.ndarray:
    """(F, 4) how far each candidate leaves the joints' ranges (0 inside): the
    silhouette method's joint limits (orientation.limb_penalty: hinges bent the right
    way, an upper arm or thigh not through the trunk, limbs near the sagittal plane)
    in the body frame ``axes`` (F, 3, 3) (columns: the performer's left, up, forward)."""
    upper = cands[:, :, 0] - root[:, None]
    lower = cands[:, :, 1] - cands[:, :, 0]
    return joint_limits(upper, lower, axes[:, None, :, 2], axes[:, None, :, 0], side, leg)


def choose_limb(relative: np.ndarray, penalty: np.ndarray,
                allowed: np.ndarray | None = None) -> np.ndarray:
    """(F,) the candidate index per frame minimising LIMIT_WEIGHT * penalty plus the
    squared accelerations of the candidates' joints ``relative`` (F, 4, 2, 3) to the
    limb's root, among the ``allowed`` ones (F, 4) (the user's foreshortening, see
    ``signs_allowed``): a Viterbi search over pairs of consecutive choices."""
    return smoothest_states(relative.reshape(len(relative), 4, -1), LIMIT_WEIGHT * penalty,
                            allowed, squared=True)
