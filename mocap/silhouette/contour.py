"""Contour analysis of the silhouette (section 3.3.2, Algorithms 2-5): limb curves read off horizontal scan
lines; angles in the body module's convention (degrees, y up), from a curve's first point to its last."""

from __future__ import annotations

import numpy as np

from mocap.body import JOINT_INDEX, LENGTH, SEGMENT_INDEX, WIDTH

MIN_CORNER_DISTANCE = 4  # Algorithm 4
MIN_CORNER_ANGLE = 10.0  # Algorithm 4, degrees


def row_runs(band: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every horizontal run of nonzero pixels: (row, start, end) arrays, end exclusive."""
    width = band.shape[1] + 2
    padded = np.zeros((band.shape[0], width), bool)
    padded[:, 1:-1] = band > 0
    flat = padded.reshape(-1)
    changes = np.flatnonzero(flat[1:] != flat[:-1])
    rows, starts = np.divmod(changes[0::2], width)
    return rows, starts, changes[1::2] % width


def _line_angles(
    xs: np.ndarray, ys: np.ndarray, counts: np.ndarray, sx, sy, sxx, syy, sxy, dx: np.ndarray, dy: np.ndarray
) -> np.ndarray:
    """Principal-axis angles of point sets given their running sums, oriented along (dx, dy)."""
    n = np.maximum(counts, 1)
    cxx = sxx / n - (sx / n) ** 2
    cyy = syy / n - (sy / n) ** 2
    cxy = sxy / n - (sx / n) * (sy / n)
    theta = 0.5 * np.arctan2(2 * cxy, cxx - cyy)
    ux, uy = np.cos(theta), np.sin(theta)
    flip = ux * dx + uy * dy < 0
    ux, uy = np.where(flip, -ux, ux), np.where(flip, -uy, uy)
    return np.degrees(np.arctan2(-uy, ux))


def find_angle(points: np.ndarray, default: float) -> float:
    """FindAngle of Algorithms 2-3: the direction of the line fitted to a curve."""
    pts = np.asarray(points, dtype=float)
    if len(pts) < 2 or np.ptp(pts, axis=0).max() < 1e-6:
        return float(default)
    x, y = pts[:, 0], pts[:, 1]
    a = _line_angles(
        x,
        y,
        np.array([len(pts)]),
        x.sum(),
        y.sum(),
        (x * x).sum(),
        (y * y).sum(),
        (x * y).sum(),
        np.array([x[-1] - x[0]]),
        np.array([y[-1] - y[0]]),
    )
    return float(_near(a[0], default))


def _near(angle: float, reference: float) -> float:
    """The representative of angle (mod 360) closest to reference."""
    return reference + (angle - reference + 180.0) % 360.0 - 180.0


def find_elbow_corner(points: np.ndarray) -> int:
    """Algorithm 4: the arm curve's split with the largest angle, if at least MIN_CORNER_ANGLE; else -1."""
    pts = np.asarray(points, dtype=float)
    n = len(pts)
    idx = np.arange(MIN_CORNER_DISTANCE, n - 2)
    if len(idx) == 0:
        return -1
    x, y = pts[:, 0], pts[:, 1]
    sums = [np.cumsum(v) for v in (x, y, x * x, y * y, x * y)]
    head = [s[idx] for s in sums]  # points 0..i
    tail = [s[-1] - s[idx - 1] for s in sums]  # points i..n-1
    upper = _line_angles(x, y, idx + 1, *head, x[idx] - x[0], y[idx] - y[0])
    lower = _line_angles(x, y, n - idx, *tail, x[-1] - x[idx], y[-1] - y[idx])
    diff = np.abs((upper - lower + 180.0) % 360.0 - 180.0)
    if diff.max() < MIN_CORNER_ANGLE:
        return -1
    return int(idx[np.argmax(diff)])


def lower_leg_band(sil: np.ndarray, joints: np.ndarray, scale: float) -> tuple[int, int]:
    """The rows (first, end) Algorithm 2 reads the lower legs on: below the knees to above the feet."""
    pelvis = joints[JOINT_INDEX["pelvis"]]
    ys = np.nonzero(sil.any(axis=1))[0]
    bottom = ys.max() if len(ys) else int(pelvis[1])
    thigh = LENGTH[SEGMENT_INDEX["upper_leg_l"]]
    knee_y = pelvis[1] + (bottom - pelvis[1]) * thigh / (thigh + LENGTH[SEGMENT_INDEX["lower_leg_l"]])
    return int(knee_y + 2 * scale), int(bottom - 2 * scale)


def lower_leg_curves(sil: np.ndarray, joints: np.ndarray, scale: float):
    """GetLeft/RightLowerKneeCurve of Algorithm 2: per ``lower_leg_band`` line the centres of the outer legs
    ({'l', 'r'}: (N, 2) x, y), and each line's run count (Algorithm 5)."""
    pelvis = joints[JOINT_INDEX["pelvis"]]
    y0, y1 = lower_leg_band(sil, joints, scale)
    half = 45 * scale
    x0 = max(int(pelvis[0] - half), 0)
    band = sil[max(y0, 0) : max(y1, y0 + 1), x0 : int(pelvis[0] + half)]
    rows, starts, ends = row_runs(band)
    leg_w = WIDTH[SEGMENT_INDEX["lower_leg_l"]] * scale
    keep = (ends - starts) >= 0.25 * leg_w
    rows, starts, ends = rows[keep], starts[keep], ends[keep]
    curves = {"l": [], "r": []}
    counts = []
    cuts = np.flatnonzero(np.diff(rows)) + 1  # runs come row by row, left to right
    for r, s, e in zip(rows[np.r_[0, cuts]] if len(rows) else [], np.split(starts, cuts), np.split(ends, cuts)):
        counts.append(len(s))
        for side, x in _leg_centres(s, e, leg_w, curves).items():
            curves[side].append((x, r))
    shift = np.array([x0, max(y0, 0)], dtype=float)
    return {k: np.array(v, dtype=float).reshape(-1, 2) + shift for k, v in curves.items()}, counts


def _leg_centres(s: np.ndarray, e: np.ndarray, leg_w: float, curves) -> dict[str, float]:
    """Which legs one scan line shows, and where: the outer runs, or one wide run split, or one narrow run for
    the leg whose curve it continues (both where they overlap)."""
    if len(s) >= 2:
        return {"l": (s[0] + e[0]) / 2, "r": (s[-1] + e[-1]) / 2}
    if e[0] - s[0] > 1.6 * leg_w:
        return {"l": s[0] + leg_w / 2, "r": e[0] - leg_w / 2}
    x = (s[0] + e[0]) / 2
    last = {k: v[-1][0] for k, v in curves.items() if v}
    if len(last) < 2 or abs(last["l"] - last["r"]) < leg_w:
        return {"l": x, "r": x}
    nearest = min(last, key=lambda k: abs(last[k] - x))
    return {nearest: x}


def lower_legs_cross(line_counts) -> bool:
    """Algorithm 5: the lower legs cross when their scan lines start as one and become two."""
    c = np.asarray(line_counts)
    if len(c) < 4 or c[0] != 1:
        return False
    two = np.nonzero(c >= 2)[0]
    if len(two) == 0:
        return False
    rest = c[two[0] :]
    return bool(np.mean(rest >= 2) > 0.8 and two[0] >= 2)


def arm_curve(canvas, joints: np.ndarray, side: str, scale: float, runs: str | None = None) -> np.ndarray:
    """GetLeft/RightArmCurve of Algorithm 2: (N, 2) from the shoulder, the centres of the outermost runs that
    torso, head and legs leave on that image side (``runs``: that side instead, for a crossing arm)."""
    shoulder = joints[JOINT_INDEX[f"shoulder_{side}"]]
    neck, pelvis = joints[JOINT_INDEX["neck"]], joints[JOINT_INDEX["pelvis"]]
    reach = (LENGTH[SEGMENT_INDEX["upper_arm_l"]] + LENGTH[SEGMENT_INDEX["lower_arm_l"]]) * scale
    y0 = max(int(shoulder[1] - reach), 0)
    y1 = int(shoulder[1] + reach)
    residual = canvas.sil[y0:y1] > canvas.fixed[y0:y1]
    rows, starts, ends = row_runs(residual)
    min_w = 0.3 * WIDTH[SEGMENT_INDEX["upper_arm_l"]] * scale
    keep = (ends - starts) >= min_w
    rows, centres = rows[keep] + y0, (starts[keep] + ends[keep]) / 2
    # torso axis x on each row: the arm's image side is relative to it
    t = (rows - pelvis[1]) / (neck[1] - pelvis[1]) if abs(neck[1] - pelvis[1]) > 1e-6 else 0 * rows
    axis_x = pelvis[0] + t * (neck[0] - pelvis[0])
    runs = runs or side
    on_side = centres < axis_x if runs == "l" else centres > axis_x
    rows, centres = rows[on_side], centres[on_side]
    if len(rows) == 0:
        return np.zeros((0, 2))
    order = np.lexsort((centres if runs == "l" else -centres, rows))
    rows, centres = rows[order], centres[order]
    first = np.r_[True, rows[1:] != rows[:-1]]  # outermost run per row
    pts = np.column_stack([centres[first], rows[first].astype(float)])
    near = np.hypot(*(pts - shoulder).T) <= reach * 1.1
    pts = pts[near]
    pts = pts[np.argsort(np.hypot(*(pts - shoulder).T))]
    return np.vstack([shoulder[None, :], pts])
