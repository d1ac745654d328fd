"""Error measures against ground truth: short pure functions over joint arrays."""

from __future__ import annotations

from itertools import permutations

import numpy as np

from mocap.body import JOINT_INDEX, LIMB_JOINTS
from mocap.lift.taylor import yaw_of

LIMBS = tuple(tuple((f"{j}_l", f"{j}_r") for j in names) for names in LIMB_JOINTS.values())


def side_matched_errors(pred: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Per-joint distances (F, J) of a prediction with image sides (section 3.3), each limb pair
    assigned to the true pair the way with the smaller total error."""
    err = np.linalg.norm(pred - truth, axis=-1)
    for limb in LIMBS:
        left = [JOINT_INDEX[a] for a, _ in limb]
        right = [JOINT_INDEX[b] for _, b in limb]
        swapped_l = np.linalg.norm(pred[:, left] - truth[:, right], axis=-1)
        swapped_r = np.linalg.norm(pred[:, right] - truth[:, left], axis=-1)
        swap = (swapped_l + swapped_r).sum(1) < (err[:, left] + err[:, right]).sum(1)
        err[np.ix_(swap, left)] = swapped_l[swap]
        err[np.ix_(swap, right)] = swapped_r[swap]
    return err


def procrustes_aligned(pred: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """pred (J, D) moved onto truth by the best similarity transform."""
    mp, mt = pred.mean(0), truth.mean(0)
    p, t = pred - mp, truth - mt
    u, s, vt = np.linalg.svd(p.T @ t)
    d = np.sign(np.linalg.det(u @ vt))
    fix = np.ones(len(s))
    fix[-1] = d
    rot = (u * fix) @ vt
    scale = (s * fix).sum() / max((p**2).sum(), 1e-12)
    return scale * p @ rot + mt


def pa_mpjpe(pred: np.ndarray, truth: np.ndarray) -> float:
    """Mean per-joint error after Procrustes alignment, averaged over frames (F, J, 3)."""
    return float(np.mean([np.linalg.norm(procrustes_aligned(p, t) - t, axis=-1).mean() for p, t in zip(pred, truth)]))


def facing_error(pred: np.ndarray, truth: np.ndarray) -> float:
    """Mean absolute facing-yaw error (degrees; lift.yaw_of, which PA-MPJPE forgives) of poses (F, 16, 3)."""
    diff = np.array([yaw_of(p) - yaw_of(t) for p, t in zip(pred, truth)])
    return float(np.mean(np.abs((diff + 180.0) % 360.0 - 180.0)))


def labelled_errors(joints2d: np.ndarray, labels: dict[str, dict[str, list[float]]]) -> dict[str, np.ndarray]:
    """Pixel distances (one per mark) of 2D joints (F, 16, 2) from hand marks, by joint kind.
    ``labels``: frame index (a string) -> joint -> (x, y); sideless pair marks (``knee_a``,
    ``knee_b``, either optional) are matched to ``knee_l``/``knee_r`` the cheaper way."""
    out: dict[str, list[float]] = {}
    for frame, marks in labels.items():
        joints = joints2d[int(frame)]
        for kind in dict.fromkeys(name.removesuffix("_a").removesuffix("_b") for name in marks):
            seen = [np.asarray(marks[n], float) for n in (kind, f"{kind}_a", f"{kind}_b") if n in marks]
            if kind in JOINT_INDEX:
                options = [(joints[JOINT_INDEX[kind]],)]
            else:
                options = list(permutations(joints[[JOINT_INDEX[f"{kind}_l"], JOINT_INDEX[f"{kind}_r"]]], len(seen)))
            distances = min((np.linalg.norm(np.array(seen) - np.array(o), axis=-1) for o in options), key=np.sum)
            out.setdefault(kind, []).extend(distances.tolist())
    return {kind: np.array(d) for kind, d in out.items()}


def labelled_body_height(labels: dict[str, dict[str, list[float]]]) -> float:
    """The body height in pixels that hand marks show: the median over frames of the
    lower marked ankle's height below the head top."""
    return float(
        np.median([max(m[a][1] for a in ("ankle_a", "ankle_b") if a in m) - m["head_top"][1] for m in labels.values()])
    )
