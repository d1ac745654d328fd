"""Camera calibration on the marked frame (Pan, Zhuang and Liu 2000, Eq. 6-9): the body's pose by Newton's method on
the key triangle's lines and, beyond the paper, the hips'. Focal length default: the frame width. Pinhole frame."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from mocap import body
from mocap.body import JOINT_INDEX, JOINTS
from mocap.camera import FLIP_YZ, Pinhole
from mocap.errors import MocapError
from mocap.track.marks import KEY_TRIANGLE, turned_apart

UNIT_M = body.BODY_HEIGHT_M / body.BODY_HEIGHT
KEY = np.array([JOINT_INDEX[j] for j in KEY_TRIANGLE])
KEY_LINES = ((0, 1), (0, 2), (1, 2))
# the hips and the chest, a second triangle beyond the paper's (see ``calibrate``)
HIP_TRIANGLE = (*(body.limb("leg", side).joints[0] for side in body.SIDES), KEY_TRIANGLE[2])
CALIBRATION_LINES = tuple(
    (JOINT_INDEX[t[i]], JOINT_INDEX[t[j]]) for t in (KEY_TRIANGLE, HIP_TRIANGLE) for i, j in KEY_LINES
)
SPAN_RANGE = (0.2, 0.5)  # metres: shoulder spans the calibration may find
# the chest's height above the pelvis the calibration may find, of the shoulders' height
CHEST_RANGE = (0.45, 0.85)
MAX_CALIBRATION_ERROR = 0.03  # of the marked body's size: a worse fit is refused
NEWTON_STEPS = 30
# body frame -> pinhole frame facing the camera (left to image right, up to image up, forward to the camera)
FACING_CAMERA = np.diag(FLIP_YZ)


def model_skeleton() -> np.ndarray:
    """(16, 3) the standing model in metres, body frame: x the performer's left, y up, z forward, pelvis origin."""
    length = dict(zip(body.SEGMENT_NAMES, body.LENGTH))
    torso = length["torso"]
    at = {
        "pelvis": (0, 0),
        "neck": (0, torso),
        "chest": (0, body.CHEST_FRACTION * torso),
        "head_top": (0, torso + length["head"]),
    }
    for one in body.LIMBS:
        sign = body.SIDE_SIGN[one.side]
        at[one.joints[0]] = (
            (sign * body.SHOULDER_HALF_SPAN, torso - body.SHOULDER_DROP)
            if one.kind == "arm"
            else (sign * body.HIP_HALF_SPAN, 0.0)
        )
        for segment, (a, b) in zip(one.segments, (one.joints[:2], one.joints[1:])):
            at[b] = (at[a][0], at[a][1] - length[segment])  # hanging straight down
    return np.array([[*at[j], 0.0] for j in JOINTS], dtype=float) * UNIT_M


MODEL = model_skeleton()


@dataclass(frozen=True)
class Calibration:
    """The body's pose in the pinhole frame on frame 0, X' = R P + t (Eq. 6): ``rotvec`` (W_x, W_y, W_z),
    ``translation`` in 3D (the paper's D_x, D_y, D_z), shoulder ``span`` and ``chest`` height, metres."""

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
        """The key joints' depths (3,) on frame 0 and the triangle's side lengths (3,) (KEY_LINES) (Eq. 10-11)."""
        triangle = self.model()[KEY]
        sides = np.array([np.linalg.norm(triangle[i] - triangle[j]) for i, j in KEY_LINES])
        return self.to_camera(triangle)[:, 2], sides

    @property
    def yaw(self) -> float:
        """The body's yaw in degrees (as lift.facing_yaw: 0 faces the camera, +90 faces image right)."""
        forward = Rotation.from_rotvec(self.rotvec).apply([0.0, 0.0, 1.0])
        return float(np.degrees(np.arctan2(forward[0], -forward[2])))


def line_distances(params: np.ndarray, camera: Pinhole, marks: np.ndarray) -> np.ndarray:
    """E of Eq. 9: (12,) signed distances of the marked end points of the CALIBRATION_LINES to the model's lines
    projected by Eq. 6-7; Eq. 8 with a unit normal, so vertical lines need no special case."""
    cal = Calibration.from_params(params)
    seen = camera.project(cal.to_camera(cal.model()))
    out = []
    for i, j in CALIBRATION_LINES:
        direction = seen[j] - seen[i]
        normal = np.array([-direction[1], direction[0]]) / max(np.hypot(*direction), 1e-9)
        d = normal @ seen[i]
        out += [normal @ marks[i] - d, normal @ marks[j] - d]
    return np.array(out)


def newton(residual, params: np.ndarray, steps: int = NEWTON_STEPS, eps: float = 1e-6) -> np.ndarray:
    """Solve residual(params) = 0 (least squares when over-determined) by Gauss-Newton steps with a numerical Jacobian
    (Eq. 9: J delta = -E), halving steps that do not reduce |E|."""
    r = residual(params)
    for _ in range(steps):
        jac = np.column_stack([(residual(params + eps * e) - r) / eps for e in np.eye(len(params))])
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
    """Start values (8,): the model upright at the depth its shoulder height matches, turned by either yaw whose
    cosine the marked hip span gives, the span the shoulders then show, the model's chest."""
    j = JOINT_INDEX

    def seen(a: str, b: str) -> np.ndarray:
        return marks[j[a]] - marks[j[b]]

    shoulders = (marks[j["shoulder_l"]] + marks[j["shoulder_r"]]) / 2 - marks[j["pelvis"]]
    depth = camera.focal * MODEL[j["shoulder_l"], 1] / max(np.hypot(*shoulders), 1e-6)
    hips = 2 * body.HIP_HALF_SPAN * UNIT_M * camera.focal / depth
    cos = np.clip(seen("hip_l", "hip_r")[0] / hips, -1.0, 1.0)
    span = np.clip(abs(seen("shoulder_l", "shoulder_r")[0]) * depth / camera.focal / max(abs(cos), 0.3), *SPAN_RANGE)
    out = []
    for yaw in (np.arccos(cos), -np.arccos(cos)):
        rotation = Rotation.from_matrix(FACING_CAMERA @ Rotation.from_euler("y", yaw).as_matrix())
        centre = camera.rays(marks[j["chest"]]) * depth
        out.append(np.r_[rotation.as_rotvec(), centre - rotation.apply(MODEL[j["chest"]]), span, MODEL[j["chest"], 1]])
    return out


def shape_ranges() -> np.ndarray:
    """(2, 2) ranges of the shape unknowns: shoulder span (SPAN_RANGE) and chest height (CHEST_RANGE)."""
    return np.array([SPAN_RANGE, np.array(CHEST_RANGE) * MODEL[KEY[0], 1]])


def bounded_fit(marks: np.ndarray, camera: Pinhole, start: np.ndarray, ranges: np.ndarray) -> np.ndarray:
    """Parameters (8,) fitted to the marks (16, 2) from ``start`` (Eq. 9), the shape unknowns refitted at the nearer
    end of ``ranges`` (2, 2; one value: held) where the free fit leaves them (near profile the span is loose)."""
    fixed = ranges[:, 0] == ranges[:, 1]
    free = held_fit(marks, camera, np.r_[start[:6], np.where(fixed, ranges[:, 0], start[6:])], fixed)
    held = np.clip(free[6:], ranges[:, 0], ranges[:, 1])
    out = (held != free[6:]) & ~fixed
    if not out.any():
        return free
    return held_fit(marks, camera, np.r_[start[:6], held], fixed | out)


def held_fit(marks: np.ndarray, camera: Pinhole, start: np.ndarray, held: np.ndarray) -> np.ndarray:
    """Parameters (8,) fitted to the marks (16, 2) from ``start`` (Eq. 9), shape unknowns ``held`` (2,) fixed."""
    vary = np.r_[np.ones(6, bool), ~held]

    def full(p: np.ndarray) -> np.ndarray:
        out = start.copy()
        out[vary] = p
        return out

    return full(newton(lambda p: line_distances(full(p), camera, marks), start[vary]))


def calibrate(marks: np.ndarray, camera: Pinhole, turn: str | None = None, chest: float | None = None) -> Calibration:
    """The body's pose on frame 0 from the marks (16, 2): Newton's method on Eq. 9 over the key triangle's and, beyond
    the paper, the hips-chest triangle's lines, with shoulder span and chest height (unless ``chest`` given)
    unknown too. ``turn`` "left"/"right" picks one of two mirror fits, else the smaller residual; MocapError where
    none fits."""
    ranges = shape_ranges()
    if chest is not None:
        ranges[1] = chest
    fits = [bounded_fit(marks, camera, p0, ranges) for p0 in initial_params(marks, camera)]
    error = [np.abs(line_distances(p, camera, marks)).max() for p in fits]
    if min(error) > MAX_CALIBRATION_ERROR * np.ptp(marks, axis=0).max():
        raise MocapError(
            "cannot calibrate the camera from the marked shoulders, chest and "
            "hips: they fit no view of a human trunk"
            + (
                "; the shoulders and the hips are marked turned opposite ways: "
                "swap shoulder_l and shoulder_r, or hip_l and hip_r"
                if turned_apart(marks)
                else ""
            )
        )
    if turn in ("left", "right"):
        wrong_side = [(Calibration.from_params(p).yaw > 0) != (turn == "right") for p in fits]
        error = [np.inf if wrong else e for e, wrong in zip(error, wrong_side)]
    return Calibration.from_params(fits[int(np.argmin(error))])
