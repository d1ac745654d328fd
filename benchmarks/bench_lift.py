"""3D lifting (section 3.4) on videos rendered from real motion capture, exact truth.

For walk, run and jumps from ../shared/data/bvh, each seen from the side and in
three-quarter view (640x480, 30 fps, orthographic), it prints:

  (a) lifting alone: the TRUE 2D joints, the true orientation, signs and torso
      foreshortening, segment lengths from the clip -> PA-MPJPE (mm);
  (b) the whole pipeline (silhouettes, 2D fit, lifting, interpolation) with an
      annotation file written from the truth (orientation changes, every sign on
      every frame, the left wrist and ankle on the first profile frame) ->
      PA-MPJPE; beside it the floor the 2D fit allows: its 2D joints (with our
      sides) with the TRUE depths; and the same pipeline given the exact 2D joints
      in place of the fit's (each limb pair on the fit's image sides): what the
      lifting stage itself costs on top of (a)'s perfect inputs;
  (c) no annotations: how often the automatic signs are right on segments whose
      foreshortening is not negligible (|dZ| > 0.25 length), automatic signs on the
      true 2D joints, the orientation, and the user inputs still needed (a simulated
      user who goes through the clip and corrects the first wrong frame each time)
      beside Taylor's (14 clicks per keyframe, one keyframe in 5 frames, plus
      every sign change) and the paper's (sign changes + orientation; 12-21% of
      Taylor's).

With ``--noise`` it prints instead the old per-frame lift beside the clip-level solve
(mocap.lift.solve) on the static-camera development clips of
../shared/data/clips (real motion capture, another renderer): their exact 2D joints
(anatomical sides), plus Gaussian noise of 1, 2, 4 and 6 % of the body's height per
coordinate, the true facing yaw and scale, no person model:

  oracle signs     the true signs, held (as a user's) wherever a segment is out of the
                   image plane (|dZ| > 0.25 length)
  automatic signs  the first guess from the noisy 2D (orientation.guess_signs); the new
                   lift then chooses its own sign paths

  old  each frame lifted by Eq. 4-5 (taylor.lift_pose) at the lengths the product's
       inputs take (FIT_LENGTH_PERCENTILE), depths smoothed over DEPTH_SMOOTH_S: the
       silhouette session's 3D before the clip solve
  new  lift_clip from the same lengths: the clip solved at once, then its sign paths,
       then again

PA-MPJPE in mm over every frame, signs right on segments out of the image plane.

With ``--perspective`` it prints instead the clip solve through scaled orthography beside the
solve through the camera's pinhole (``ClipArrays.camera``, `mocap fit --focal`) on the
perspective development clips (track_*: a camera 3.5 m away), from their exact 2D joints plus
0, 2 and 4 % noise, the true facing yaw, signs (the first guess) and scale, each segment's true
|dZ| / length plus Gaussian noise of 0.15 as the person model's depths (the solve sees through
the pinhole only with them: ``ClipArrays.camera``).

    python benchmarks/bench_lift.py [--seconds 6]
    python benchmarks/bench_lift.py --noise [--per-clip] [--seed 0]
    python benchmarks/bench_lift.py --perspective [--seed 0]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.ndimage import gaussian_filter1d

from mocap.body import BODY_HEIGHT, JOINT_INDEX, SEGMENT_JOINTS, SEGMENT_NAMES
from mocap.camera import Pinhole
from mocap.io.annotations import Annotations
from mocap.lift.clipdata import ClipArrays
from mocap.lift.inputs import FIT_LENGTH_PERCENTILE
from mocap.lift.orientation import NEGLIGIBLE, guess_signs
from mocap.lift.solve import lift_clip
from mocap.lift.taylor import (
    UNIT_M,
    clip_lengths,
    depth_fractions,
    facing_yaw,
    image_to_model,
    lift_pose,
    orientation_of_yaw,
    signs_of,
    yaw_of,
)
from mocap.pipeline import fit_video
from mocap.session import SilhouetteSession as Session
from mocap.smoothest import DEPTH_SMOOTH_S
from mocap.synth import render_motion
from mocap.synth.metrics import pa_mpjpe
from mocap.synth.oracle import annotations_for_poses

BVH = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "bvh"
DEV_CLIPS = BVH.parent / "clips"
NOISE = (0.0, 1.0, 2.0, 4.0, 6.0)  # % of the body's height, per coordinate
CLIPS = (("walk", "cmu_walk.bvh"), ("walk", "walk01.bvh"), ("run", "cmu_run.bvh"), ("jumps", "cmu_01_01_jumps.bvh"))
VIEWS = ("side", "three-quarter")
TAYLOR_CLICKS, TAYLOR_KEY_EVERY = 14, 5
LIMBS = {"arms": ("elbow", "wrist"), "legs": ("knee", "ankle")}


def truth_of(truth) -> dict:
    """Per-frame true orientation, yaw, signs and non-negligible mask."""
    yaw = np.array([yaw_of(p) for p in truth.joints3d])
    return {
        "yaw": yaw,
        "orientation": [orientation_of_yaw(y) for y in yaw],
        "signs": np.array([signs_of(p) for p in truth.joints3d]),
        "visible": np.array([depth_fractions(p) for p in truth.joints3d]) > NEGLIGIBLE,
    }


def lift_true_2d(truth, t: dict) -> float:
    """(a) PA-MPJPE of lifting the true 2D joints with the true inputs."""
    n = len(truth.joints2d)
    ppu = np.full(n, truth.body_height_px / BODY_HEIGHT)
    lengths = clip_lengths(truth.joints2d, ppu)
    spread = np.abs(np.cos(np.radians(t["yaw"])))
    yaw = [facing_yaw(o, s) for o, s in zip(t["orientation"], spread)]
    pred = np.array([lift_pose(truth.joints2d[i], ppu[i], yaw[i], t["signs"][i], lengths) for i in range(n)])
    return pa_mpjpe(pred, truth.joints3d)


def auto_signs_true_2d(truth, t: dict) -> float:
    """(c) automatic signs from the true 2D joints and true orientation."""
    n = len(truth.joints2d)
    ppu = np.full(n, truth.body_height_px / BODY_HEIGHT)
    spread = np.abs(np.cos(np.radians(t["yaw"])))
    yaw = np.array([facing_yaw(o, s) for o, s in zip(t["orientation"], spread)])
    signs = guess_signs(truth.joints2d, ppu, yaw, clip_lengths(truth.joints2d, ppu))
    return float((signs == t["signs"])[t["visible"]].mean())


def floor_2d(session: Session, truth) -> float:
    """PA-MPJPE of the fitted 2D joints (our sides) with the true depths."""
    inputs = session.inputs
    xy = np.stack([image_to_model(j, p) for j, p in zip(inputs.joints2d, inputs.px_per_unit)]) * UNIT_M
    return pa_mpjpe(np.concatenate([xy, truth.joints3d[..., 2:]], axis=-1), truth.joints3d)


def with_true_2d(fits: list, truth) -> list:
    """The fits with the exact 2D joints in place of theirs, each left/right pair in
    the order the fit put it on the image."""
    pairs = [(JOINT_INDEX[j], JOINT_INDEX[j[:-1] + "r"]) for j in JOINT_INDEX if j.endswith("_l")]
    out = []
    for f in fits:
        if f.joints2d is None:
            out.append(f)
            continue
        got, want = f.joints2d, truth.joints2d[f.index]
        joints = want.copy()
        for a, b in pairs:
            kept = np.linalg.norm(got[[a, b]] - want[[a, b]], axis=-1).sum()
            if np.linalg.norm(got[[a, b]] - want[[b, a]], axis=-1).sum() < kept:
                joints[[a, b]] = want[[b, a]]
        out.append(replace(f, joints2d=joints))
    return out


def wrong_sides(session: Session, truth, frame: int) -> list[str]:
    """Limb pairs whose fitted 2D limbs are clearly given the wrong sides on a frame."""
    out = []
    got, want = session.inputs.joints2d[frame], truth.joints2d[frame]
    for pair, names in LIMBS.items():
        left = [JOINT_INDEX[f"{n}_l"] for n in names]
        right = [JOINT_INDEX[f"{n}_r"] for n in names]
        keep = (
            np.linalg.norm(got[left] - want[left], axis=-1).sum()
            + np.linalg.norm(got[right] - want[right], axis=-1).sum()
        )
        swap = (
            np.linalg.norm(got[left] - want[right], axis=-1).sum()
            + np.linalg.norm(got[right] - want[left], axis=-1).sum()
        )
        if swap < 0.7 * keep:
            out.append(pair)
    return out


def first_mistake(session: Session, truth, t: dict, sides_fixed: set[int]) -> tuple[int, dict] | None:
    """The earliest frame with a wrong orientation, side or sign, and what is wrong
    (sides once per frame: an override that cannot mend a bad 2D fit is not repeated)."""
    inputs = session.inputs
    wrong_sign = (inputs.signs != t["signs"]) & t["visible"]
    for i in range(len(truth.joints2d)):
        if inputs.orientation[i] != t["orientation"][i]:
            return i, {"orientation": t["orientation"][i]}
        pairs = [] if i in sides_fixed else wrong_sides(session, truth, i)
        if pairs:
            return i, {"sides": pairs}
        if wrong_sign[i].any():
            return i, {"signs": np.flatnonzero(wrong_sign[i]).tolist()}
    return None


def simulate_user(session: Session, truth, t: dict, cap: int = 400) -> dict:
    """Inputs a user needs: from no annotations, correct the first wrong frame (its
    orientation, else the sides by one joint override per limb pair, else every
    wrong sign) until nothing is wrong."""
    notes, counts = Annotations(), {"orientation": 0, "sides": 0, "signs": 0}
    sides_fixed: set[int] = set()
    for _ in range(cap):
        session.annotate(notes)
        found = first_mistake(session, truth, t, sides_fixed)
        if found is None:
            break
        i, what = found
        if "sides" in what:
            sides_fixed.add(i)
        if "orientation" in what:
            notes = notes.with_orientation(i, what["orientation"])
            counts["orientation"] += 1
        for pair in what.get("sides", []):
            joint = f"{LIMBS[pair][1]}_l"
            notes = notes.with_joint(i, joint, tuple(truth.joints2d[i, JOINT_INDEX[joint]]))
            counts["sides"] += 1
        for k in what.get("signs", []):
            notes = notes.with_foreshortening(i, SEGMENT_NAMES[k], "toward" if t["signs"][i, k] > 0 else "away")
            counts["signs"] += 1
    return counts


def sign_changes(t: dict) -> int:
    """Sign inputs without any guess: each segment's first non-negligible sign and
    every later change (the paper's and Taylor's foreshortening clicks)."""
    total = 0
    for k in range(len(SEGMENT_NAMES)):
        seen = t["signs"][t["visible"][:, k], k]
        total += int(len(seen) > 0) + int(np.count_nonzero(np.diff(seen)))
    return total


def run_clip(bvh: Path, view: str, seconds: float, folder: Path) -> dict:
    video = folder / f"{bvh.stem}_{view}.mp4"
    truth = render_motion(bvh, video, view=view, seconds=seconds, size=(640, 480), fps=30.0)
    t = truth_of(truth)
    info, fits = fit_video(video)
    row = {"frames": len(fits), "a": lift_true_2d(truth, t), "c_true2d": auto_signs_true_2d(truth, t)}
    session = Session(info, fits, annotations_for_poses(truth.joints3d, truth.joints2d))
    row["b"] = pa_mpjpe(session.motion().joints3d, truth.joints3d)
    row["floor"] = floor_2d(session, truth)
    exact = Session(info, with_true_2d(fits, truth), annotations_for_poses(truth.joints3d, truth.joints2d))
    row["b_exact"] = pa_mpjpe(exact.motion().joints3d, truth.joints3d)
    session.annotate(Annotations())
    inputs = session.inputs
    row["c_signs"] = float((inputs.signs == t["signs"])[t["visible"]].mean())
    row["c_orient"] = float(np.mean([a == b for a, b in zip(inputs.orientation, t["orientation"])]))
    row["c_visible"] = int(t["visible"].sum())
    row["inputs"] = simulate_user(session, truth, t)
    row["changes"] = sign_changes(t)
    row["taylor"] = TAYLOR_CLICKS * int(np.ceil(len(fits) / TAYLOR_KEY_EVERY)) + row["changes"]
    row["paper"] = row["changes"] + 1 + sum(a != b for a, b in zip(t["orientation"], t["orientation"][1:]))
    return row


def print_table(rows: list[tuple[str, dict]]) -> None:
    print("PA-MPJPE in mm (body height 1.75 m); signs on segments with |dZ| > 0.25 length\n")
    print(
        f"{'clip':22s} {'frames':>6s} {'(a) true2D':>10s} {'(b) annot':>9s} {'2D floor':>8s} "
        f"{'exact 2D':>8s} {'(c) signs':>9s} {'true2D':>6s} {'orient':>6s} {'n':>5s}"
    )
    for name, r in rows:
        print(
            f"{name:22s} {r['frames']:6d} {1000 * r['a']:10.1f} {1000 * r['b']:9.1f} {1000 * r['floor']:8.1f} "
            f"{1000 * r['b_exact']:8.1f} {100 * r['c_signs']:8.1f}% {100 * r['c_true2d']:5.1f}% "
            f"{100 * r['c_orient']:5.0f}% {r['c_visible']:5d}"
        )
    mean = {
        k: np.mean([r[k] for _, r in rows]) for k in ("a", "b", "floor", "b_exact", "c_signs", "c_true2d", "c_orient")
    }
    print(
        f"{'mean':22s} {'':6s} {1000 * mean['a']:10.1f} {1000 * mean['b']:9.1f} {1000 * mean['floor']:8.1f} "
        f"{1000 * mean['b_exact']:8.1f} {100 * mean['c_signs']:8.1f}% {100 * mean['c_true2d']:5.1f}% "
        f"{100 * mean['c_orient']:5.0f}%"
    )
    n = sum(r["c_visible"] for _, r in rows)
    pooled = {k: sum(r[k] * r["c_visible"] for _, r in rows) / n for k in ("c_signs", "c_true2d")}
    print(
        f"{'all segments pooled':22s} {'':6s} {'':10s} {'':9s} {'':8s} {'':8s} "
        f"{100 * pooled['c_signs']:8.1f}% {100 * pooled['c_true2d']:5.1f}% {'':6s} {n:5d}"
    )
    print("\nUser inputs still needed without annotations (simulated user) vs the paper's accounting")
    print(
        f"{'clip':22s} {'orient':>6s} {'sides':>5s} {'signs':>5s} {'ours':>5s} {'paper':>5s} "
        f"{'Taylor':>6s} {'ours/Taylor':>11s} {'paper/Taylor':>12s}"
    )
    for name, r in rows:
        ours = sum(r["inputs"].values())
        print(
            f"{name:22s} {r['inputs']['orientation']:6d} {r['inputs']['sides']:5d} {r['inputs']['signs']:5d} "
            f"{ours:5d} {r['paper']:5d} {r['taylor']:6d} {100 * ours / r['taylor']:10.1f}% "
            f"{100 * r['paper'] / r['taylor']:11.1f}%"
        )
    print("paper (section 4): walking 60/290 = 21%, dancing 59/506 = 12%")


# -- old and new lift against the 2D's noise (--noise) ---------------------------------


def dev_truths() -> list[tuple[str, dict]]:
    """(name, truth) of every static-camera development clip: joints2d (F, 16, 2), joints3d
    (F, 16, 3), yaw (F,) degrees, body_px, fps."""
    out = []
    for folder in sorted(DEV_CLIPS.iterdir()):
        path = folder / "truth.json"
        if not path.is_file() or folder.name.startswith("track_"):
            continue
        doc = json.loads(path.read_text())
        frames = doc["frames"]
        truth = {
            "joints2d": np.array([f["joints2d"] for f in frames], float),
            "joints3d": np.array([f["joints3d"] for f in frames], float),
            "yaw": np.array([f["facing_deg"] for f in frames], float),
            "body_px": float(doc["body_height_px"]),
            "fps": float(doc["video"]["fps"]),
        }
        out.append((folder.name, truth))
    return out


def old_lift(joints2d: np.ndarray, ppu: np.ndarray, yaw: np.ndarray, signs: np.ndarray, fps: float) -> np.ndarray:
    """(F, 16, 3) metres: each frame by Eq. 4-5 at the clip's fitted lengths, depths smoothed over time."""
    lengths = clip_lengths(joints2d, ppu, FIT_LENGTH_PERCENTILE, pool=True)
    poses = np.array([lift_pose(j, p, y, s, lengths) for j, p, y, s in zip(joints2d, ppu, yaw, signs)])
    poses[..., 2] = gaussian_filter1d(poses[..., 2], DEPTH_SMOOTH_S * fps, axis=0, mode="nearest")
    return poses


def first_guess(joints2d: np.ndarray, ppu: np.ndarray, yaw: np.ndarray, fps: float) -> tuple[np.ndarray, np.ndarray]:
    """(signs (F, 10), lengths (10,)) as resolve_inputs guesses them with no user input."""
    lengths = clip_lengths(joints2d, ppu, FIT_LENGTH_PERCENTILE, pool=True)
    judged = np.maximum(clip_lengths(joints2d, ppu), lengths)
    return guess_signs(joints2d, ppu, yaw, judged, fps=fps), lengths


def noise_row(truth: dict, percent: float, rng: np.random.Generator) -> dict:
    """PA-MPJPE (m), sign accuracy and solve time of the old and new lift at one noise level."""
    n, fps = len(truth["joints2d"]), truth["fps"]
    joints2d = truth["joints2d"] + rng.normal(0.0, percent / 100 * truth["body_px"], truth["joints2d"].shape)
    ppu, yaw = np.full(n, truth["body_px"] / BODY_HEIGHT), truth["yaw"]
    true_signs = signs_of(truth["joints3d"])
    out_of_plane = depth_fractions(truth["joints3d"]) > NEGLIGIBLE
    guess, lengths = first_guess(joints2d, ppu, yaw, fps)
    row = {}
    for mode, signs, held in (("oracle", true_signs, np.where(out_of_plane, true_signs, 0)), ("auto", guess, None)):
        old = old_lift(joints2d, ppu, yaw, signs, fps)
        new = lift_clip(ClipArrays(joints2d, ppu, yaw, signs, lengths, held=held, fps=fps))
        for name, poses in (("old", old), ("new", new.joints3d)):
            row[f"{mode} {name}"] = pa_mpjpe(poses, truth["joints3d"])
            row[f"{mode} {name} signs"] = float((signs_of(poses) == true_signs)[out_of_plane].mean())
        row[f"{mode} seconds"] = new.seconds
    return row


def bench_noise(seed: int, per_clip: bool) -> None:
    truths = dev_truths()
    if not truths:
        print(f"skipped: no development clips in {DEV_CLIPS}")
        return
    rng = np.random.default_rng(seed)
    rows = {p: [] for p in NOISE}
    for name, truth in truths:
        for p in NOISE:
            rows[p].append(noise_row(truth, p, rng))
        if per_clip:
            cells = " | ".join(
                f"{1000 * r['oracle old']:5.1f} {1000 * r['oracle new']:5.1f}" for r in (rows[p][-1] for p in NOISE)
            )
            print(f"{name:18s} oracle old/new by noise: {cells}", flush=True)
    print(f"PA-MPJPE in mm, mean over {len(truths)} development clips; signs right where |dZ| > {NEGLIGIBLE} length\n")
    print(
        f"{'2D noise':>9s} {'oracle signs: old':>17s} {'new':>6s} {'auto signs: old':>15s} {'new':>6s} "
        f"{'signs old':>9s} {'new':>6s} {'solve s':>8s}"
    )
    mean = {p: {k: np.mean([r[k] for r in rows[p]]) for k in rows[p][0]} for p in NOISE}
    for p in NOISE:
        m = mean[p]
        label = "exact" if p == 0 else f"{p:.0f} %"
        print(
            f"{label:>9s} {1000 * m['oracle old']:17.1f} {1000 * m['oracle new']:6.1f} {1000 * m['auto old']:15.1f} "
            f"{1000 * m['auto new']:6.1f} {100 * m['auto old signs']:8.1f}% {100 * m['auto new signs']:5.1f}% "
            f"{max(m['oracle seconds'], m['auto seconds']):8.2f}"
        )
    for mode in ("oracle", "auto"):
        ratio = mean[4.0][f"{mode} new"] / mean[0.0][f"{mode} new"]
        print(f"{mode} signs, new lift: 4 % noise / exact 2D = {ratio:.2f}")


PERSPECTIVE_NOISE = (0.0, 2.0, 4.0)  # % of the body's height, per coordinate
DEPTH_NOISE = 0.15  # of a segment's length: the person model's |dZ| error, about MediaPipe's


def perspective_truths() -> list[tuple[str, dict]]:
    """(name, truth) of the perspective development clips: joints2d, joints3d, yaw, body_px, the camera
    (Pinhole) and px_per_unit (F,) from the pelvis's true depth."""
    out = []
    for folder in sorted(DEV_CLIPS.glob("track_*")):
        doc = json.loads((folder / "truth.json").read_text())
        cam, frames = doc["camera"], doc["frames"]
        depth_m = np.abs([f["pelvis_cam"][2] for f in frames])
        truth = {
            "joints2d": np.array([f["joints2d"] for f in frames], float),
            "joints3d": np.array([f["joints3d"] for f in frames], float),
            "yaw": np.array([f["facing_deg"] for f in frames], float),
            "body_px": float(doc["body_height_px"]),
            "camera": Pinhole(cam["fx"], cam["cx"], cam["cy"]),
            "px_per_unit": cam["fx"] * UNIT_M / depth_m,
        }
        out.append((folder.name, truth))
    return out


def perspective_row(truth: dict, percent: float, rng: np.random.Generator) -> dict:
    """PA-MPJPE (mm) of the orthographic and the pinhole solve, with person-model depths."""
    joints2d = truth["joints2d"] + rng.normal(0.0, percent / 100 * truth["body_px"], truth["joints2d"].shape)
    ppu, yaw = truth["px_per_unit"], truth["yaw"]
    signs, lengths = first_guess(joints2d, ppu, yaw, 25.0)
    v = truth["joints3d"][:, SEGMENT_JOINTS[:, 1]] - truth["joints3d"][:, SEGMENT_JOINTS[:, 0]]
    share = np.abs(v[..., 2]) / np.linalg.norm(v, axis=-1)
    depths = np.clip(share + rng.normal(0.0, DEPTH_NOISE, share.shape), 0.0, 1.0) * lengths
    row = {}
    for name, camera in (("orthography", None), ("pinhole", truth["camera"])):
        clip = ClipArrays(joints2d, ppu, yaw, signs, lengths, depths=depths, fps=25.0, camera=camera)
        row[name] = 1000 * pa_mpjpe(lift_clip(clip).joints3d, truth["joints3d"])
    return row


def bench_perspective(seed: int) -> None:
    truths = perspective_truths()
    if not truths:
        print(f"skipped: no perspective development clips (track_*) in {DEV_CLIPS}")
        return
    rng = np.random.default_rng(seed)
    print("PA-MPJPE in mm: the clip solve through scaled orthography and through the camera's pinhole\n")
    print(f"{'clip':14s} {'2D noise':>8s} {'orthography':>12s} {'pinhole':>8s}")
    rows = []
    for name, truth in truths:
        for p in PERSPECTIVE_NOISE:
            rows.append(perspective_row(truth, p, rng))
            print(f"{name:14s} {p:7.0f}% {rows[-1]['orthography']:12.1f} {rows[-1]['pinhole']:8.1f}", flush=True)
    mean = {k: np.mean([r[k] for r in rows]) for k in rows[0]}
    print(f"{'mean':14s} {'':8s} {mean['orthography']:12.1f} {mean['pinhole']:8.1f}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=6.0, help="longest clip, seconds (default 6)")
    parser.add_argument("--noise", action="store_true", help="old and new lift against the 2D's noise")
    parser.add_argument("--per-clip", action="store_true", help="with --noise, each clip's oracle row too")
    parser.add_argument("--perspective", action="store_true", help="orthographic and pinhole solve, track clips")
    parser.add_argument("--seed", type=int, default=0, help="with --noise or --perspective, the noise's seed")
    args = parser.parse_args()
    if args.perspective:
        bench_perspective(args.seed)
        return 0
    if args.noise:
        bench_noise(args.seed, args.per_clip)
        return 0
    missing = [name for _, name in CLIPS if not (BVH / name).is_file()]
    if missing:
        print(f"skipped: {', '.join(missing)} absent from {BVH}")
        return 0
    rows, start = [], time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        for kind, name in CLIPS:
            for view in VIEWS:
                rows.append(
                    (f"{kind} {Path(name).stem[:8]} {view[:5]}", run_clip(BVH / name, view, args.seconds, Path(tmp)))
                )
    print_table(rows)
    print(f"\n{len(rows)} clips in {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
