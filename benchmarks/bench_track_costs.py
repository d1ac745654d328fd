"""Why the tracker loses a part: the block-matching cost where it put the part against
the cost where the truth has it, on the tracking clips of bench_track_clips.py.

The clip is tracked as `mocap fit --method track` tracks it from its frame-0 marks
(mocap.track.tracker.BodyTracker, one pass from frame 0). On every frame, for every
part, the cost 1/S (grey levels, blocks.similarity) of the tracked block and of the
block between the truth's two joints (as wide as the tracked one) against the colour
model the tracker matches that part with, and the error of the part's far joint in %
of the body's height. A part off by more than --off % is "preferred" where its
tracked block costs less than the truth's (the colour model prefers the wrong place:
a matching problem) and "missed" where the truth's costs less (the search did not
reach it, or a twin, a penalty or the joint search with the limb's other part won).
Parts are compared with the truth's joints of their own name: a leg tracking its twin
(on the other leg where they cross) counts as off.

    python benchmarks/bench_track_costs.py [--clips track_salsa] [--part upper_arm_l]
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np
from bench_track_clips import RENDERED, SHARED, clip_files

from mocap.body import JOINTS
from mocap.camera import default_camera
from mocap.io.video import iter_frames, open_video, processing_scale
from mocap.track import blocks
from mocap.track.parts import PART_JOINTS, PARTS
from mocap.track.tracker import BodyTracker
from mocap.track.tracking import turn_of

OFF_PCT = 5.0  # % of the body's height: a part's far joint this far from the truth is off


def part_costs(video: Path, truth: Path, marks: Path) -> dict[str, np.ndarray]:
    """Per frame after the first (F-1, 10): ``tracked`` and ``true`` costs (grey
    levels) and ``error`` (% of the body's height) of every part's far joint; (F-1,)
    ``lost``: whether the tracker marked the body lost."""
    info = open_video(video)
    scale = processing_scale(info)
    known = json.loads(truth.read_text())
    true2d = (np.array([f["joints2d"] for f in known["frames"]]) + 0.5) * scale - 0.5
    height = known["body_height_px"] * scale  # as the scorer reads it
    first = json.loads(marks.read_text())["frames"]["0"]
    marked = (np.array([first["joints2d"][j] for j in JOINTS], float) + 0.5) * scale - 0.5
    camera = default_camera(info.width, info.height).scaled(scale)
    images = (image for _, image in iter_frames(info, scale=scale))
    tracker = BodyTracker(next(images), marked, camera, turn_of(first.get("orientation")), info.fps)
    out: dict[str, list] = {"tracked": [], "true": [], "error": [], "lost": []}
    for i, image in enumerate(images, start=1):
        models = [tracker._model(k) for k in range(len(PARTS))]  # as matched, before the update
        joints, _ = tracker.step(image)
        placed = tracker.blocks
        truths = blocks.between(true2d[i, PART_JOINTS[:, 0]], true2d[i, PART_JOINTS[:, 1]], placed[:, blocks.N])
        for key, where in (("tracked", placed), ("true", truths)):
            out[key].append([cost(image, models[k], tracker.grids[k], where[k]) for k in range(len(PARTS))])
        far = PART_JOINTS[:, 1]
        out["error"].append(np.linalg.norm(joints[far] - true2d[i, far], axis=-1) / height * 100)
        out["lost"].append(tracker.lost)
    return {key: np.array(value) for key, value in out.items()}


def cost(image: np.ndarray, model: np.ndarray, grid: blocks.Grid, block: np.ndarray) -> float:
    """1/S (grey levels) of a part's ``block`` against its colour ``model``."""
    return float(1.0 / blocks.score(image, model, grid, block)[0])


def summary(costs: dict[str, np.ndarray], off: float) -> None:
    """Per part: frames off (the body not marked lost), of them preferred / missed,
    and the mean costs there."""
    print(f"{'part':<13} {'off':>4} {'preferred':>9} {'missed':>6} {'tracked':>7} {'true':>6}")
    for k, part in enumerate(PARTS):
        bad = (costs["error"][:, k] > off) & ~costs["lost"]
        preferred = bad & (costs["tracked"][:, k] < costs["true"][:, k])
        tracked, true = (f"{costs[c][bad, k].mean():>6.1f}" if bad.any() else f"{'-':>6}" for c in ("tracked", "true"))
        print(
            f"{part.segment:<13} {bad.sum():>4} {preferred.sum():>9} {(bad & ~preferred).sum():>6} {tracked:>7} {true}"
        )


def frames_of(costs: dict[str, np.ndarray], segment: str) -> None:
    """One part's costs and error on every frame."""
    k = next(i for i, p in enumerate(PARTS) if p.segment == segment)
    print(f"{'frame':>5} {'tracked':>7} {'true':>6} {'err %':>6}")
    rows = zip(costs["tracked"][:, k], costs["true"][:, k], costs["error"][:, k], costs["lost"])
    for i, (tracked, true, error, lost) in enumerate(rows, start=1):
        print(f"{i:>5} {tracked:>7.1f} {true:>6.1f} {error:>6.1f}{'  lost' if lost else ''}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clips", nargs="+", default=list(SHARED), choices=[*SHARED, *RENDERED])
    parser.add_argument("--part", choices=[p.segment for p in PARTS], help="also list this part's frames")
    parser.add_argument("--off", type=float, default=OFF_PCT, help="%% of the body's height a part is off from")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.clips:
            costs = part_costs(*clip_files(name, Path(tmp)))
            print(
                f"{name}: parts off by more than {args.off:g}% of the body's height on frames 1.."
                f"{len(costs['error'])}, {int(costs['lost'].sum())} marked lost aside"
            )
            summary(costs, args.off)
            if args.part:
                frames_of(costs, args.part)


if __name__ == "__main__":
    main()
