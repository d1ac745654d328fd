"""How steady the limbs' left/right naming is when the fit moves by a pixel.

Each development clip is fitted on its true masks as they are, dilated and eroded by
one pixel (bench_clips.true_mask_session), and named with no user input
(mocap.lift.sides). Per clip and fit it prints the mean 2D error in % of the body
height as named and what the naming adds to it (as named less side-matched:
mocap.synth.metrics.side_matched_errors), and the frames whose naming differs from the
fit on the masks as they are, where the two namings lie over 10% of the body height
apart; last the naming's share summed over the clips. A naming that rests on its
evidence adds little on every fit and hardly changes from one fit to the next.

    python benchmarks/bench_naming.py [--clips NAME ...]
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np
from bench_clips import CLIPS, clip_names, true_mask_session

from mocap.body import JOINT_INDEX, LIMB_JOINTS
from mocap.synth.metrics import side_matched_errors

GROWS = (0, 1, -1)  # pixels the true masks are dilated by (eroded where negative)
CLEAR = 0.1  # of the body height between the two namings of a frame's legs: it matters
_LEGS = [[JOINT_INDEX[f"{n}_{s}"] for n in LIMB_JOINTS["leg"][1:]] for s in "lr"]


def named_right_leg(joints: np.ndarray, truth: np.ndarray, height: float) -> tuple[np.ndarray, np.ndarray]:
    """(F,) bool: whether the output's right leg is the truth's (its knee and ankle
    nearer), and (F,) whether that matters (the two pairings CLEAR apart)."""
    own = sum(np.linalg.norm(joints[:, j] - truth[:, j], axis=-1).sum(1) for j in _LEGS)
    other = sum(np.linalg.norm(joints[:, j] - truth[:, k], axis=-1).sum(1) for j, k in zip(_LEGS, _LEGS[::-1]))
    return own < other, np.abs(own - other) > CLEAR * height


def naming_errors(joints: np.ndarray, true2d: np.ndarray, height: float) -> tuple[float, float]:
    """The mean 2D error of named joints (F, 16, 2; NaN where nobody was found)
    against the truth's in % of the body height, and what the naming adds to it (as
    named less side-matched: mocap.synth.metrics.side_matched_errors)."""
    ok = np.isfinite(joints).all(axis=(1, 2))
    named = float(np.linalg.norm(joints - true2d, axis=-1)[ok].mean()) * 100 / height
    return named, named - float(side_matched_errors(joints[ok], true2d[ok]).mean()) * 100 / height


def clip_rows(name: str) -> list[tuple[float, float, float]]:
    """Per fit of GROWS: mean 2D error as named, what the naming adds, % of the
    frames where it matters named otherwise than on the masks as they are."""
    truth = json.loads((CLIPS / name / "truth.json").read_text())
    true2d = np.array([f["joints2d"] for f in truth["frames"]], float)
    rows, first = [], None
    for grow in GROWS:
        joints = true_mask_session(name, grow=grow).inputs.joints2d
        ok = np.isfinite(joints).all(axis=(1, 2))
        right, clear = named_right_leg(joints, true2d, truth["body_height_px"])
        first = right if first is None else first
        changed = 100 * np.mean((right != first)[clear & ok]) if (clear & ok).any() else 0.0
        rows.append(naming_errors(joints, true2d, truth["body_height_px"]) + (changed,))
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--clips", nargs="+", metavar="NAME", help="only these clips")
    args = parser.parse_args()
    if not CLIPS.is_dir():
        print(f"skipped: {CLIPS} is absent (the shared data sits beside the checkout)")
        return 0
    print(f"{'clip':18s} " + " ".join(f"{f'grow {g:+d}: 2d% naming% changed%':>32s}" for g in GROWS))
    total = np.zeros(len(GROWS))
    for name in args.clips or clip_names():
        rows = clip_rows(name)
        total += [naming for _, naming, _ in rows]
        print(f"{name:18s} " + " ".join(f"{a:14.2f} {b:7.2f} {c:9.1f}" for a, b, c in rows), flush=True)
    print(f"{'naming adds, sum':18s} " + " ".join(f"{t:22.2f} {'':9s}" for t in total))
    return 0


if __name__ == "__main__":
    sys.exit(main())
