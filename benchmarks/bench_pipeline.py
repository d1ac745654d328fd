"""Whole-pipeline speed of `mocap fit` on a 640x480 clip, stage by stage.

Renders 20 s of the CMU jumps motion capture (600 frames, 640x480, three-quarter
view) and times each stage of the fit as the command line runs it, then the
command itself end to end.

    python benchmarks/bench_pipeline.py [--seconds 20]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from mocap.silhouette.passes import body_heights, iter_fits, iter_silhouettes
from mocap.synth import render_motion
from mocap.io.video import open_video, processing_scale

BVH = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "bvh" / "cmu_01_01_jumps.bvh"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=20.0)
    args = parser.parse_args()
    if not BVH.is_file():
        print(f"skipped: {BVH} is absent")
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        video = Path(tmp) / "jumps.mp4"
        render_motion(BVH, video, view="three-quarter", seconds=args.seconds)
        info = open_video(video)
        scale = processing_scale(info)
        t0 = time.perf_counter()
        sils = list(iter_silhouettes(info, scale))
        t1 = time.perf_counter()
        fits = list(iter_fits(sils, body_heights(sils, info.fps), scale, info.fps))
        t2 = time.perf_counter()
        out = Path(tmp) / "jumps.motion.json"
        subprocess.run(["mocap", "fit", str(video), "--out", str(out), "--quiet"], check=True)
        t3 = time.perf_counter()
    n = info.frame_count
    print(f"{'stage':40s} {'ms/frame':>9s} {'frames/s':>9s}")
    for name, seconds in (("background + silhouettes (decode incl.)", t1 - t0),
                          ("torso foreshortening + 2D fit", t2 - t1),
                          ("mocap fit, whole command", t3 - t2)):
        print(f"{name:40s} {1000 * seconds / n:9.2f} {n / seconds:9.1f}")
    print(f"{n} frames {info.width}x{info.height}; {sum(f.joints2d is not None for f in fits)} fitted")
    return 0


if __name__ == "__main__":
    sys.exit(main())
