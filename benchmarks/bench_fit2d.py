"""2D fit accuracy and speed on videos rendered from real motion capture.

Renders each BVH of ../shared/data/bvh from side and three-quarter views with the
motion's own proportions, runs the pipeline, and prints 2D errors in % of body
height (image-side matching, as the 2D fit labels sides): each clip's median, mean
and 90th percentile over its frames' joints, each joint's median, then
the fit's CPU time per frame (benchmarks/bench_pipeline.py times the whole command).

    python benchmarks/bench_fit2d.py [--quick]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("OMP_NUM_THREADS", "1")
import cv2  # noqa: E402

cv2.setNumThreads(1)

from mocap.body import JOINTS  # noqa: E402
from mocap.io.video import open_video  # noqa: E402
from mocap.pipeline import silhouette_passes  # noqa: E402
from mocap.silhouette.fit2d import FIT_SCALE, fit_frame  # noqa: E402
from mocap.silhouette.passes import body_heights, normalise, normalised_grey  # noqa: E402
from mocap.silhouette.torso import torso_spread  # noqa: E402
from mocap.synth import render_motion  # noqa: E402
from mocap.synth.metrics import side_matched_errors  # noqa: E402

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "bvh"
CLIPS = [  # (bvh, view, source frame range)
    ("cmu_walk.bvh", "side", None),
    ("cmu_walk.bvh", "three-quarter", None),
    ("cmu_run.bvh", "side", None),
    ("cmu_run.bvh", "three-quarter", None),
    ("cmu_01_01_jumps.bvh", "side", (0, 1200)),
    ("cmu_01_01_jumps.bvh", "three-quarter", (0, 1200)),
    ("walk01.bvh", "side", None),
    ("walk01.bvh", "three-quarter", None),
]


def run_clip(bvh: str, view: str, frames, workdir: Path):
    video = workdir / f"{Path(bvh).stem}_{view}.mp4"
    truth = render_motion(DATA / bvh, video, view=view, frames=frames)
    info = open_video(video)
    sils, fits = silhouette_passes(info)
    heights = body_heights(sils, info.fps)
    fit_ms = time_fits(sils, heights, [f.fit.pose.spread if f.fit else None for f in fits])
    pred = np.array([f.joints2d if f.joints2d is not None else np.full((16, 2), np.nan) for f in fits])
    err = side_matched_errors(pred, truth.joints2d) / truth.body_height_px * 100
    return err, fit_ms, (info.width, info.height)


def time_fits(sils, heights, spreads, repeats: int = 3) -> np.ndarray:
    """CPU milliseconds of the 2D fit alone (normalisation, torso foreshortening and
    Algorithms 1-6) per frame, on one thread: the best of ``repeats`` runs of each
    frame, so that other load on the machine does not count."""
    out, prev = [], None
    for sil, h, spread in zip(sils, heights, spreads):
        if sil is None:
            continue
        best = np.inf
        for _ in range(repeats):
            t = time.process_time()
            small, _, _ = normalise(sil, h)
            torso_spread(small, FIT_SCALE)
            fit = fit_frame(small, FIT_SCALE, prev, spread, normalised_grey(sil, h))
            best = min(best, time.process_time() - t)
        out.append(best * 1000)
        prev = fit.pose if fit.score >= 0.5 else None
    return np.array(out)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="first clip of each motion only")
    args = parser.parse_args()
    if not DATA.is_dir():
        print(f"skipped: {DATA} is absent")
        return 0
    clips = CLIPS[::2] if args.quick else CLIPS
    all_err, all_ms = [], []
    print(f"{'clip':34s} {'frames':>6s} {'median%':>8s} {'mean%':>6s} {'p90%':>6s} {'fit ms':>7s}  size")
    with tempfile.TemporaryDirectory() as tmp:
        for bvh, view, frames in clips:
            err, ms, size = run_clip(bvh, view, frames, Path(tmp))
            all_err.append(err)
            all_ms.append(ms)
            print(
                f"{Path(bvh).stem + ' ' + view:34s} {len(err):6d} {np.nanmedian(err):8.2f} "
                f"{np.nanmean(err):6.2f} {np.nanpercentile(err, 90):6.2f} {np.median(ms):7.2f}  {size[0]}x{size[1]}"
            )
    err = np.concatenate(all_err)
    print(
        f"{'all':34s} {len(err):6d} {np.nanmedian(err):8.2f} {np.nanmean(err):6.2f} {np.nanpercentile(err, 90):6.2f} "
        f"{np.median(np.concatenate(all_ms)):7.2f}"
    )
    print("\nper joint, median % of body height:")
    print("  ".join(f"{n}={np.nanmedian(err[:, i]):.1f}" for i, n in enumerate(JOINTS)))
    print(f"frames with a result: {np.isfinite(err).all(axis=1).mean() * 100:.1f}%")
    ms = np.median(np.concatenate(all_ms))
    print(
        f"2D fit: {ms:.2f} ms per frame (median, one thread, CPU time); the paper: about "
        f"1000 ms (2.7 GHz Celeron), {1000 / ms:.0f} times slower"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
