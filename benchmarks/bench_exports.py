"""Root depth and foot contacts of the silhouette method on walks rendered with a
perspective camera from real motion capture (../shared/data/bvh/cmu_walk.bvh, 640x480,
30 fps), against their exact truth.

For each view it prints the correlation of the root's depth (-z of the motion file's
``root``) with the true pelvis depth, the depth range of both, and how often each
foot's contact flag agrees with the same rule (mocap.lift.contacts) applied to the
true ankles (the exports in Blender: tests/test_blender.py), and how far planted feet
slide: the largest distance between two places of an ankle in one contact, in the
motion as exported and foot-locked (``Motion.foot_locked``, ``--foot-lock``), with how
far the lock moved the body. ``--dev`` prints the slides on the static-camera
development clips of ../shared/data/clips instead (no user input, the person model as
`mocap fit` has it), with how often the contacts agree with the truth's: the same rule on
the clip's motion capture (its BVH window, the speed in depth counted too: the capture
knows it), none for a treadmill render, whose feet the video shows gliding.

    python benchmarks/bench_exports.py [--focal 500] [--dev]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

from mocap.body import JOINT_INDEX
from mocap.cli import main as mocap
from mocap.io.bvh_reader import contract_joints, read_bvh
from mocap.lift.contacts import FEET, foot_contacts
from mocap.pipeline import open_session, person_model
from mocap.synth.truth import load_truth

CMU_WALK = Path(__file__).resolve().parents[2] / "shared" / "data" / "bvh" / "cmu_walk.bvh"
DEV_CLIPS = CMU_WALK.parents[1] / "clips"
# camera yaw from the performer's right side: 45 = walks toward the camera at 45 degrees
VIEWS = {"side (depth constant)": 0.0, "toward, 45 degrees": 45.0, "toward, 60 degrees": 60.0}


def measure(folder: Path, yaw: float, focal: float) -> dict:
    """Render, fit and compare one view."""
    video = folder / f"walk{int(yaw)}.mp4"
    motion = folder / f"walk{int(yaw)}.motion.json"
    assert mocap(["synth", str(CMU_WALK), str(video), "--yaw", str(yaw), "--perspective", str(focal)]) == 0
    assert mocap(["fit", str(video), "--quiet", "--out", str(motion)]) == 0
    truth = load_truth(video.with_suffix(".truth.json"))
    frames = json.loads(motion.read_text())["frames"]
    have = np.array(["root" in f for f in frames])
    depth = np.array([-f["root"][2] if "root" in f else np.nan for f in frames])
    true_depth = -truth.pelvis_camera[:, 2]
    contacts = np.array(
        [[f["contacts"][a] for a in ("ankle_l", "ankle_r")] if "contacts" in f else [False, False] for f in frames]
    )
    true_contacts = foot_contacts(truth.joints3d + truth.pelvis_camera[:, None], truth.fps)
    return {
        "frames": len(frames),
        "with root": int(have.sum()),
        "corr": float(np.corrcoef(depth[have], true_depth[have])[0, 1]),
        "depth": (np.nanmin(depth), np.nanmax(depth)),
        "true": (true_depth.min(), true_depth.max()),
        "agree": (contacts[have] == true_contacts[have]).mean(axis=0),
    }


def slides(motion, contacts: np.ndarray) -> np.ndarray:
    """Metres: per contact of ``contacts`` (F, 2), the largest distance between two places of its ankle."""
    out = []
    for k, foot in enumerate(FEET):
        ankle = motion.world_joints[:, JOINT_INDEX[foot]]
        edges = np.diff(np.concatenate([[0], contacts[:, k].astype(int), [0]]))
        for start, stop in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
            at = ankle[start:stop]
            out.append(np.linalg.norm(at[:, None] - at[None], axis=-1).max())
    return np.array(out)


def capture_contacts(folder: Path) -> np.ndarray | None:
    """(F, 2) a development clip's true contacts: ``foot_contacts`` with depth on its BVH window (truth.json's
    source) at the clip's frame rate; None for a treadmill render or where the BVH is absent."""
    truth = json.loads((folder / "truth.json").read_text())
    source, video = truth["source"], truth["video"]
    bvh = CMU_WALK.parent / source["bvh"]
    if truth["camera"].get("treadmill") or not bvh.is_file():
        return None
    capture = read_bvh(bvh)
    frames = np.round((source["start_s"] + np.arange(video["frame_count"]) / video["fps"]) * source["bvh_fps"])
    world = contract_joints(capture)[np.clip(frames.astype(int), 0, capture.n_frames - 1)]
    return foot_contacts(world, video["fps"], depth=True)


def slide_row(video: Path, truth: np.ndarray | None = None) -> str:
    """Contacts (with ``truth`` (F, 2): the truth's share and the agreement), the exported and the locked
    motion's largest and median slide (cm), the body's shift."""
    motion = open_session(video, person=person_model(None)).motion()
    locked = motion.foot_locked()
    free, held = slides(motion, motion.contacts), slides(locked, locked.contacts)
    shift = np.linalg.norm(locked.root - motion.root, axis=-1)
    known = "" if truth is None else f"{truth.mean():>6.2f} {(motion.contacts == truth).mean():>6.2f} "
    if not len(free):
        return f"{known}{motion.contacts.mean():>8.2f} {0:>5}"
    return (
        f"{known}{motion.contacts.mean():>8.2f} {len(free):>5} {100 * free.max():>7.1f} {100 * np.median(free):>6.1f} "
        f"{100 * held.max():>7.1f} {100 * np.median(held):>6.1f} {100 * shift.max():>9.1f}"
    )


SLIDE_HEAD = (
    f"{'planted':>8} {'runs':>5} {'slide max':>9} {'median':>6} {'locked max':>10} {'median':>6} {'shift max':>9}"
)
TRUTH_HEAD = f"{'true':>6} {'agree':>6} "


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--focal", type=float, default=500.0, help="the render's focal length (px)")
    parser.add_argument("--dev", action="store_true", help="the slides on the development clips")
    args = parser.parse_args()
    if args.dev:
        print(f"{'clip':18} {TRUTH_HEAD}{SLIDE_HEAD}   (cm)")
        for folder in sorted(DEV_CLIPS.iterdir()):
            if (folder / "truth.json").is_file() and not folder.name.startswith("track_"):
                truth = capture_contacts(folder)
                known = f"{'-':>6} {'-':>6} " if truth is None else ""
                print(f"{folder.name:18} {known}{slide_row(folder / 'video.mp4', truth)}", flush=True)
        return 0
    if not CMU_WALK.exists():
        print(f"{CMU_WALK} absent", file=sys.stderr)
        return 1
    print(f"{'view':24} {'frames':>6} {'depth r':>8} {'depth (m)':>12} {'true (m)':>12} {'contacts L/R agree':>19}")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, yaw in VIEWS.items():
            r = measure(Path(tmp), yaw, args.focal)
            print(
                f"{name:24} {r['frames']:>6} {r['corr']:>8.3f} "
                f"{r['depth'][0]:>5.2f}-{r['depth'][1]:<5.2f}  {r['true'][0]:>5.2f}-{r['true'][1]:<5.2f} "
                f"{100 * r['agree'][0]:>8.1f}% {100 * r['agree'][1]:>6.1f}%"
            )
            rows.append((name, slide_row(Path(tmp) / f"walk{int(yaw)}.mp4")))
    print(f"\n{'view':24} {SLIDE_HEAD}   (cm)")
    for name, row in rows:
        print(f"{name:24} {row}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
