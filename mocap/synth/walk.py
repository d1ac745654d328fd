"""A procedural walk with the model's proportions: motion for tests and the bundled
sample when no motion capture is at hand."""

from __future__ import annotations

import numpy as np

from mocap import body


def walk_cycle(
    seconds: float = 4.0, fps: float = 30.0, *, in_place: bool = False, period: float = 1.1, hip_swing_deg: float = 20.0
) -> np.ndarray:
    """(F, 16, 3) joints of a walk with the model's proportions (1.75 m): metres, y up, facing
    and (unless ``in_place``) advancing along +z, left +x; the lower ankle at y = 0."""
    n = max(1, int(round(seconds * fps)))
    phase = 2 * np.pi * np.arange(n) / (fps * period)
    unit = body.BODY_HEIGHT_M / body.BODY_HEIGHT
    seg = dict(zip(body.SEGMENT_NAMES, body.LENGTH * unit))
    lean, swing = np.radians(4.0), np.radians(hip_swing_deg)
    pose = {"pelvis": np.zeros((n, 3)), "neck": np.tile([0.0, np.cos(lean), np.sin(lean)], (n, 1)) * seg["torso"]}
    pose["head_top"] = pose["neck"] + [0.0, seg["head"], 0.0]
    pose["chest"] = body.CHEST_FRACTION * pose["neck"]
    for side, sign, leg_phase in (("r", -1.0, phase), ("l", 1.0, phase + np.pi)):
        hip = swing * np.sin(leg_phase)
        knee = np.radians(8.0 + 55.0 * np.maximum(0.0, np.cos(leg_phase + 0.5)) ** 2)
        arm = -0.8 * hip
        elbow = np.radians(15.0) + 0.5 * np.maximum(arm, 0.0)
        hip_at = pose["pelvis"] + [sign * body.HIP_HALF_SPAN * unit, 0.0, 0.0]
        shoulder_at = pose["neck"] / body.NECK_PER_SHOULDER + [sign * body.SHOULDER_HALF_SPAN * unit, 0.0, 0.0]
        _chain(
            pose,
            body.limb("leg", side).joints,
            hip_at,
            (seg["upper_leg_l"], seg["lower_leg_l"]),
            (hip, hip - knee),
            0.0,
        )
        _chain(
            pose,
            body.limb("arm", side).joints,
            shoulder_at,
            (seg["upper_arm_l"], seg["lower_arm_l"]),
            (arm, arm + elbow),
            0.1 * sign,
        )
    out = np.stack([pose[name] for name in body.JOINTS], axis=1)
    ankles = out[:, [body.JOINT_INDEX["ankle_l"], body.JOINT_INDEX["ankle_r"]], 1]
    out[:, :, 1] -= ankles.min(axis=1)[:, None]
    if not in_place:
        step = 2 * (seg["upper_leg_l"] + seg["lower_leg_l"]) * np.sin(swing)
        out[:, :, 2] += (2 * step / period * np.arange(n) / fps)[:, None]
    return out


def _chain(
    pose: dict,
    names: tuple[str, str, str],
    start: np.ndarray,
    lengths: tuple[float, float],
    angles: tuple[np.ndarray, np.ndarray],
    outward: float,
) -> None:
    """Add a two-segment limb to ``pose``, each segment hanging down, swung forward by its angle."""
    middle = start + lengths[0] * _sagittal(angles[0], outward)
    end = middle + lengths[1] * _sagittal(angles[1], outward)
    pose.update(zip(names, (start, middle, end)))


def _sagittal(angle: np.ndarray, outward: float) -> np.ndarray:
    """(F, 3) unit vectors pointing down, swung forward (+z) by ``angle`` radians and
    tilted by ``outward`` along x."""
    v = np.stack([np.full_like(angle, outward), -np.cos(angle), np.sin(angle)], axis=-1)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)
