"""Does the review queue send the user to the wrong signs? On each static-camera development clip of
../shared/data/clips, fitted with no input through the person model (the product, as `mocap fit`
runs it), the solved foreshortening signs are compared with the truth's (segments whose true
|dZ| / length >= 0.1, as ../shared/bench/score.py counts them).

Columns: "wrong %", signs wrong among those counted; "close %", the share of counted signs the
queue calls a close call (mocap.session.review.close_calls); "wrong if close %", signs wrong
among the close calls; "found %", the share of the wrong signs that are close calls; "top-10
wrong", the wrong signs per frame on the queue's first 10 frames against every frame's mean
("per frame"): a review that stops there fixes that many per stop.

    python benchmarks/bench_review.py [--clips NAME ...]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from mocap.pipeline import open_session
from mocap.session.review import close_calls, seen_fractions

SHARED = Path(__file__).resolve().parents[1].parent / "shared"
CLIPS = SHARED / "data" / "clips"


def true_signs(clip: Path) -> tuple[np.ndarray, np.ndarray]:
    """(F, 10) the truth's signs (+1 toward) and (F, 10) bool, which the scorer counts (its own contract.signs
    and SIGN_MIN_RATIO, from ../shared/bench)."""
    sys.path.insert(0, str(SHARED / "bench"))
    from contract import SIGN_MIN_RATIO, signs

    joints = np.array([f["joints3d"] for f in json.loads((clip / "truth.json").read_text())["frames"]], float)
    toward, ratio = signs(joints)
    return np.where(toward, 1, -1), ratio >= SIGN_MIN_RATIO


def row(clip: Path) -> dict:
    """One clip's figures (the module's columns)."""
    session = open_session(clip / "video.mp4", person="mediapipe")
    inputs = session.inputs
    truth, counted = true_signs(clip)
    counted &= session.person[:, None]
    wrong = (session.solution().signs != truth) & counted
    close = close_calls(session.sign_margins(), seen_fractions(inputs.joints2d, inputs.px_per_unit, inputs.lengths))
    close &= counted
    top = [d.frame for d in session.review_queue()[:10]]
    return {
        "wrong %": 100 * wrong.sum() / counted.sum(),
        "close %": 100 * close.sum() / counted.sum(),
        "wrong if close %": 100 * (wrong & close).sum() / max(close.sum(), 1),
        "found %": 100 * (wrong & close).sum() / max(wrong.sum(), 1),
        "top-10 wrong": wrong[top].sum(axis=1).mean() if top else float("nan"),
        "per frame": wrong[session.person].sum(axis=1).mean(),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clips", nargs="*")
    args = parser.parse_args()
    if not CLIPS.is_dir():
        sys.exit(f"skipped: the development clips are absent ({CLIPS})")
    names = args.clips or sorted(p.name for p in CLIPS.iterdir() if (p / "truth.json").is_file())
    names = [n for n in names if not n.startswith("track_")]
    rows = {name: row(CLIPS / name) for name in names}
    columns = list(next(iter(rows.values())))
    print(f"{'clip':18s}" + "".join(f"{c:>18s}" for c in columns))
    for name, r in rows.items():
        print(f"{name:18s}" + "".join(f"{r[c]:18.2f}" for c in columns))
    print(f"{'mean':18s}" + "".join(f"{np.mean([r[c] for r in rows.values()]):18.2f}" for c in columns))


if __name__ == "__main__":
    main()
