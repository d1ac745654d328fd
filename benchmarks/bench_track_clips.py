"""The tracking method on the perspective development clips, scored by the shared scorer.

Clips: the perspective clips of ../shared/data/clips (track_salsa, track_walk: real
motion capture over a panning background, frame 0 marked from the truth in their
oracle_track.json), and clips rendered here with `mocap synth` from the real motion
capture of ../shared/data/bvh where the body is hard to keep: laugh_arms_up (CMU
13_14, the arms thrown over the head, bending and turning) and salsa_spin (CMU 60_05,
a full spin), perspective camera, moving background, frame 0 marked from the truth.

Each clip runs `mocap fit --method track VIDEO --annotations MARKS` in-process
(mocap.pipeline.fit_video_to_file), looking through the person model (--person-model,
default mediapipe; none: the colours alone), and is scored with ../shared/bench/score.py.
``--proposed`` leaves frame 0's joints out of the marks (its orientation kept): the person
model proposes them (`mocap fit --method track VIDEO` without marks), each row followed by its
2D mean error and PA-MPJPE over those from the truth's marks, run too. A
frame the tracker marks as lost carries no joints and counts there as a failure
(the "failed" column); the 2D errors (% of body height) and PA-MPJPE (mm) are over
the frames answered. "lost" counts the frames the motion file marks lost. "exact 2D"
is the PA-MPJPE of the same 3D reconstruction (mocap.session.TrackSession, with the
marks file's orientation and foreshortening, and the person model's facing, which
releases a held orientation) from the truth's 2D joints on every frame: what the 3D step
costs alone, the rest of "PA-MPJPE mm" is what the 2D
tracking's errors cost. ``--joints`` adds each joint's PA-MPJPE from the tracked and
from the exact 2D: which joints carry the 3D step's error and which the tracking's.
``--mark-noise PCT`` moves each of frame 0's marks by Gaussian noise of PCT % of the body's
height per coordinate, as a user's clicks place them (1 % is 2.5 px on the shared clips), over
``--seeds`` draws per clip, each a row, then their mean: the truth's exact marks are a user's best
case.

    python benchmarks/bench_track_clips.py [--clips track_salsa laugh_arms_up] [--keep DIR] [--joints]
        [--person-model none] [--proposed | --mark-noise PCT [--seeds N]]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
sys.path.insert(0, str(ROOT.parent / "shared" / "bench"))

import contract  # noqa: E402
from score import score  # noqa: E402

from mocap.body import JOINTS  # noqa: E402
from mocap.camera import default_camera  # noqa: E402
from mocap.errors import MocapError  # noqa: E402
from mocap.io.annotations import load_annotations  # noqa: E402
from mocap.io.video import iter_frames, open_video, processing_scale  # noqa: E402
from mocap.lift.taylor import orientation_of_yaw, yaw_of  # noqa: E402
from mocap.person import open_person_model  # noqa: E402
from mocap.pipeline import fit_video_to_file  # noqa: E402
from mocap.session.tracking import TrackSession  # noqa: E402
from mocap.synth import RenderOptions, render_motion  # noqa: E402
from mocap.synth.metrics import procrustes_aligned  # noqa: E402
from mocap.track.landmarks import facing_yaw  # noqa: E402
from mocap.track.tracking import TrackResult  # noqa: E402

SHARED = ("track_salsa", "track_walk")
# name: (BVH, source frames A:B, render yaw, seed)
RENDERED = {
    "laugh_arms_up": ("cmu_13_14_laugh.bvh", (1080, 1560), 30.0, 7),
    "salsa_spin": ("cmu_60_05_salsa.bvh", (600, 840), 90.0, 11),
}
SIZE, FOCAL = (480, 360), 600.0
# the joints' names in five characters: head_top -> head, shoulder_l -> shoL
SHORT = tuple(j[:3] + j[-1].upper() if j[-2] == "_" else j.split("_")[0][:5] for j in JOINTS)


def scored_truth(truth: dict) -> dict:
    """A `mocap synth` truth with the fields score.py reads (each segment's
    foreshortening and |dz|/length from the true 3D, contract.signs)."""
    toward, ratio = contract.signs(np.array([f["joints3d"] for f in truth["frames"]]))
    for f, t, r in zip(truth["frames"], toward, ratio):
        f["foreshortening"] = {s: ("toward" if x else "away") for s, x in zip(contract.SEGMENTS, t)}
        f["foreshortening_ratio"] = dict(zip(contract.SEGMENTS, r.tolist()))
    return truth


def render(name: str, folder: Path) -> tuple[Path, Path, Path]:
    """Render a clip of RENDERED into ``folder``: (video, truth, frame-0 marks)."""
    bvh, frames, yaw, seed = RENDERED[name]
    video, truth_path = folder / f"{name}.mp4", folder / f"{name}.truth.json"
    if not video.exists():
        opts = RenderOptions(yaw=yaw, size=SIZE, fps=25.0, perspective=FOCAL, moving_background=True, seed=seed)
        render_motion(DATA / "bvh" / bvh, video, opts, frames=frames, truth_path=truth_path)
    truth = scored_truth(json.loads(truth_path.read_text()))
    truth_path.write_text(json.dumps(truth))
    first = truth["frames"][0]
    marks = {
        "format": "mocap-annotations",
        "version": 1,
        "frames": {
            "0": {
                "orientation": orientation_of_yaw(yaw_of(np.array(first["joints3d"]))),
                "joints2d": dict(zip(JOINTS, first["joints2d"])),
            }
        },
    }
    marks_path = folder / f"{name}.marks.json"
    marks_path.write_text(json.dumps(marks))
    return video, truth_path, marks_path


def clip_files(name: str, folder: Path) -> tuple[Path, Path, Path]:
    """(video, truth, marks) of a shared clip or a rendered one."""
    if name in SHARED:
        base = DATA / "clips" / name
        return base / "video.mp4", base / "truth.json", base / "oracle_track.json"
    return render(name, folder)


def person_facing(info, person: str) -> np.ndarray:
    """(F,) the ``person`` model's facing yaw on every frame, as the tracking takes it (landmarks.facing_yaw)."""
    model = open_person_model(person)
    if model is None:
        return np.full(info.frame_count, np.nan)
    try:
        views = [model.observe(frame) for _, frame in iter_frames(info, scale=processing_scale(info))]
    finally:
        model.close()
    return np.array([facing_yaw(None if view is None else view.landmarks) for view in views])


def exact_2d_pa_mpjpe(video: Path, truth: Path, marks: Path, person: str) -> np.ndarray:
    """(16,) each joint's PA-MPJPE (mm) of the tracking method's 3D from the truth's 2D
    joints on every frame, with the annotations of ``marks`` and the ``person`` model's facing."""
    info = open_video(video)
    frames = json.loads(truth.read_text())["frames"]
    joints2d = np.array([f["joints2d"] for f in frames])
    ones = np.ones(joints2d.shape[:2])
    tracked = TrackResult(
        info,
        joints2d,
        ones,
        np.zeros((*joints2d.shape[:2], 3)),
        default_camera(info.width, info.height).focal,
        ones,
        np.zeros(len(frames), bool),
        person_facing(info, person),
    )
    session = TrackSession(info, tracked, load_annotations(marks, info.frame_count))
    joints3d = np.array([session.pose3d(f) for f in range(len(frames))])
    truth3d = np.array([f["joints3d"] for f in frames])
    aligned = np.array([procrustes_aligned(p, t) for p, t in zip(joints3d, truth3d)])
    return np.linalg.norm(aligned - truth3d, axis=-1).mean(axis=0) * 1000


def unmarked(marks: Path, folder: Path) -> Path:
    """A copy of the marks file in ``folder`` without frame 0's joints (its orientation kept): the person model's."""
    notes = json.loads(marks.read_text())
    notes["frames"]["0"].pop("joints2d")
    out = folder / f"{marks.parent.name}.{marks.stem}.unmarked.json"
    out.write_text(json.dumps(notes))
    return out


def noisy(marks: Path, folder: Path, body_px: float, percent: float, seed: int) -> Path:
    """A copy of the marks file in ``folder`` with frame 0's joints moved by Gaussian noise of ``percent`` % of
    ``body_px`` per coordinate (draw ``seed``)."""
    notes = json.loads(marks.read_text())
    rng = np.random.default_rng(seed)
    joints = notes["frames"]["0"]["joints2d"]
    for joint in JOINTS:
        joints[joint] = (np.asarray(joints[joint], float) + rng.normal(0.0, percent / 100 * body_px, 2)).tolist()
    out = folder / f"{marks.parent.name}.{marks.stem}.noisy{seed}.json"
    out.write_text(json.dumps(notes))
    return out


def run(name: str, folder: Path, person: str, proposed: bool, noise: tuple[float, int] | None = None) -> dict:
    """Track and score one clip looking through the ``person`` model, frame 0 marked by it if ``proposed``, or
    the truth's marks moved by ``noise`` (percent of the body's height, seed: ``noisy``)."""
    video, truth, marks = clip_files(name, folder)
    out = folder / f"{name}.track.json"
    start = time.perf_counter()
    notes = unmarked(marks, folder) if proposed else marks
    if noise is not None:
        notes = noisy(marks, folder, json.loads(truth.read_text())["body_height_px"], *noise)
    fit_video_to_file(video, {"json": out}, annotations=notes, method="track", person=person)
    seconds = time.perf_counter() - start
    result = score(out, truth)
    frames = json.loads(out.read_text())["frames"]
    result["lost"] = sum(bool(f.get("lost")) for f in frames)
    result["seconds"] = seconds
    result["exact"] = exact_2d_pa_mpjpe(video, truth, marks, person)
    return result


def print_joints(result: dict) -> None:
    """Each joint's PA-MPJPE (mm) of a clip's ``run`` from the tracked and the exact 2D."""
    print("  " + " ".join(f"{short:>5s}" for short in SHORT) + "  (joint PA-MPJPE mm)")
    tracked = [result["per_joint"][joint]["pampjpe_mm"] for joint in JOINTS]
    for label, values in (("tracked", tracked), ("exact 2D", result["exact"])):
        print("  " + " ".join(f"{v:>5.0f}" for v in values) + f"  {label}")


ROW_KEYS = ("frames", "failed", "lost", "err2d_median_pct", "err2d_mean_pct", "pampjpe_mm", "exact", "seconds")


def print_row(label: str, r: dict) -> None:
    """One clip's (or its draws' mean) row of the table."""
    print(
        f"{label:<15} {r['frames']:>6.0f} {r['failed']:>6.0f} {r['lost']:>5.0f} {r['err2d_median_pct']:>8.2f} "
        f"{r['err2d_mean_pct']:>9.2f} {r['pampjpe_mm']:>11.1f} {np.mean(r['exact']):>8.1f} {r['seconds']:>5.0f}",
        flush=True,
    )


def print_over_exact(proposed: dict, exact: dict) -> None:
    """A clip's 2D mean error and PA-MPJPE from the person model's marks over those from the truth's."""
    print(
        f"  over the truth's marks ({exact['err2d_mean_pct']:.2f} %, {exact['pampjpe_mm']:.1f} mm): "
        f"2D mean x{proposed['err2d_mean_pct'] / exact['err2d_mean_pct']:.2f}, "
        f"PA-MPJPE x{proposed['pampjpe_mm'] / exact['pampjpe_mm']:.2f}",
        flush=True,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clips", nargs="+", default=[*SHARED, *RENDERED])
    parser.add_argument("--keep", type=Path, help="folder for the renders and motion files")
    parser.add_argument(
        "--joints", action="store_true", help="each joint's PA-MPJPE from the tracked and from the exact 2D"
    )
    parser.add_argument("--person-model", default="mediapipe", help="the person model looked through (none: colours)")
    marks = parser.add_mutually_exclusive_group()
    marks.add_argument(
        "--proposed", action="store_true", help="frame 0 marked by the person model instead of the truth"
    )
    marks.add_argument("--mark-noise", type=float, metavar="PCT", help="the truth's marks moved by this noise")
    parser.add_argument("--seeds", type=int, default=4, help="draws of --mark-noise per clip (default 4)")
    args = parser.parse_args()
    draws = [None] if args.mark_noise is None else [(args.mark_noise, seed) for seed in range(args.seeds)]
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.keep or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        print(
            f"{'clip':<15} {'frames':>6} {'failed':>6} {'lost':>5} {'2D med %':>8} {'2D mean %':>9} "
            f"{'PA-MPJPE mm':>11} {'exact 2D':>8} {'s':>5}"
        )
        for name in args.clips:
            rows = []
            for noise in draws:
                label = name if noise is None else f"{name}#{noise[1]}"
                try:
                    r = run(name, folder, args.person_model, args.proposed, noise)
                except MocapError as error:
                    print(f"{label:<15} failed: {error}", flush=True)
                    continue
                rows.append(r)
                print_row(label, r)
                if args.proposed:
                    print_over_exact(r, run(name, folder, args.person_model, False))
                if args.joints:
                    print_joints(r)
            if len(draws) > 1 and rows:
                print_row(f"{name} mean", {key: np.mean([r[key] for r in rows], axis=0) for key in ROW_KEYS})


if __name__ == "__main__":
    main()
