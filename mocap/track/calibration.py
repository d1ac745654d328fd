"""The body's pose relative to the camera on the marked frame: the tracking paper's
calibration (Pan, Zhuang and Liu, *Video motion capture in VBA*, 2000, section
"Reconstruction of 3D human motion skeleton", Eq. 6-9).

The body's rotation and translation relative to the camera on frame 0, by Newton's
method on the perpendicular distances E of the marked lines' end points to the
model's projected lines: the key triangle (both shoulders and the chest) of the
model (body.py, a 1.75 m body) and, beyond the paper, the triangle of the hips and
the chest with the shoulder span as a seventh unknown (see ``calibrate``).

The focal length is not measured (three points cannot give it): ``focal_px``
defaults to the frame's width, a 53-degree horizontal field of view, an ordinary
lens. A wrong focal length mostly changes the body's distance, hardly its shape, once
the body is a few body heights away.

Points are in the pinhole frame (X right, Y down, Z the depth along the optical axis).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from mocap import body
from mocap.body import JOINT_INDEX, JOINTS
from mocap.errors import MocapError
from mocap.track.marks import KEY_TRIANGLE, turned_apart

UNIT_M = body.BODY_HEIGHT_M / body.BODY_HEIGHT
KEY = np.array([JOINT_INDEX[j] for j in KEY_TRIANGLE])
KEY_LINES = ((0, 1), (0, 2), (1, 2))
# the hips and the chest, a second triangle beyond the paper's (see ``calibrate``)
HIP_TRIANGLE = (*(body.limb("leg", side).joints[0] for side in body.SIDES), KEY_TRIANGLE[2])
CALIBRATION_LINES = tuple((JOINT_INDEX[t[i]], JOINT_INDEX[t[j]])
                          for t in (KEY_TRIANGLE, HIP_TRIANGLE) for i, j in KEY_LINES)
SPAN_RANGE = (0.2, 0.5)         # metres: shoulder spans the calibration may find
# the chest's height above the pelvis that the calibration may find, as fractions of the
# shoulders' height above it
CHEST_RANGE = (0.45, 0.85)
MAX_CALIBRATION_ERROR = 0.03    # of the marked body's size: a worse fit is refused
NEWTON_STEPS = 30
# body frame -> pinhole frame for a performer facing the camera (left to image right,
# up to image up, forward toward the camera)
FACING_CAMERA = np.diag([1.0, -1.0, -1.0])


def model_skeleton() -> np.ndarray:
    """(16, 3) the body model standing, arms and legs hanging, in metres in the body
    frame: x the performer's left, y up, z forward, origin at the pelvis."""
    length = dict(zip(body.SEGMENT_NAMES, body.LENGTH))
    torso = length["torso"]
    at = {"pelvis": (0, 0), "neck": (0, torso), "chest": (0, body.CHEST_FRACTION * torso),
          "head_top": (0, torso + length["head"])}
    for one in body.LIMBS:
        sign = body.SIDE_SIGN[one.side]
        at[one.joints[0]] = ((sign * body.SHOULDER_HALF_SPAN, torso - body.SHOULDER_DROP)
                             if one.kind == "arm" else (sign * body.HIP_HALF_SPAN, 0.0))
        for segment, (a, b) in zip(one.segments, (one.joints[:2], one.joints[1:])):
            at[b] = (at[a][0], at[a][1] - length[segment])      # hanging straight down
    return np.array([[*at[j], 0.0] for j in JOINTS], dtype=float) * UNIT_M


MODEL = model_skeleton()


@dataclass(frozen=True)
class Pinhole:
    """The camera: focal length and principal point in pixels."""

    focal: float
    cx: float
    cy: float

    def rays(self, pixels: np.ndarray) -> np.ndarray:
        """(..., 3) viewing rays (x, y, 1): the point at depth Z is Z times the ray (Eq. 10)."""
        p = np.asarray(pixels, float)
        return np.stack([(p[..., 0] - self.cx) / self.focal, (p[..., 1] - self.cy) / self.focal,
                         np.ones(p.shape[:-1])], axis=-1)

    def project(self, points: np.ndarray) -> np.ndarray:
        """(..., 2) pixels of pinhole-frame points (..., 3)."""
        z = points[..., 2:3]
        return np.array([self.cx, self.cy]) + self.focal * points[..., :2] / z

    def scaled(self, factor: float) -> "Pinhole":
        """The camera of the frames resized by ``factor``."""
        return Pinhole(self.focal * factor, self.cx * factor, self.cy * factor)


def default_camera(width: int, height: int, focal_px: float | None = None) -> Pinhole:
    """The assumed camera of a video: ``focal_px`` or the frame's width, centred."""
    return Pinhole(float(focal_px or width), width / 2.0, height / 2.0)


@dataclass(frozen=True)
class Calibration:
    """The body's pose in the pinhole frame on frame 0 (the camera's, seen from the
    body): X' = R P + t (Eq. 6) with R the rotation vector (W_x, W_y, W_z) and t the
    translation (the paper's D_x, D_y, D_z, here a true 3D translation rather than
    image offsets), the performer's shoulder span and the chest's height above the
    pelvis in metres."""

    rotvec: np.ndarray
    translation: np.ndarray
    span: float
    chest: float = float(MODEL[KEY[2], 1])

    @classmethod
    def from_params(cls, params: np.ndarray) -> "Calibration":
        return cls(params[:3], params[3:6], float(params[6]), float(params[7]))

    @property
    def params(self) -> np.ndarray:
        """(8,) the parameters ``from_params`` reads."""
        return np.r_[self.rotvec, self.translation, self.span, self.chest]

    def model(self) -> np.ndarray:
        """(16, 3) the standing model with this shoulder span and chest (body frame)."""
        out = MODEL.copy()
        out[[KEY[0], KEY[1]], 0] = self.span / 2, -self.span / 2
        out[KEY[2], 1] = self.chest
        return out

    def to_camera(self, points: np.ndarray) -> np.ndarray:
        """Body points (..., 3) in the pinhole frame (Eq. 6)."""
        return Rotation.from_rotvec(self.rotvec).apply(points) + self.translation

    def key_triangle(self) -> tuple[np.ndarray, np.ndarray]:
        """The key joints' depths (3,) on the calibrated frame and the key triangle's
        side lengths (3,) (KEY_LINES) that later frames keep (Eq. 10-11)."""
        triangle = self.model()[KEY]
        sides = np.array([np.linalg.norm(triangle[i] - triangle[j]) for i, j in KEY_LINES])
        return self.to_camera(triangle)[:, 2], sides

    @property
    def yaw(self) -> float:
        """The body's yaw in degrees (as lift.facing_yaw: 0 faces the camera, +90
        faces image right)."""
        forward = Rotation.from_rotvec(self.rotvec).apply([0.0, 0.0, 1.0])
        return float(np.degrees(np.arctan2(forward[0], -forward[2])))


def line_distances(params: np.ndarray, camera: Pinhole, marks: np.ndarray) -> np.ndarray:
    """E of Eq. 9: (12,) signed perpendicular distances of the two marked end points of
    each of the six CALIBRATION_LINES to the model's line projected by Eq. 6-7.

    The projected line is Eq. 8, -m/sqrt(m^2+1) u + 1/sqrt(m^2+1) v = d, written with
    its unit normal so that vertical lines (infinite slope m) need no special case.
    """
    cal = Calibration.from_params(params)
    seen = camera.project(cal.to_camera(cal.model()))
    out = []
    for i, j in CALIBRATION_LINES:
        direction = seen[j] - seen[i]
        normal = np.array([-direction[1], direction[0]]) / max(np.hypot(*direction), 1e-9)
        d = normal @ seen[i]
        out += [normal @ marks[i] - d, normal @ marks[j] - d]
    return np.array(out)


def newton(residual, params: np.ndarray, steps: int = NEWTON_STEPS,
           eps: float = 1e-6) -> np.ndarray:
    """Solve residual(params) = 0, in the least-squares sense when over-determined,
    by Newton / Gauss-Newton steps with a numerical Jacobian (Eq. 9: J delta = -E),
    halving a step that does not reduce |E|."""
    r = residual(params)
    for _ in range(steps):
        jac = np.column_stack([(residual(params + eps * e) - r) / eps
                               for e in np.eye(len(params))])
        delta = np.linalg.lstsq(jac, -r, rcond=None)[0]
        for _ in range(10):
            trial = residual(params + delta)
            if trial @ trial < r @ r:
                params, r = params + delta, trial
                break
            delta = delta / 2
        else:
            break
    return params


def initial_params(marks: np.ndarray, camera: Pinhole) -> list[np.ndarray]:
    """Start values (8,) for the calibration: the model upright at the depth where the
    height of its shoulders above its pelvis matches the marks, turned by either of
    the two yaws whose cosine the marked hip span gives (left hip on the image right:
    facing the camera), with the shoulder span that the marked shoulders then show
    and the model's chest."""
    j = JOINT_INDEX

    def seen(a: str, b: str) -> np.ndarray:
        return marks[j[a]] - marks[j[b]]
    shoulders = (marks[j["shoulder_l"]] + marks[j["shoulder_r"]]) / 2 - marks[j["pelvis"]]
    depth = camera.focal * MODEL[j["shoulder_l"], 1] / max(np.hypot(*shoulders), 1e-6)
    hips = 2 * body.HIP_HALF_SPAN * UNIT_M * camera.focal / depth
    cos = np.clip(seen("hip_l", "hip_r")[0] / hips, -1.0, 1.0)
    span = np.clip(abs(seen("shoulder_l", "shoulder_r")[0]) * depth / camera.focal
                   / max(abs(cos), 0.3), *SPAN_RANGE)
    out = []
    for yaw in (np.arccos(cos), -np.arccos(cos)):
        rotation = Rotation.from_matrix(FACING_CAMERA @ Rotation.from_euler("y", yaw).as_matrix())
        centre = camera.rays(marks[j["chest"]]) * depth
        out.append(np.r_[rotation.as_rotvec(), centre - rotation.apply(MODEL[j["chest"]]), span,
                         MODEL[j["chest"], 1]])
    return out


def shape_ranges() -> np.ndarray:
    """(2, 2) the ranges of the calibration's shape unknowns: the shoulder span
    (SPAN_RANGE) and the chest's height (CHEST_RANGE of the model shoulders')."""
    return np.array([SPAN_RANGE, np.array(CHEST_RANGE) * MODEL[KEY[0], 1]])


def bounded_fit(marks: np.ndarray, camera: Pinhole, start: np.ndarray,
                ranges: np.ndarray) -> np.ndarray:
    """The calibration's parameters (8,) fitted to the marks (16, 2) from ``start``
    (Eq. 9 by Newton's method), the shape unknowns kept within ``ranges`` (2, 2; a
    range of one value holds that one): where the free fit leaves them, the fit
    again with those held at their range's nearer end.

    Seen nearly from the side, the shoulders' image span hardly depends on the span,
    and the free fit's reads anything from 0.14 to 0.51 m from exact projections of
    motion capture 10 degrees from profile (benchmarks/bench_track.py's motions),
    while the pose it fits is sound."""
    fixed = ranges[:, 0] == ranges[:, 1]
    free = held_fit(marks, camera, np.r_[start[:6], np.where(fixed, ranges[:, 0], start[6:])], fixed)
    held = np.clip(free[6:], ranges[:, 0], ranges[:, 1])
    out = (held != free[6:]) & ~fixed
    if not out.any():
        return free
    return held_fit(marks, camera, np.r_[start[:6], held], fixed | out)


def held_fit(marks: np.ndarray, camera: Pinhole, start: np.ndarray, held: np.ndarray) -> np.ndarray:
    """The calibration's parameters (8,) fitted to the marks (16, 2) from ``start``
    (Eq. 9), the shape unknowns ``held`` (2,) bool kept at their start values."""
    vary = np.r_[np.ones(6, bool), ~held]

    def full(p: np.ndarray) -> np.ndarray:
        out = start.copy()
        out[vary] = p
        return out
    return full(newton(lambda p: line_distances(full(p), camera, marks), start[vary]))


def calibrate(marks: np.ndarray, camera: Pinhole, turn: str | None = None,
              chest: float | None = None) -> Calibration:
    """The body's pose relative to the camera on frame 0 from its 16 marked joints
    (16, 2), by Newton's method on Eq. 9 over the key triangle's three lines (both
    shoulders and the chest) and, beyond the paper, the three lines of the triangle of
    the hips and the chest (12 equations, 8 unknowns: Gauss-Newton).

    Beyond the paper, the shoulder span is a seventh unknown: real shoulder spans
    differ by +-25% (0.26 to 0.44 m in the CMU skeletons) and the key triangle alone
    reads such a difference as a turn of the body; the hips (a steadier 0.18 to 0.21 m)
    fix the turn. The chest's height above the pelvis is the eighth (``chest`` holds
    it): where a body or a skeleton puts the chest differs (0.63 to 0.68 of the
    shoulders' height in the motion capture at hand, the model's 0.68), and a key
    triangle of the wrong height is fitted nearer or farther and turned to match
    the shoulders' image: the model's chest put the shared perspective clips' bodies
    at 0.72-0.79 of their distance, turned 15-17 degrees too far (from the exact 2D,
    track_salsa 49.3 -> 43.4 mm PA-MPJPE, track_walk 45.8 -> 39.2, laugh_arms_up
    52.6 -> 52.7). Two upright poses fit equally, turned to either side; ``turn``
    "left" or "right" (the side of CONTRACT.md's orientation, e.g. the "right" of
    forward_right) picks one, else the one with the smaller residual.
    """
    ranges = shape_ranges()
    if chest is not None:
        ranges[1] = chest
    fits = [bounded_fit(marks, camera, p0, ranges) for p0 in initial_params(marks, camera)]
    error = [np.abs(line_distances(p, camera, marks)).max() for p in fits]
    if min(error) > MAX_CALIBRATION_ERROR * np.ptp(marks, axis=0).max():
        raise MocapError("cannot calibrate the camera from the marked shoulders, chest and "
                         "hips: they fit no view of a human trunk" + (
                             "; the shoulders and the hips are marked turned opposite ways: "
                             "swap shoulder_l and shoulder_r, or hip_l and hip_r"
                             if turned_apart(marks) else ""))
    if turn in ("left", "right"):
        wrong_side = [(Calibration.from_params(p).yaw > 0) != (turn == "right") for p in fits]
        error = [np.inf if wrong else e for e, wrong in zip(error, wrong_side)]
    return Calibration.from_params(fits[int(np.argmin(error))])
