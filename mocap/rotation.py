"""Rotations of the skeleton: the part of scipy.spatial.transform's Rotation and Slerp
that the lift uses, in numpy with scipy's formulas (tests/test_rotation.py holds them
to scipy's), since importing scipy.spatial takes a quarter of a second of every
`mocap fit`'s start.

A Rotation holds K unit quaternions (K, 4), scalar last (x, y, z, w).
"""

from __future__ import annotations

import numpy as np

SMALL_ANGLE = 1e-3      # radians: below it the rotation vector's scale is its Taylor series
ORTHOGONAL_ATOL = 1e-12  # a matrix's Gram matrix this near the identity is orthogonal


class Rotation:
    """K rotations; ``r * s`` applies ``s`` first, then ``r``."""

    def __init__(self, quat: np.ndarray):
        self._quat = quat

    @classmethod
    def from_quat(cls, quat: np.ndarray) -> Rotation:
        """From quaternions (K, 4), normalised."""
        return cls(_normalised(np.asarray(quat, dtype=float)))

    @classmethod
    def identity(cls, k: int) -> Rotation:
        return cls(np.tile([0.0, 0.0, 0.0, 1.0], (k, 1)))

    @classmethod
    def from_rotvec(cls, rotvec: np.ndarray) -> Rotation:
        """From rotation vectors (K, 3): axis times angle (radians)."""
        rotvec = np.asarray(rotvec, dtype=float)
        angle = np.linalg.norm(rotvec, axis=-1, keepdims=True)
        small = angle <= SMALL_ANGLE
        angle2 = angle ** 2
        scale = np.where(small, 0.5 - angle2 / 48 + angle2 ** 2 / 3840, np.sin(angle / 2) / (angle + small))
        return cls(np.concatenate([rotvec * scale, np.cos(angle / 2)], axis=-1))

    @classmethod
    def from_matrix(cls, matrix: np.ndarray) -> Rotation:
        """From rotation matrices (K, 3, 3); one that is not orthogonal is replaced by
        the nearest orthogonal one (U V^T of its SVD), then converted by Markley's
        method (from the largest of the diagonal and the trace)."""
        matrix = np.array(matrix, dtype=float)
        if (np.linalg.det(matrix) <= 0).any():
            raise ValueError("a rotation matrix has a non-positive determinant")
        skew = ~np.isclose(matrix @ np.swapaxes(matrix, -1, -2), np.eye(3), atol=ORTHOGONAL_ATOL).all(axis=(-2, -1))
        if skew.any():
            u, _, vt = np.linalg.svd(matrix[skew], full_matrices=False)
            matrix[skew] = u @ vt
        return cls(_normalised(_markley(matrix)))

    def __len__(self) -> int:
        return len(self._quat)

    def __getitem__(self, index) -> Rotation:
        return Rotation(self._quat[index])

    def __mul__(self, other: Rotation) -> Rotation:
        """The composition, normalised."""
        p, q = self._quat, other._quat
        cross = np.cross(p[..., :3], q[..., :3])
        return Rotation.from_quat(np.stack([
            p[..., 3] * q[..., 0] + q[..., 3] * p[..., 0] + cross[..., 0],
            p[..., 3] * q[..., 1] + q[..., 3] * p[..., 1] + cross[..., 1],
            p[..., 3] * q[..., 2] + q[..., 3] * p[..., 2] + cross[..., 2],
            p[..., 3] * q[..., 3] - p[..., 0] * q[..., 0] - p[..., 1] * q[..., 1] - p[..., 2] * q[..., 2],
        ], axis=-1))

    def inv(self) -> Rotation:
        quat = self._quat.copy()
        quat[..., :3] *= -1
        return Rotation(quat)

    def as_quat(self) -> np.ndarray:
        return self._quat.copy()

    def as_matrix(self) -> np.ndarray:
        x, y, z, w = np.moveaxis(self._quat, -1, 0)
        x2, y2, z2, w2 = x * x, y * y, z * z, w * w
        xy, zw, xz, yw, yz, xw = x * y, z * w, x * z, y * w, y * z, x * w
        return np.stack([x2 - y2 - z2 + w2, 2 * (xy - zw), 2 * (xz + yw),
                         2 * (xy + zw), -x2 + y2 - z2 + w2, 2 * (yz - xw),
                         2 * (xz - yw), 2 * (yz + xw), -x2 - y2 + z2 + w2], axis=-1).reshape(*x.shape, 3, 3)

    def as_rotvec(self) -> np.ndarray:
        """Rotation vectors (K, 3) of the quaternions turned to w >= 0 (angles up to pi)."""
        quat = _canonical(self._quat)
        angle = 2 * np.arctan2(np.linalg.norm(quat[..., :3], axis=-1, keepdims=True), quat[..., 3:])
        small = angle <= SMALL_ANGLE
        angle2 = angle ** 2
        scale = np.where(small, 2 + angle2 / 12 + 7 * angle2 ** 2 / 2880, angle / (np.sin(angle / 2.0) + small))
        return scale * quat[..., :3]

    def apply(self, vectors: np.ndarray) -> np.ndarray:
        """The vectors (3,) or (K, 3) rotated, one rotation to each (K, 3)."""
        vectors = np.broadcast_to(np.asarray(vectors, dtype=float), (len(self), 3))
        return np.einsum("ijk,ik->ij", self.as_matrix(), vectors)


class Slerp:
    """Spherical linear interpolation between rotations at increasing ``times``."""

    def __init__(self, times: np.ndarray, rotations: Rotation):
        self.times = np.asarray(times, dtype=float)
        self.rotations = rotations
        self.rotvecs = (rotations[:-1].inv() * rotations[1:]).as_rotvec()

    def __call__(self, times: np.ndarray) -> Rotation:
        """The rotations at ``times`` within the first and last of self.times."""
        times = np.asarray(times)
        i = np.searchsorted(self.times, times) - 1
        i[times == self.times[0]] = 0
        alpha = (times - self.times[i]) / np.diff(self.times)[i]
        return self.rotations[i] * Rotation.from_rotvec(self.rotvecs[i] * alpha[:, None])


def _markley(m: np.ndarray) -> np.ndarray:
    """Unnormalised quaternions (K, 4) of orthogonal matrices (K, 3, 3)."""
    trace = m[..., 0, 0] + m[..., 1, 1] + m[..., 2, 2]
    choice = np.argmax(np.stack([m[..., 0, 0], m[..., 1, 1], m[..., 2, 2], trace], axis=-1), axis=-1)
    cases = [
        [1 - trace + 2 * m[..., 0, 0], m[..., 1, 0] + m[..., 0, 1], m[..., 2, 0] + m[..., 0, 2],
         m[..., 2, 1] - m[..., 1, 2]],
        [m[..., 1, 0] + m[..., 0, 1], 1 - trace + 2 * m[..., 1, 1], m[..., 2, 1] + m[..., 1, 2],
         m[..., 0, 2] - m[..., 2, 0]],
        [m[..., 2, 0] + m[..., 0, 2], m[..., 2, 1] + m[..., 1, 2], 1 - trace + 2 * m[..., 2, 2],
         m[..., 1, 0] - m[..., 0, 1]],
        [m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0], m[..., 1, 0] - m[..., 0, 1], 1 + trace],
    ]
    quats = np.stack([np.stack(case, axis=-1) for case in cases])         # (4, K, 4)
    return np.take_along_axis(quats, choice[None, ..., None], axis=0)[0]


def _normalised(quat: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(quat, axis=-1, keepdims=True)
    if (norm == 0).any():
        raise ValueError("a quaternion has zero norm")
    return quat / norm


def _canonical(quat: np.ndarray) -> np.ndarray:
    """Each quaternion or its negation, whichever has w > 0 (or, where w is 0, the
    first nonzero of x, y, z positive): scipy's canonical choice."""
    flip = quat[..., 3] < 0
    zero = quat[..., 3] == 0
    for c in range(3):
        flip |= zero & (quat[..., c] < 0)
        zero &= quat[..., c] == 0
    return np.where(flip[..., None], -quat, quat)
