"""The keyframes the fit proposes (mocap.session.propose_keyframes, the app's default) against
lifting every frame and against every k-th frame, on the bundled sample and on motion capture
rendered from ../shared/data/bvh (walk, run, jumps; side and three-quarter views, 640x480,
30 fps): how many keyframes, and the exported motion's PA-MPJPE (mm) against the truth.

    python benchmarks/bench_keys.py [--seconds 4]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from mocap.lift.motion import build_motion
from mocap.pipeline import fit_video
from mocap.session import SilhouetteSession, propose_keyframes
from mocap.synth import render_motion
from mocap.synth.metrics import pa_mpjpe
from mocap.synth.truth import load_truth

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "sample_videos" / "walk.mp4"
BVH = ROOT.parent / "shared" / "data" / "bvh"
CLIPS = (("walk", "cmu_walk.bvh"), ("run", "cmu_run.bvh"), ("jumps", "cmu_01_01_jumps.bvh"))


def row(video: Path, truth) -> dict:
    """Frames, proposed keyframes, and PA-MPJPE (mm) of every frame, the proposal, every 3rd and 5th."""
    session = SilhouetteSession(*fit_video(video))
    person = [int(k) for k in np.flatnonzero(session.person)]
    poses = {k: session.pose3d(k) for k in person}
    n, fps, root = session.n_frames, session.info.fps, session.root()

    def error(keys) -> float:
        motion = build_motion({k: poses[k] for k in keys}, n, fps, root=root).joints3d
        return 1000 * pa_mpjpe(motion[person], truth.joints3d[person])

    proposed = propose_keyframes(session)
    return {
        "frames": len(person),
        "keys": len(proposed),
        "every": error(person),
        "proposed": error(proposed),
        "3rd": error(person[::3] + person[-1:]),
        "5th": error(person[::5] + person[-1:]),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=4.0)
    args = parser.parse_args()
    rows = [("sample walk", row(SAMPLE, load_truth(SAMPLE.with_suffix(".truth.json"))))]
    with tempfile.TemporaryDirectory() as tmp:
        for kind, name in CLIPS:
            if not (BVH / name).is_file():
                print(f"skipped: {name} absent from {BVH}")
                continue
            for view in ("side", "three-quarter"):
                video = Path(tmp) / f"{kind}_{view}.mp4"
                truth = render_motion(BVH / name, video, view=view, seconds=args.seconds, size=(640, 480), fps=30.0)
                rows.append((f"{kind} {view}", row(video, truth)))
    print(f"{'clip':<20} {'frames':>6} {'keys':>5}  PA-MPJPE mm: {'every':>6} {'proposed':>8} {'3rd':>6} {'5th':>6}")
    for name, r in rows:
        print(
            f"{name:<20} {r['frames']:>6} {r['keys']:>5}               {r['every']:>6.1f} {r['proposed']:>8.1f}"
            f" {r['3rd']:>6.1f} {r['5th']:>6.1f}"
        )


if __name__ == "__main__":
    main()
