"""Where the 2D error's mean comes from: each development clip's worst frames and joints.

Reads the outputs that ``bench_clips.py --keep DIR`` leaves (DIR/<clip>/auto.json, or
oracle.out.json with --oracle, beside the clip's truth.json) and, per clip, splits the
2D error (% of the true body height, as ../shared/bench/score.py measures it) into
the fit's own error, with each arm pair and leg pair matched to the truth's sides
(``mocap.synth.metrics.side_matched_errors``: the fit names limbs by image side, the lift
names them), and what the naming adds (left/right swaps). It lists the frames with the
largest side-matched error and their worst joints, and the share of the clip's mean
that its worst tenth of the frames carries. With --draw OUT it writes each listed frame
as OUT/<clip>_<frame>.png: the video frame with the true mask's outline (yellow), the
truth's joints (green) and the output's (the overlay's colours: image-left limbs
orange, image-right blue, as named in the file).

With --base DIR2 (another --keep folder, e.g. of the main branch) each clip also gets a
line of its means before -> after and the joints that moved most.

    python benchmarks/fit_tails.py DIR [--base DIR2] [--clips NAME ...] [--worst N] [--draw OUT] [--oracle]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from mocap.body import JOINTS
from mocap.synth.metrics import side_matched_errors

CLIPS = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "clips"
TAIL_SHARE = 0.1  # the worst tenth of the frames: the mean's tail
TRUTH_COLOUR = (60, 220, 60)  # BGR
MASK_COLOUR = (0, 220, 255)
ZOOM = 3


def clip_errors(motion: dict, truth: dict) -> tuple[np.ndarray, np.ndarray]:
    """(F, 16) 2D errors in % of the true body height: as named, and side-matched;
    NaN rows where the output has no joints."""
    n = len(truth["frames"])
    pred = np.full((n, len(JOINTS), 2), np.nan)
    for entry in motion["frames"]:
        if entry.get("joints2d") is not None and 0 <= entry["index"] < n:
            pred[entry["index"]] = entry["joints2d"]
    true = np.array([f["joints2d"] for f in truth["frames"]], float)
    scale = 100.0 / truth["body_height_px"]
    return np.linalg.norm(pred - true, axis=-1) * scale, side_matched_errors(pred, true) * scale


def tail_report(name: str, named: np.ndarray, matched: np.ndarray, worst: int) -> tuple[str, list[int]]:
    """The clip's text block and its worst frames (by side-matched mean error)."""
    ok = np.isfinite(named).all(1)
    per_frame = np.where(ok, np.nan_to_num(matched).mean(1), -np.inf)
    order = [int(i) for i in np.argsort(-per_frame) if ok[i]]
    tail = order[: max(1, int(round(TAIL_SHARE * ok.sum())))]
    mean_named, mean_matched = named[ok].mean(), matched[ok].mean()
    share = matched[tail].sum() / max(matched[ok].sum(), 1e-9)
    joints = matched[ok].mean(0)
    lines = [
        f"{name}: mean {mean_named:.2f}% as named, {mean_matched:.2f}% side-matched "
        f"(swaps add {mean_named - mean_matched:.2f}); median {np.median(matched[ok]):.2f}%; "
        f"worst {TAIL_SHARE:.0%} of frames carry {share:.0%} of the side-matched error",
        "  joints (side-matched mean %): " + " ".join(f"{JOINTS[k]} {joints[k]:.1f}" for k in np.argsort(-joints)[:6]),
    ]
    for i in order[:worst]:
        top = np.argsort(-matched[i])[:4]
        lines.append(
            f"  frame {i:4d}: {matched[i].mean():5.2f}% (named {named[i].mean():5.2f})  "
            + "  ".join(f"{JOINTS[k]} {matched[i, k]:.1f}" for k in top)
        )
    return "\n".join(lines), order[:worst]


def draw_frame(clip: Path, truth: dict, motion: dict, index: int) -> np.ndarray:
    """The video frame around the true body, enlarged ZOOM times, with the true mask's
    outline, the truth's joints and the output's."""
    import cv2

    from mocap.image.draw import draw_skeleton

    video = cv2.VideoCapture(str(clip / "video.mp4"))
    video.set(cv2.CAP_PROP_POS_FRAMES, index)
    ok, image = video.read()
    if not ok:
        raise SystemExit(f"fit_tails: cannot read frame {index} of {clip / 'video.mp4'}")
    truth_joints = np.array(truth["frames"][index]["joints2d"])
    pad = truth["body_height_px"] / 3
    x0, y0 = np.maximum(truth_joints.min(0) - pad, 0).astype(int)
    x1, y1 = (truth_joints.max(0) + pad).astype(int)
    view = cv2.resize(image[y0:y1, x0:x1], None, fx=ZOOM, fy=ZOOM, interpolation=cv2.INTER_CUBIC)

    def placed(points: np.ndarray) -> np.ndarray:
        return (points - [x0, y0]) * ZOOM

    mask = cv2.imread(str(clip / truth["frames"][index]["mask"]), cv2.IMREAD_GRAYSCALE)
    if mask is not None:
        outline, _ = cv2.findContours((mask > 127).astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
        cv2.polylines(view, [placed(c[:, 0]).astype(np.int32) for c in outline], True, MASK_COLOUR, 1)
    draw_skeleton(view, placed(truth_joints), thickness=2, colour=TRUTH_COLOUR)
    entry = next((f for f in motion["frames"] if f["index"] == index), None)
    if entry is not None and entry.get("joints2d") is not None:
        draw_skeleton(view, placed(np.array(entry["joints2d"])), thickness=2)
    return view


def load(folder: Path, name: str, output: str) -> tuple[dict, dict]:
    """A clip's output in a --keep folder and its truth (SystemExit naming what is missing)."""
    motion_path, truth_path = folder / name / output, CLIPS / name / "truth.json"
    if not (motion_path.is_file() and truth_path.is_file()):
        raise SystemExit(f"fit_tails: {motion_path} or {truth_path} is missing")
    return json.loads(motion_path.read_text()), json.loads(truth_path.read_text())


def change_report(before: tuple[np.ndarray, np.ndarray], after: tuple[np.ndarray, np.ndarray]) -> str:
    """One line: a clip's means as named and side-matched before -> after, and the
    joints whose side-matched mean moved most."""
    ok = np.isfinite(before[0]).all(1) & np.isfinite(after[0]).all(1)
    (named0, matched0), (named1, matched1) = ((n[ok], m[ok]) for n, m in (before, after))
    moved = matched1.mean(0) - matched0.mean(0)
    return (
        f"  against the base: {named0.mean():.2f} -> {named1.mean():.2f}% as named, "
        f"{matched0.mean():.2f} -> {matched1.mean():.2f}% side-matched; most moved: "
        + " ".join(
            f"{JOINTS[k]} {matched0[:, k].mean():.1f}->{matched1[:, k].mean():.1f}"
            for k in np.argsort(-np.abs(moved))[:4]
        )
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("dir", type=Path, help="a bench_clips.py --keep folder")
    parser.add_argument("--base", type=Path, metavar="DIR", help="another --keep folder to compare against")
    parser.add_argument("--clips", nargs="+", metavar="NAME", help="only these clips")
    parser.add_argument("--worst", type=int, default=8, help="frames listed per clip (default 8)")
    parser.add_argument("--draw", type=Path, metavar="OUT", help="write the listed frames as PNGs here")
    parser.add_argument("--oracle", action="store_true", help="read oracle.out.json instead of auto.json")
    args = parser.parse_args()
    output = "oracle.out.json" if args.oracle else "auto.json"
    if not args.dir.is_dir():
        print(f"fit_tails: {args.dir} is not a folder", file=sys.stderr)
        return 1
    names = args.clips or sorted(p.name for p in args.dir.iterdir() if (p / output).is_file())
    if not names:
        print(f"fit_tails: no {output} under {args.dir}", file=sys.stderr)
        return 1
    totals = []
    for name in names:
        motion, truth = load(args.dir, name, output)
        named, matched = clip_errors(motion, truth)
        text, frames = tail_report(name, named, matched, args.worst)
        print(text)
        if args.base:
            print(change_report(clip_errors(*load(args.base, name, output)), (named, matched)))
        ok = np.isfinite(named).all(1)
        totals.append((named[ok].mean(), matched[ok].mean()))
        if args.draw:
            import cv2

            args.draw.mkdir(parents=True, exist_ok=True)
            for i in frames:
                cv2.imwrite(str(args.draw / f"{name}_{i:04d}.png"), draw_frame(CLIPS / name, truth, motion, i))
    named_mean, matched_mean = np.mean(totals, axis=0)
    print(f"devset: 2d_err={named_mean:.2f}% as named, {matched_mean:.2f}% side-matched")
    return 0


if __name__ == "__main__":
    sys.exit(main())
