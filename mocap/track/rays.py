"""Joints on their viewing rays, centre to fringe (Pan, Zhuang and Liu 2000, reconstruction): two roots per joint,
mirror images in depth; beyond the paper, each limb's are chosen over the clip by dynamic programming."""

from __future__ import annotations

import numpy as np

from mocap import body
from mocap.body import JOINT_INDEX, SIDE_SIGN
from mocap.body import limb_penalty as joint_limits
from mocap.smoothest import smoothest_states

# (root, middle, end, leg, side): side +1 left, -1 right
LIMBS = tuple((*(JOINT_INDEX[j] for j in one.joints), one.kind == "leg", SIDE_SIGN[one.side]) for one in body.LIMBS)
LIMIT_WEIGHT = 3.0  # m^2 of squared acceleration that a unit of joint-limit penalty costs


def ray_roots(known: np.ndarray, rays: np.ndarray, length: float) -> np.ndarray:
    """(..., 2, 3) points on rays (..., 3) at ``length`` from ``known`` (..., 3), nearer first (or both nearest)."""
    u = rays / np.linalg.norm(rays, axis=-1, keepdims=True)
    along = (u * known).sum(-1)
    half = np.sqrt(np.maximum(along**2 - (known * known).sum(-1) + length**2, 0.0))
    return np.stack([(along - half)[..., None] * u, (along + half)[..., None] * u], axis=-2)


def toward_signs(depths: np.ndarray) -> np.ndarray:
    """(..., n-1) segment signs from a chain's depths (..., n), proximal first: +1 toward the camera, -1 away."""
    return np.where(depths[..., 1:] < depths[..., :-1], 1, -1)


def signs_allowed(signs: np.ndarray, fixed: np.ndarray) -> np.ndarray:
    """(F, C) bool: candidates with signs (F, C, S) as ``fixed`` (F, S) (+1, -1, 0 unsaid); all where none is."""
    ok = ((fixed[:, None, :] == 0) | (signs == fixed[:, None, :])).all(axis=-1)
    return ok | ~ok.any(axis=1, keepdims=True)


def limb_candidates(root: np.ndarray, rays: np.ndarray, lengths: tuple[float, float]) -> np.ndarray:
    """(F, 4, 2, 3) middle, end joints per root choice (middle near/far x end near/far) of ``root`` (F, 3)."""
    middle = ray_roots(root, rays[:, 0], lengths[0])  # (F, 2, 3)
    end = ray_roots(middle, rays[:, 1, None, :], lengths[1])  # (F, 2, 2, 3)
    return np.stack([np.repeat(middle, 2, axis=1), end.reshape(-1, 4, 3)], axis=2)


def limb_penalty(root: np.ndarray, cands: np.ndarray, axes: np.ndarray, leg: bool, side: float) -> np.ndarray:
    """(F, 4) how far candidates leave the joint ranges (body.limb_penalty); ``axes`` (F, 3, 3): left, up, forward."""
    upper = cands[:, :, 0] - root[:, None]
    lower = cands[:, :, 1] - cands[:, :, 0]
    return joint_limits(upper, lower, axes[:, None, :, 2], axes[:, None, :, 0], side, leg)


def choose_limb(relative: np.ndarray, penalty: np.ndarray, allowed: np.ndarray | None = None) -> np.ndarray:
    """(F,) candidate per frame minimising LIMIT_WEIGHT * penalty plus squared accelerations of ``relative``
    (F, 4, 2, 3) to the root, among ``allowed`` (F, 4): a Viterbi search."""
    return smoothest_states(relative.reshape(len(relative), 4, -1), LIMIT_WEIGHT * penalty, allowed, squared=True)
