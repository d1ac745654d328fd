"""The 2D body model the silhouette method fits (the 2013 paper, section 3.1): ten
cylinders seen as rectangles, posed by the pelvis, a scale, each segment's image angle
and foreshortening ratio (Algorithm 6) and the seen share of the shoulder and hip span."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mocap.body import (
    CHEST_FRACTION,
    HIP_HALF_SPAN,
    JOINT_INDEX,
    JOINTS,
    LENGTH,
    SEGMENT_INDEX,
    SEGMENT_NAMES,
    SEGMENTS,
    SHOULDER_DROP,
    SHOULDER_HALF_SPAN,
    SIDE_SIGN,
)


def image_angle(d: np.ndarray) -> float:
    """The angle (degrees, y up) of an image vector ``d`` (x right, y down): inverse of ``direction``."""
    return float(np.degrees(np.arctan2(-d[1], d[0])))


@dataclass(frozen=True)
class Pose2D:
    """The 2D model. ``angle``, ``ratio`` are indexed like SEGMENT_NAMES; ``ratio`` is
    Algorithm 6's foreshortening ratio (projected / model length); ``spread`` in [0, 1]
    is the seen share of the shoulder and hip span (1 facing the camera, 0 in profile)."""

    pelvis: np.ndarray  # (2,) pixels
    scale: float  # pixels per model unit
    angle: np.ndarray = field(default_factory=lambda: default_angles())
    ratio: np.ndarray = field(default_factory=lambda: np.ones(len(SEGMENT_NAMES)))
    spread: float = 1.0


def default_angles() -> np.ndarray:
    """Standing upright, arms and legs hanging straight down."""
    return np.array([90.0 if s in ("torso", "head") else 270.0 for s in SEGMENT_NAMES])


def forward_kinematics_2d(pose: Pose2D) -> np.ndarray:
    """Joint positions (16, 2) in pixels from a 2D pose (image-side left/right)."""
    return forward_kinematics_2d_batch(
        np.asarray(pose.pelvis, float)[None], pose.scale, pose.angle[None], pose.ratio[None], np.array([pose.spread])
    )[0]


def _kinematic_matrix() -> np.ndarray:
    """(16, 12) weights giving each joint from [pelvis, 10 segment vectors, span]."""
    m = np.zeros((len(JOINTS), 12))
    m[JOINT_INDEX["pelvis"], 0] = 1.0
    m[JOINT_INDEX["neck"]] = m[JOINT_INDEX["pelvis"]]
    m[JOINT_INDEX["neck"], 1 + SEGMENT_INDEX["torso"]] = 1.0
    m[JOINT_INDEX["chest"]] = m[JOINT_INDEX["pelvis"]]
    m[JOINT_INDEX["chest"], 1 + SEGMENT_INDEX["torso"]] = CHEST_FRACTION
    m[JOINT_INDEX["head_top"]] = m[JOINT_INDEX["neck"]]
    m[JOINT_INDEX["head_top"], 1 + SEGMENT_INDEX["head"]] = 1.0
    for side, sign in SIDE_SIGN.items():
        m[JOINT_INDEX[f"shoulder_{side}"]] = m[JOINT_INDEX["neck"]]
        m[JOINT_INDEX[f"shoulder_{side}"], 1 + SEGMENT_INDEX["torso"]] -= SHOULDER_DROP / LENGTH[SEGMENT_INDEX["torso"]]
        m[JOINT_INDEX[f"shoulder_{side}"], 11] = sign * SHOULDER_HALF_SPAN
        m[JOINT_INDEX[f"hip_{side}"]] = m[JOINT_INDEX["pelvis"]]
        m[JOINT_INDEX[f"hip_{side}"], 11] = sign * HIP_HALF_SPAN
    for seg, (a, b) in list(SEGMENTS.items())[2:]:
        m[JOINT_INDEX[b]] = m[JOINT_INDEX[a]]
        m[JOINT_INDEX[b], 1 + SEGMENT_INDEX[seg]] = 1.0
    return m


KINEMATIC_MATRIX = _kinematic_matrix()


def forward_kinematics_2d_batch(
    pelvis: np.ndarray, scale: float, angle: np.ndarray, ratio: np.ndarray, spread: np.ndarray
) -> np.ndarray:
    """Joints (B, 16, 2) of B poses (B, 2), (B, 10), (B, 10), (B,) (pelvis (2,), spread a
    float where shared): KINEMATIC_MATRIX times ``kinematic_basis``'s vectors."""
    return joints_of_basis(kinematic_basis(pelvis, scale, angle, ratio, spread)[0])


def kinematic_basis(
    pelvis: np.ndarray, scale: float, angle: np.ndarray, ratio: np.ndarray, spread, rows: int = 12
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pelvis, the 10 segment vectors and the image-left unit vector scaled by the
    seen span of B poses: the first 12 of ``rows`` vectors (rows, B, 2), the rest left
    to the caller; and the cosines and sines (10, B) of the segments' angles."""
    a = np.radians(angle).T  # (10, B)
    cos, sin = np.cos(a), np.sin(a)
    length = LENGTH[:, None] * ratio.T * scale
    basis = np.empty((rows, len(angle), 2))
    basis[0] = pelvis
    basis[1:11, :, 0] = cos * length
    basis[1:11, :, 1] = -sin * length
    sin_t, cos_t = sin[SEGMENT_INDEX["torso"]], cos[SEGMENT_INDEX["torso"]]
    span = spread * scale
    # image-left normal of the torso axis: (-sin t, -cos t), flipped if the torso points down
    basis[11, :, 0] = -np.abs(sin_t) * span
    basis[11, :, 1] = -np.copysign(cos_t, sin_t) * span
    return basis, cos, sin


def joints_of_basis(basis: np.ndarray) -> np.ndarray:
    """Joints (B, 16, 2) of ``kinematic_basis``'s vectors."""
    return (KINEMATIC_MATRIX @ basis[:12].reshape(12, -1)).reshape(len(JOINTS), -1, 2).transpose(1, 0, 2)
