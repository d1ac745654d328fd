"""Which way the performer faces and which limb is which, with no user input, on the
development clips against their exact truth.

Each static-camera clip of ../shared/data/clips is fitted as `mocap fit` fits it (its
own silhouettes against the estimated background) or, with --true-masks, on its true
masks, and its first guess (mocap.lift.orientation, mocap.lift.sides) is compared with
the truth frame by frame. Per clip it prints, in % of frames: the orientation named
as the truth names it (one of the six), named a profile, truly in one (|cos yaw| <
0.5), the legs and the arms named the other way round (the anatomical sides that put
the fit's knees and ankles, elbows and wrists nearer the truth, where the true limbs
are apart); then the mean 2D error in % of the body height as named and with each
frame's arms and legs named the way that fits the truth best: what naming alone could
still gain on top of the fit.

    python benchmarks/bench_sides.py [--true-masks] [--clips NAME ...]
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np
from bench_clips import CLIPS, clip_names, true_mask_session

from mocap.body import JOINT_INDEX
from mocap.pipeline import open_session

APART = 0.05  # of the body height between the true distal joints: limbs told apart
PROFILE = 0.5  # true |cos yaw| below which the truth is a profile
_PAIRS = {"arm": ("shoulder", "elbow", "wrist"), "leg": ("hip", "knee", "ankle")}


def guessed(name: str, true_masks: bool) -> tuple[dict, list, np.ndarray]:
    """A clip's truth, its orientations as guessed with no input and its 2D joints
    (F, 16, 2) named by the guessed sides."""
    session = true_mask_session(name) if true_masks else open_session(CLIPS / name / "video.mp4")
    truth = json.loads((CLIPS / name / "truth.json").read_text())
    return truth, session.inputs.orientation, session.inputs.joints2d


def swapped(joints: np.ndarray, kind: str) -> np.ndarray:
    """(F, 16, 2) with the limbs of ``kind`` exchanged between the sides."""
    out = joints.copy()
    left, right = ([JOINT_INDEX[f"{n}_{s}"] for n in _PAIRS[kind]] for s in "lr")
    out[:, left], out[:, right] = joints[:, right], joints[:, left]
    return out


def clip_row(name: str, true_masks: bool) -> list[float]:
    """The table's values for one clip (see the module docstring)."""
    truth, named, joints = guessed(name, true_masks)
    frames, height = truth["frames"], truth["body_height_px"]
    true2d = np.array([f["joints2d"] for f in frames])
    cos = np.abs(np.cos(np.radians([f["facing_deg"] for f in frames])))
    row = [
        100 * np.mean([n == f["orientation"] for n, f in zip(named, frames)]),
        100 * np.mean([n in ("left", "right") for n in named]),
        100 * np.mean(cos < PROFILE),
    ]

    def error(j: np.ndarray) -> np.ndarray:
        return np.linalg.norm(j - true2d, axis=-1).mean(axis=1) / height * 100

    for kind in ("leg", "arm"):
        tip = [JOINT_INDEX[f"{_PAIRS[kind][-1]}_{s}"] for s in "lr"]
        apart = np.linalg.norm(true2d[:, tip[0]] - true2d[:, tip[1]], axis=-1) > APART * height
        chain = [JOINT_INDEX[f"{n}_{s}"] for n in _PAIRS[kind][1:] for s in "lr"]
        own = np.linalg.norm(joints[:, chain] - true2d[:, chain], axis=-1).sum(axis=1)
        other = np.linalg.norm(swapped(joints, kind)[:, chain] - true2d[:, chain], axis=-1).sum(axis=1)
        row.append(100 * np.mean(other[apart] < own[apart]) if apart.any() else np.nan)
    options = [joints, swapped(joints, "arm"), swapped(joints, "leg"), swapped(swapped(joints, "arm"), "leg")]
    return row + [float(np.nanmean(error(joints))), float(np.nanmean(np.nanmin([error(j) for j in options], 0)))]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--true-masks", action="store_true", help="fit each clip's true masks")
    parser.add_argument("--clips", nargs="+", metavar="NAME", help="only these clips")
    args = parser.parse_args()
    if not CLIPS.is_dir():
        print(f"skipped: {CLIPS} is absent (the shared data sits beside the checkout)")
        return 0
    print(
        f"{'clip':18s} {'orient%':>7s} {'profile%':>8s} {'true%':>6s} {'legs_x%':>7s} {'arms_x%':>7s} "
        f"{'2d%':>6s} {'best%':>6s}"
    )
    rows = []
    for name in args.clips or clip_names():
        rows.append(clip_row(name, args.true_masks))
        print(
            f"{name:18s} "
            + " ".join(f"{v:{w}.1f}" for v, w in zip(rows[-1][:5], (7, 8, 6, 7, 7)))
            + f" {rows[-1][5]:6.2f} {rows[-1][6]:6.2f}",
            flush=True,
        )
    mean = np.nanmean(rows, axis=0)
    print(
        f"{'mean':18s} "
        + " ".join(f"{v:{w}.1f}" for v, w in zip(mean[:5], (7, 8, 6, 7, 7)))
        + f" {mean[5]:6.2f} {mean[6]:6.2f}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
