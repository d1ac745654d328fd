"""The 2D fit alone (pass two, chained frame to frame as the pipeline chains it) on the
development clips' silhouettes: each clip's fit's own 2D error, in % of the true body
height with each arm pair and leg pair matched to the truth's sides
(``mocap.synth.metrics.side_matched_errors``), in seconds a clip where bench_clips.py takes
minutes (no silhouette pass, no lift, no scorer).

The silhouettes are each clip's true masks, or with --masks DIR those a
``bench_clips.py --keep DIR`` run wrote (DIR/<clip>/auto_masks): a change to the fit
measured on the pipeline's own silhouettes of main, the same for both sides of the
comparison. The means come near the side-matched ones fit_tails.py reads from the
session's output (which also smooths the joints over time): scoop_34 6.68 here and
6.77 there on the true masks, 8.15 and 8.20 on main's silhouettes. Refitting single
frames from a recorded run's previous poses is no shortcut: each search is centred
on the previous frame's fit, so a change's effect carries on (on scoop_34, capping the
head's ratio at 1 gained 0.16 frame by frame and lost 0.34 chained).

    python benchmarks/bench_fit_sils.py [--masks DIR] [--clips NAME ...]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("OMP_NUM_THREADS", "1")

from bench_clips import CLIPS, clip_names, mask_silhouettes  # noqa: E402

from mocap.body import JOINT_INDEX  # noqa: E402
from mocap.silhouette.passes import iter_fits  # noqa: E402
from mocap.synth.metrics import side_matched_errors  # noqa: E402

ARMS = [JOINT_INDEX[f"{j}_{s}"] for j in ("elbow", "wrist") for s in "lr"]
LEGS = [JOINT_INDEX[f"{j}_{s}"] for j in ("knee", "ankle") for s in "lr"]


def clip_errors(name: str, masks: Path) -> tuple[np.ndarray, float]:
    """(F, 16) side-matched 2D errors (% of the true body height, NaN where nothing
    was fitted) of the fit of one clip's masks, and the fit's CPU seconds a frame."""
    info, scale, silhouettes = mask_silhouettes(CLIPS / name, masks)
    start = time.process_time()
    fits = list(iter_fits(silhouettes, scale, info.fps))
    seconds = (time.process_time() - start) / max(len(fits), 1)
    truth = json.loads((CLIPS / name / "truth.json").read_text())
    nan = np.full((len(JOINT_INDEX), 2), np.nan)
    pred = np.array([nan if f.joints2d is None else f.joints2d for f in fits], float)
    true = np.array([f["joints2d"] for f in truth["frames"]], float)
    return side_matched_errors(pred, true) * 100.0 / truth["body_height_px"], seconds


def report(names: list[str], kept: Path | None) -> None:
    """Print each clip's row (side-matched mean, median and 90th percentile of the
    frames' means, arms' and legs' means, the fit's CPU ms a frame) and the mean of
    the clips' means; ``kept``: a bench_clips.py --keep folder's silhouettes, else
    the true masks."""
    print(f"{'clip':18s} {'mean':>6s} {'median':>6s} {'p90':>6s} {'arms':>6s} {'legs':>6s} {'ms/frame':>8s}")
    means = []
    for name in names:
        err, seconds = clip_errors(name, CLIPS / name / "masks" if kept is None else kept / name / "auto_masks")
        frame = np.nanmean(err, axis=1)
        means.append(np.nanmean(err))
        print(
            f"{name:18s} {means[-1]:6.2f} {np.nanmedian(frame):6.2f} {np.nanpercentile(frame, 90):6.2f} "
            f"{np.nanmean(err[:, ARMS]):6.2f} {np.nanmean(err[:, LEGS]):6.2f} {seconds * 1000:8.1f}",
            flush=True,
        )
    print(f"devset: side-matched 2d_err={np.mean(means):.2f}% over {len(means)} clips")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--masks", type=Path, metavar="DIR", help="a bench_clips.py --keep folder's silhouettes")
    parser.add_argument("--clips", nargs="+", metavar="NAME", help="only these clips")
    args = parser.parse_args()
    if CLIPS.is_dir():
        report(args.clips or clip_names(), args.masks)
    else:
        print(f"skipped: {CLIPS} is absent (the shared data sits beside the checkout)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
