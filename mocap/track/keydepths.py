"""The key triangle (both shoulders and the chest) on every frame after the marked one: the paper's Eq. 10-11 (Pan,
Zhuang and Liu 2000), and the choice between the two mirror-image triangles a frontal view leaves open."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from mocap.camera import Pinhole
from mocap.track.calibration import KEY, KEY_LINES, calibrate, newton

SIDE_MARGIN_DEG = 15.0  # a trunk turned less than this from facing the camera (or away) shows no side
# the side a body is turned to ("left", "right", None: unsaid): one for every frame, or each frame's
Turns = str | Sequence[str | None] | None


def key_depths(rays: np.ndarray, depths: np.ndarray, sides: np.ndarray) -> np.ndarray:
    """Depths Z_i (3,) of the key joints on their ``rays`` (3, 3) keeping the triangle's ``sides`` (3,) (Eq. 11 with
    P_i = Z_i ray_i, Eq. 10), least squares by Gauss-Newton from the previous ``depths``."""

    def residual(z):
        p = z[:, None] * rays
        return np.array([np.linalg.norm(p[i] - p[j]) for i, j in KEY_LINES]) - sides

    return newton(residual, np.asarray(depths, float))


def body_axes(key: np.ndarray) -> np.ndarray:
    """(..., 3, 3) body -> pinhole rotations of key joints (..., 3, 3): columns left (shoulders), up, forward."""
    left = key[..., 0, :] - key[..., 1, :]
    left = left / np.linalg.norm(left, axis=-1, keepdims=True)
    up = (key[..., 0, :] + key[..., 1, :]) / 2 - key[..., 2, :]
    up = up - (up * left).sum(-1, keepdims=True) * left
    up = up / np.linalg.norm(up, axis=-1, keepdims=True)
    return np.stack([left, up, np.cross(left, up)], axis=-1)


def triangle_yaw(key: np.ndarray) -> np.ndarray:
    """The facing yaw in degrees (as Calibration.yaw) of key joints (..., 3, 3)."""
    forward = body_axes(key)[..., :, 2]
    return np.degrees(np.arctan2(forward[..., 0], -forward[..., 2]))


def side_of(yaw: float) -> str | None:
    """ "left" or "right": the side a yaw (degrees) clearly (SIDE_MARGIN_DEG) faces; None near 0 and 180 or NaN."""
    if not SIDE_MARGIN_DEG < abs(yaw) < 180.0 - SIDE_MARGIN_DEG:
        return None
    return "right" if yaw > 0 else "left"


def turned_against(key: np.ndarray, turn: str | None) -> bool:
    """Whether key joints (3, 3) face clearly (``side_of``) to the other side than ``turn`` (None: either)."""
    return turn is not None and side_of(float(triangle_yaw(key))) not in (None, turn)


def frame_key_depths(rays: np.ndarray, depths: np.ndarray, sides: np.ndarray, turn: str | None) -> np.ndarray:
    """A frame's key depths (3,) from the previous frame's (Eq. 10-11) on the side ``turn`` says: where the solution
    faces the other side, the one from its depths mirrored about their mean, if that faces ``turn``."""
    found = key_depths(rays, depths, sides)
    if not turned_against(found[:, None] * rays, turn):
        return found
    mirror = key_depths(rays, 2 * found.mean() - found, sides)
    return found if turned_against(mirror[:, None] * rays, turn) else mirror


def key_joints(
    joints2d: np.ndarray, camera: Pinhole, turns: Turns = None, before: tuple[np.ndarray, np.ndarray] | None = None
) -> np.ndarray:
    """(F, 3, 3) key joints per frame: calibrated on frame 0 (Eq. 6-9), then each from the one before (Eq. 10-11).
    ``turns``: one side or each frame's; ``before``: (2D joints, key joints) of an earlier call, reused unmoved."""
    rays = camera.rays(joints2d[:, KEY])
    held = [turns] * len(rays) if turns is None or isinstance(turns, str) else list(turns)
    depths, sides = calibrate(joints2d[0], camera, held[0]).key_triangle()
    redo = np.ones(len(rays), bool)
    if before is not None and before[0].shape == joints2d.shape:
        moved = (before[0][:, KEY] != joints2d[:, KEY]).any(axis=(1, 2))
        redo = redo if moved[0] else moved
    out = np.empty((len(rays), 3, 3))
    for f, (frame_rays, turn) in enumerate(zip(rays, held)):
        if redo[f]:
            depths = frame_key_depths(frame_rays, depths, sides, turn)
            out[f] = depths[:, None] * frame_rays
        else:
            out[f] = before[1][f]
            depths = out[f, :, 2]
    return out


def mirror_images(key: np.ndarray, steps: int = 20) -> np.ndarray:
    """(F, 3, 3) the other Eq. 10-11 solution for key joints (F, 3, 3), from depths mirrored about their mean."""
    lines = np.array(KEY_LINES)
    sides = np.median(np.linalg.norm(key[:, lines[:, 0]] - key[:, lines[:, 1]], axis=-1), axis=0)
    rays = key / key[..., 2:]
    z = 2 * key[..., 2].mean(axis=1, keepdims=True) - key[..., 2]
    rows = np.arange(len(lines))
    for _ in range(steps):
        points = z[..., None] * rays
        gap = points[:, lines[:, 0]] - points[:, lines[:, 1]]  # (F, 3, 3)
        length = np.maximum(np.linalg.norm(gap, axis=-1), 1e-12)
        jac = np.zeros((len(key), len(lines), 3))
        jac[:, rows, lines[:, 0]] = (gap * rays[:, lines[:, 0]]).sum(-1) / length
        jac[:, rows, lines[:, 1]] = -(gap * rays[:, lines[:, 1]]).sum(-1) / length
        normal = jac.transpose(0, 2, 1) @ jac + 1e-9 * np.eye(3)
        z = z - np.linalg.solve(normal, (jac.transpose(0, 2, 1) @ (length - sides)[..., None]))[..., 0]
    return z[..., None] * rays
