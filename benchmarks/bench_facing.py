"""Front or back: the orientation guess on renders of real motion capture seen from
every side, the performer's head drawn with hair (`mocap synth --hair`).

A silhouette and its 2D joints are the same seen from the front or from behind with
the depths mirrored; the head's look (mocap.silhouette.facing.facing_away) tells them apart.
Each BVH of ../shared/data/bvh below is rendered (640x480, 25 fps, 3 s, orthographic)
from seven camera yaws (90 front, 45 and 135 three-quarter front, 0 profile, -45 and
-135 three-quarter back, -90 back), fitted with the empty scene as the clean plate
(the silhouettes are not what is measured here) and guessed with no user input. Per
clip it prints the frames truly turned away (|yaw| > 90), the frames named forward,
backward and in profile, and of those named forward or backward the share named
the right way; then the mean 2D error in % of the body height as the limbs are
named and what the naming adds to it (as named less side-matched:
mocap.synth.metrics.side_matched_errors); last the same over all clips (the naming's share
summed).

    python benchmarks/bench_facing.py [--hairless]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np
from bench_naming import naming_errors

from mocap.io.bvh_reader import contract_joints, read_bvh
from mocap.lift.taylor import yaw_of
from mocap.pipeline import open_session
from mocap.synth import RenderOptions, background, plan_scene, render_clip, resample_indices

BVH = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "bvh"
MOTIONS = (
    ("cmu_16_15_walk.bvh", 10),
    ("cmu_02_04_jump_balance.bvh", 10),
    ("cmu_13_14_laugh.bvh", 1080),
    ("cmu_60_05_salsa.bvh", 600),
)
YAWS = (90.0, 45.0, 135.0, 0.0, -45.0, -135.0, -90.0)


def guess_clip(
    bvh: Path, start: int, yaw: float, hair: bool, folder: Path
) -> tuple[np.ndarray, list, tuple[float, float]]:
    """Render one clip, fit it against its empty scene; (F,) truly turned away, the
    guessed orientations and the 2D error as named and the naming's share of it
    (bench_naming.naming_errors)."""
    motion = read_bvh(bvh)
    joints = contract_joints(motion)
    opts = RenderOptions(yaw=yaw, fps=25.0, hair=hair)
    joints = joints[resample_indices(len(joints), motion.frame_time, opts.fps, (start, None), 3.0)]
    video, plate = folder / "clip.mp4", folder / "plate.png"
    truth = render_clip(joints, video, opts)
    cv2.imwrite(str(plate), background(plan_scene(joints, opts), 0))
    inputs = open_session(video, background=plate).inputs
    errors = naming_errors(inputs.joints2d, truth.joints2d, truth.body_height_px)
    return np.array([abs(yaw_of(p)) > 90 for p in truth.joints3d]), inputs.orientation, errors


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--hairless", action="store_true", help="heads of one colour (no cue)")
    args = parser.parse_args()
    if not BVH.is_dir():
        print(f"skipped: {BVH} is absent (the shared data sits beside the checkout)")
        return 0
    print(
        f"{'clip':34s} {'frames':>6s} {'away':>5s} {'fwd':>4s} {'back':>5s} {'prof':>5s} {'right%':>7s} "
        f"{'2d%':>6s} {'naming%':>7s}"
    )
    right = named = 0
    errors = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, start in MOTIONS:
            for yaw in YAWS:
                away, names, error = guess_clip(BVH / name, start, yaw, not args.hairless, Path(tmp))
                errors.append(error)
                back = np.array([str(n).startswith("backward") for n in names])
                fwd = np.array([str(n).startswith("forward") for n in names])
                hits = int((back & away).sum() + (fwd & ~away).sum())
                right, named = right + hits, named + int(back.sum() + fwd.sum())
                share = f"{100 * hits / max(back.sum() + fwd.sum(), 1):7.1f}" if (back | fwd).any() else "      -"
                print(
                    f"{Path(name).stem + f' yaw {yaw:.0f}':34s} {len(names):6d} {int(away.sum()):5d} "
                    f"{int(fwd.sum()):4d} {int(back.sum()):5d} {len(names) - int(back.sum() + fwd.sum()):5d} {share} "
                    f"{error[0]:6.2f} {error[1]:7.2f}",
                    flush=True,
                )
    print(
        f"all: {named} frames named forward or backward, {100 * right / max(named, 1):.1f}% the right way; "
        f"2D error {np.mean([e[0] for e in errors]):.2f}%, the naming's share summed {sum(e[1] for e in errors):.2f}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
