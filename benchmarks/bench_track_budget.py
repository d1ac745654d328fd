"""Where the tracking method's 3D error comes from: PA-MPJPE (mm) of bench_track's
clips with parts of the tracked input replaced by the truth.

Every row runs the 3D of mocap.track.tracking (mocap.track.tracking.steady_reconstruction) on 2D
joints of the bench_track clips (real motion capture rendered with a pinhole camera
over a panning, cluttered background; the tracker given the true joints of frame 0):

- tracked: the tracked 2D joints, as ``mocap fit --method track`` reconstructs them;
- exact 2D: the true 2D joints (the 3D stage's own floor);
- tracked rays, exact depths: each tracked joint at the depth the exact 2D gives it
  (what the 2D errors cost across the image); exact rays, tracked depths: the other
  way round (what they cost in depth);
- far arm / far leg exact: the elbow and wrist (knee and ankle) of the side farther
  from the camera on each frame replaced by the truth;
- limbs exact where > x%: every elbow, wrist, knee and ankle tracked more than x% of
  body height off replaced by the truth on those frames (the gross failures);
- pins 1 frame in 10: a simulated user who visits every REVIEW_EVERY-th
  frame and puts every joint more than GROSS[-1]% off where it really is (joint
  overrides), on that frame only, then as the app applies them, carried to the frames
  around it (mocap.track.tracking.spread_corrections); pins on the review's stops: the same
  user visiting the app's review stops instead (the middle frame of every 0.4 s
  stretch, most doubtful first, at most as many as one frame in 10); on its far arm
  only: the same user correcting only the elbow and wrist of the arm the review says
  to check first (mocap.session.TrackSession.far_arm);
- facing said 1 in 10: the same visits, the user saying on each the side the
  performer really faces (an orientation entry, held until the next), with the exact
  and with the tracked 2D.

A second table counts the far wrist's gross failures (more than GROSS[0]% off) by
where the tracker put it: on the near forearm (within its width of the near arm's
true forearm), on the trunk (within its half width of the true neck-pelvis line) or
elsewhere, and how many of them have the true far wrist on the trunk (hidden behind
it or crossing in front).

    python benchmarks/bench_track_budget.py [--quick] [--yaws 60 120]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from bench_track import DATA, FOCAL, bench_main, orientation_of

from mocap.body import BODY_HEIGHT, JOINT_INDEX, JOINTS, SEGMENT_INDEX, WIDTH
from mocap.camera import default_camera
from mocap.io.annotations import Annotations
from mocap.session import TrackSession
from mocap.session.review import covering, review_queue
from mocap.synth import render_motion
from mocap.synth.metrics import pa_mpjpe
from mocap.synth.truth import Truth
from mocap.track.perspective import to_contract
from mocap.track.tracking import SPREAD_S, TrackResult, spread_corrections, steady_reconstruction, track_clip, turn_of

LIMB_JOINTS = {
    (side, kind): [JOINT_INDEX[f"{a}_{side}"], JOINT_INDEX[f"{b}_{side}"]]
    for side in "lr"
    for kind, a, b in (("arm", "elbow", "wrist"), ("leg", "knee", "ankle"))
}
GROSS = (8.0, 4.0)  # % of body height: limb joints off by more are "gross failures"
REVIEW_EVERY = 10  # frames: the simulated user corrects one frame in this many


def far_side(joints3d: np.ndarray) -> np.ndarray:
    """(F,) "l" or "r": the side whose shoulder and hip are farther from the camera
    (contract frame: z toward the camera)."""
    j = JOINT_INDEX
    left = joints3d[:, [j["shoulder_l"], j["hip_l"]], 2].mean(axis=1)
    right = joints3d[:, [j["shoulder_r"], j["hip_r"]], 2].mean(axis=1)
    return np.where(left < right, "l", "r")


def segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(F,) distance of each point (F, 2) to the segment from a to b (each (F, 2))."""
    ab = b - a
    t = np.clip(((points - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-9), 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * ab), axis=-1)


def far_wrist_failures(tracked: np.ndarray, truth: Truth) -> dict[str, int]:
    """The far wrist's gross failures (frames more than GROSS[0]% off) by where the
    tracker put it, and those with the true wrist on the trunk (the second table)."""
    j, t, px = JOINT_INDEX, truth.joints2d, truth.body_height_px / BODY_HEIGHT
    frames = np.arange(len(t))
    far = far_side(truth.joints3d)
    near = np.where(far == "l", "r", "l")
    wrist = np.array([j[f"wrist_{s}"] for s in far])
    near_arm = np.array([[j[f"elbow_{s}"], j[f"wrist_{s}"]] for s in near])
    placed, true = tracked[frames, wrist], t[frames, wrist]
    gross = np.linalg.norm(placed - true, axis=-1) > GROSS[0] / 100 * truth.body_height_px
    trunk_reach = WIDTH[SEGMENT_INDEX["torso"]] / 2 * px

    def on_trunk(points: np.ndarray) -> np.ndarray:
        return segment_distance(points, t[:, j["neck"]], t[:, j["pelvis"]]) < trunk_reach

    twin = segment_distance(placed, t[frames, near_arm[:, 0]], t[frames, near_arm[:, 1]]) < (
        WIDTH[SEGMENT_INDEX["lower_arm_l"]] * px
    )
    trunk = on_trunk(placed) & ~twin
    return {
        f"far wrist > {GROSS[0]:g}% off": int(gross.sum()),
        "... on the near forearm": int((gross & twin).sum()),
        "... on the trunk": int((gross & trunk).sum()),
        "... elsewhere": int((gross & ~twin & ~trunk).sum()),
        "... truly on the trunk": int((gross & on_trunk(true)).sum()),
    }


def with_far(tracked: np.ndarray, truth: Truth, kind: str) -> np.ndarray:
    """The tracked joints with the far side's arm or leg (``kind``) from the truth."""
    out = tracked.copy()
    for f, side in enumerate(far_side(truth.joints3d)):
        joints = LIMB_JOINTS[side, kind]
        out[f, joints] = truth.joints2d[f, joints]
    return out


def with_gross_fixed(tracked: np.ndarray, truth: Truth, percent: float) -> np.ndarray:
    """The tracked joints with every limb joint more than ``percent`` of body height off
    replaced by the truth."""
    limbs = np.concatenate(list(LIMB_JOINTS.values()))
    err = np.linalg.norm(tracked - truth.joints2d, axis=-1) / truth.body_height_px * 100
    gross = np.zeros(err.shape, bool)
    gross[:, limbs] = err[:, limbs] > percent
    return np.where(gross[..., None], truth.joints2d, tracked)


def user_corrections(
    tracked: np.ndarray, truth: Truth, visits, joints: list[int] | None = None
) -> dict[int, dict[str, tuple]]:
    """Joint overrides of a user who corrects, on each frame of ``visits``, every joint
    (of ``joints``, default all) more than GROSS[-1]% of body height off."""
    err = np.linalg.norm(tracked - truth.joints2d, axis=-1) / truth.body_height_px * 100
    looked = range(len(JOINTS)) if joints is None else joints
    return {f: {JOINTS[j]: tuple(truth.joints2d[f, j]) for j in looked if err[f, j] > GROSS[-1]} for f in visits}


def review_plan(result: TrackResult, orientation: str) -> tuple[list[int], str | None]:
    """The frames the app's review visits for this tracking, most doubtful first
    (app.state.AppState.review_stops), at most one in REVIEW_EVERY; and the far arm
    it says to check first (TrackSession.far_arm)."""
    notes = Annotations().with_method("track").with_orientation(0, orientation)
    session = TrackSession(result.info, result, notes)
    stops = covering(review_queue(session), len(result.joints2d), session.review_spacing)
    return [d.frame for d in stops][: len(result.joints2d) // REVIEW_EVERY], session.far_arm()


def said_turns(truth: Truth) -> list[str]:
    """Each frame's side of the orientation a user says on every REVIEW_EVERY-th frame."""
    visited = np.arange(len(truth.joints3d)) // REVIEW_EVERY * REVIEW_EVERY
    return [turn_of(orientation_of(truth.joints3d[f])) for f in visited]


def budget(tracked: np.ndarray, truth: Truth, turn: str, stops: list[int], far: str | None) -> dict[str, float]:
    """PA-MPJPE (mm) of every row of the table for one clip; ``stops`` and ``far``: the
    review's stops and the arm it says to check first."""
    camera = default_camera(truth.width, truth.height)

    def pinhole(joints2d: np.ndarray, turns=turn) -> np.ndarray:
        return steady_reconstruction(joints2d, camera, turns, truth.fps)

    mine, exact = pinhole(tracked), pinhole(truth.joints2d)
    rows = {
        "tracked": mine,
        "exact 2D": exact,
        "tracked rays, exact depths": mine * (exact[..., 2] / mine[..., 2])[..., None],
        "exact rays, tracked depths": exact * (mine[..., 2] / exact[..., 2])[..., None],
        "far arm exact": pinhole(with_far(tracked, truth, "arm")),
        "far leg exact": pinhole(with_far(tracked, truth, "leg")),
        **{f"limbs exact where > {p:g}%": pinhole(with_gross_fixed(tracked, truth, p)) for p in GROSS},
        **{
            f"pins 1 frame in {REVIEW_EVERY}, {name}": pinhole(
                spread_corrections(
                    tracked, user_corrections(tracked, truth, range(0, len(tracked), REVIEW_EVERY)), truth.fps, spread_s
                )
            )
            for name, spread_s in (("own frame", 0.0), ("spread", SPREAD_S))
        },
        "pins on the review's stops": pinhole(
            spread_corrections(tracked, user_corrections(tracked, truth, stops), truth.fps)
        ),
        "... on its far arm only": pinhole(
            spread_corrections(
                tracked, user_corrections(tracked, truth, stops, LIMB_JOINTS[far, "arm"] if far else []), truth.fps
            )
        ),
        **{
            f"facing said 1 in {REVIEW_EVERY}, {name}": pinhole(joints2d, said_turns(truth))
            for name, joints2d in (("exact 2D", truth.joints2d), ("tracked", tracked))
        },
    }
    return {name: pa_mpjpe(to_contract(points), truth.joints3d) * 1000 for name, points in rows.items()}


def run_clip(bvh: str, frames, fps: float, yaw: float, tmp: Path) -> tuple[str, dict[str, float]]:
    video = tmp / f"{Path(bvh).stem}_{yaw:.0f}.mp4"
    truth = render_motion(DATA / bvh, video, frames=frames, fps=fps, yaw=yaw, perspective=FOCAL, moving_background=True)
    orientation = orientation_of(truth.joints3d[0])
    result = track_clip(video, truth.joints2d[0], orientation=orientation)
    name = Path(bvh).stem.replace("cmu_01_01_", "cmu_")
    stops, far = review_plan(result, orientation)
    return f"{name} {yaw:.0f}", (
        budget(result.joints2d, truth, turn_of(orientation), stops, far),
        far_wrist_failures(result.joints2d, truth),
    )


def print_rows(columns: list[tuple[str, dict]], title: str, total: str, summary) -> None:
    """One table: a column per clip, a row per key of its dict, the ``total`` column
    ``summary(values)`` (a string) of the row's values."""
    print(f"{title:30s} " + " ".join(f"{name[:13]:>13s}" for name, _ in columns) + f" {total:>6s}")
    for row in columns[0][1]:
        values = [table[row] for _, table in columns]
        print(f"{row:30s} " + " ".join(f"{v:13.0f}" for v in values) + f" {summary(values):>6s}")


def print_table(columns: list[tuple[str, tuple[dict[str, float], dict[str, int]]]]) -> None:
    print_rows(
        [(name, pa) for name, (pa, _) in columns], "PA-MPJPE mm", "mean", lambda values: f"{np.mean(values):.1f}"
    )
    print("target: PA-MPJPE <= 60 mm from the tracked 2D\n")
    print_rows(
        [(name, failures) for name, (_, failures) in columns], "frames", "all", lambda values: f"{np.sum(values):d}"
    )


if __name__ == "__main__":
    sys.exit(bench_main(__doc__, run_clip, print_table))
