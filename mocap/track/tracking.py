"""The tracking method (Pan, Zhuang and Liu, *Video motion capture in VBA*, 2000) as
one call: the user marks the 16 joints on frame 0; every frame is tracked
(mocap.track.tracker), stretches of low reliability are filled by interpolation, and the
3D skeleton is reconstructed under perspective (mocap.track.perspective) from the 2D
joints lightly smoothed in time (SMOOTH_S).

    result = track_video("clip.mp4", marks)        # marks: (16, 2) or {joint: (x, y)}
    result.joints2d, result.reliability, result.joints3d

Frames are streamed: only the current and the previous frame are in memory. Large
frames are tracked at video.processing_scale (1280 px on the longer side); results
are in the original frame's pixels.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d

from mocap.body import JOINT_INDEX, JOINT_PARENT, JOINTS, SIDES, knee_facing, limb
from mocap.errors import MocapError
from mocap.track.marks import check_marks
from mocap.track.calibration import Pinhole, default_camera
from mocap.track.keydepths import Turns
from mocap.track.perspective import reconstruct, steady_depths, to_contract
from mocap.track.parts import HEAD, LIMBS, PART_JOINTS, PARTS, TORSO
from mocap.track.loss import GAP_S, bridged, joint_confidence
from mocap.track.reseed import Track, track_seeded
from mocap.io.video import VideoInfo, iter_frames, open_video, processing_scale

Progress = Callable[[int, int], None]
LOW_RELIABILITY = 0.5      # a part matched this much worse than usual is taken as hidden
# seconds (Gaussian sigma) over which the 2D joints are smoothed for the 3D alone: a
# pixel of tracking jitter moves a joint on its ray by centimetres where its bone is
# nearly in the image plane (depth sqrt(l^2 - d^2) is steep there)
SMOOTH_S = 0.05
TURN_CUE_S = 1.0           # seconds from frame 0 whose knee bends tell an unsaid turn
# seconds over which a user's correction of a tracked joint fades out on the frames
# around it (spread_corrections): a tracker that is off on one frame was off the same
# way on the frames around it
SPREAD_S = 0.2
# an arm joint a correction also carries by its parent joint (spread_corrections)
CARRIED_BY = {JOINT_INDEX[joint]: JOINT_INDEX[JOINT_PARENT[joint]]
              for side in SIDES for joint in limb("arm", side).joints[1:]}


def _joint_parts() -> list[tuple[int, ...]]:
    """For every joint, the parts whose match placed it: the head's joints by the
    head, the trunk's (with shoulders and hips, carried by it) by the trunk, a limb's
    middle and end joints by both of its parts."""
    out = [(TORSO,)] * len(JOINTS)
    out[JOINT_INDEX["head_top"]] = out[JOINT_INDEX["neck"]] = (HEAD,)
    for k in LIMBS:
        out[PART_JOINTS[k, 1]] = out[PART_JOINTS[k + 1, 1]] = (k, k + 1)
    return out


JOINT_PARTS = _joint_parts()


@dataclass(frozen=True, eq=False)
class TrackResult:
    """What the tracking method found in a video.

    ``joints2d`` (F, 16, 2): pixels of the original frames, anatomical sides as
    marked, low-reliability stretches interpolated; ``reliability`` (F, 16) in
    [0, 1]: the similarity of the match that placed each joint over that part's
    median similarity in the clip (1 on the marked frame 0; below LOW_RELIABILITY the
    joint was interpolated where reliable frames surround it); ``joints3d``
    (F, 16, 3): metres, CONTRACT.md's frame; ``focal_px``: the focal length assumed;
    ``confidence`` (F, 16) in [0, 1]: whether each joint was still on the body
    (mocap.track.loss.joint_confidence); ``lost`` (F,) bool: the frames where the
    body was lost and could not be bridged (mocap.track.loss.bridged), whose joints
    are no answer.
    """

    info: VideoInfo
    joints2d: np.ndarray
    reliability: np.ndarray
    joints3d: np.ndarray
    focal_px: float
    confidence: np.ndarray
    lost: np.ndarray


def track_frames(frames: Iterable[np.ndarray], marks: np.ndarray,
                 progress: Callable[[int], None] | None = None, camera: Pinhole | None = None,
                 turn: str | None = None, fps: float = 25.0,
                 remarks: dict[int, np.ndarray] | None = None) -> Track:
    """Track checked ``marks`` (16, 2) of the first frame, and the body marked again
    on later frames (``remarks``, frame -> checked marks; mocap.track.reseed), through
    ``frames`` (BGR) seen by ``camera`` (default the frame's), the body turned to
    ``turn``: (F, 16, 2) joints, (F, 10) similarities S of the parts (inf on a
    marked frame), (F, 10) their confidence (mocap.track.loss; 1 on a marked frame)
    and (F,) whether the body was lost (mocap.track.loss.body_lost)."""
    return track_seeded(frames, {**(remarks or {}), 0: marks}, progress, camera, turn, fps)


def joint_reliability(similarity: np.ndarray) -> np.ndarray:
    """(F, 16) reliability of every joint from the parts' similarities (F, 10): each
    part's S over its median S in the clip, at most 1; a joint's is the least of its
    parts' (JOINT_PARTS)."""
    tracked = np.where(np.isfinite(similarity[1:]), similarity[1:], np.nan)   # marked frames aside
    usual = np.nanmedian(tracked, axis=0) if np.isfinite(tracked).any() else np.ones(len(PARTS))
    part = np.minimum(similarity / usual, 1.0)
    return np.stack([part[:, list(parts)].min(axis=1) for parts in JOINT_PARTS], axis=1)


def fill_unreliable(joints2d: np.ndarray, reliability: np.ndarray,
                    threshold: float = LOW_RELIABILITY) -> np.ndarray:
    """Joints (F, 16, 2) with every stretch of frames below ``threshold`` that lies
    between two reliable frames replaced by linear interpolation between them (the
    paper's handling of self-occlusion); stretches at the end of the clip stay."""
    out = joints2d.copy()
    frames = np.arange(len(joints2d))
    for j in range(joints2d.shape[1]):
        good = np.flatnonzero(reliability[:, j] >= threshold)
        bad = frames[(reliability[:, j] < threshold) & (frames > good[0]) & (frames < good[-1])]
        for c in range(2):
            out[bad, j, c] = np.interp(bad, good, joints2d[good, j, c])
    return out


def spread_corrections(joints2d: np.ndarray, corrections: dict[int, dict[str, tuple[float, float]]],
                       fps: float, spread_s: float = SPREAD_S) -> np.ndarray:
    """Tracked joints (F, 16, 2) with the user's ``corrections`` (frame -> {joint:
    (x, y)}, the annotations' joint overrides) put in: each correction wins on its own
    frame, and the frames around it move by its offset from the tracked joint
    (``faded_offsets`` over ``spread_s`` seconds); an elbow or a wrist is moreover
    carried there by its parent joint (``carried``).

    Beyond the paper: tracking errors last (a limb lost to clutter stays lost for a
    while), so a correction says how far off the tracker was on the frames around it
    too; a user who corrects one frame in ten then fixes most of a drift, not a tenth."""
    out = joints2d.copy()
    fade = spread_frames(fps, spread_s)
    # in joint order: a shoulder or elbow is spread before the joint it carries
    for j in sorted({JOINT_INDEX[name] for points in corrections.values() for name in points}):
        keys = sorted(f for f, points in corrections.items() if JOINTS[j] in points and f < len(out))
        pins = np.array([corrections[f][JOINTS[j]] for f in keys], float)
        offsets = pins - joints2d[keys, j]
        out[:, j] += faded_offsets(len(out), keys, list(offsets), fade)
        if j in CARRIED_BY:
            out[:, j] = carried(out, j, CARRIED_BY[j], keys, pins, offsets.any(axis=1), fade)
    return out


def carried(joints2d: np.ndarray, j: int, parent: int, keys: list[int], pins: np.ndarray,
            moved: np.ndarray, fade: int) -> np.ndarray:
    """(F, 2) joint ``j`` of ``joints2d`` (its pins' offsets spread) around its ``pins``
    (K, 2) on the frames ``keys`` carried by its ``parent`` joint: the pinned vector from
    the parent (interpolated between pins) added to the parent's place, weighted as
    the offsets of the pins that ``moved`` the joint fade (``faded_offsets``), the rest
    the joint as it was. A pin where the tracker already was (the marks on frame 0)
    carries nothing.

    Beyond the paper: an arm lost to clutter or hidden behind the trunk is not off by a
    steady offset but elsewhere, moving with the body; carried by its shoulder (an
    elbow) or its elbow (a wrist), the pinned arm follows the body. A simulated user
    who pins every joint more than 4% of body height off on one frame in ten
    (benchmarks/bench_track_budget.py): PA-MPJPE 59.8 -> 59.0 mm; the legs carried too
    (a knee by its hip, an ankle by its knee): 59.2."""
    frames = np.arange(len(joints2d))
    vectors = pins - joints2d[keys, parent]
    along = np.stack([np.interp(frames, keys, vectors[:, c]) for c in range(2)], axis=-1)
    weight = faded_offsets(len(joints2d), keys, [np.full(2, float(m)) for m in moved], fade)[:, :1]
    return weight * (joints2d[:, parent] + along) + (1.0 - weight) * joints2d[:, j]


def faded_offsets(n_frames: int, keys: list[int], offsets: list[np.ndarray], fade: int) -> np.ndarray:
    """(n_frames, 2) the ``offsets`` at the frames ``keys`` (sorted), changing linearly
    from one to the next where they are fewer than 2 ``fade`` frames apart, else fading
    linearly to zero ``fade`` frames away (so every frame moved is nearer than ``fade``
    to a key: carried_pins)."""
    at, values, zero = [], [], np.zeros(2)
    for n, (key, offset) in enumerate(zip(keys, offsets)):
        alone_before = n == 0 or key - keys[n - 1] >= 2 * fade
        alone_after = n == len(keys) - 1 or keys[n + 1] - key >= 2 * fade
        at += [key - fade] * alone_before + [key] + [key + fade] * alone_after
        values += [zero] * alone_before + [offset] + [zero] * alone_after
    values = np.array(values)
    frames = np.arange(n_frames)
    return np.stack([np.interp(frames, at, values[:, c], left=0.0, right=0.0) for c in range(2)], axis=-1)


def carried_pins(corrections: dict[int, dict[str, tuple[float, float]]], frame: int,
                 fps: float) -> dict[str, int]:
    """joint -> the frame of the nearest correction of it that moves it on ``frame``
    (spread_corrections) without being on that frame; frame 0's (the marks) aside."""
    fade = spread_frames(fps)
    out: dict[str, int] = {}
    for source in sorted(corrections, key=lambda f: abs(f - frame)):
        if source == 0 or not 0 < abs(source - frame) < fade:
            continue
        for joint in corrections[source]:
            if joint not in corrections.get(frame, {}):
                out.setdefault(joint, source)
    return out


def spread_frames(fps: float, spread_s: float = SPREAD_S) -> int:
    """The frames (at least 1) over which a correction fades out (spread_corrections)."""
    return max(1, int(round(spread_s * fps)))


def turn_of(orientation: str | None) -> str | None:
    """'left' or 'right' from a CONTRACT.md orientation (e.g. forward_right)."""
    if orientation is None:
        return None
    side = orientation.rsplit("_", 1)[-1]
    if side not in ("left", "right"):
        raise MocapError(f"unknown orientation {orientation!r}")
    return side


def track_video(video: str | os.PathLike | VideoInfo, marks, progress: Progress | None = None,
                *, focal_px: float | None = None, orientation: str | None = None,
                remarks: dict | None = None) -> TrackResult:
    """Track a video (a path or an opened one) from the 16 joints marked on its frame 0
    and reconstruct 3D.

    ``marks``: (16, 2) pixels in JOINTS order or a mapping joint -> (x, y) (frame 0's
    ``joints2d`` of an annotations file); bad marks raise a MocapError naming the
    joint. ``focal_px``: the camera's focal length in pixels if known (default: the
    frame width, see mocap.track.perspective). ``orientation``: the performer's orientation
    on frame 0 in CONTRACT.md's words; its side ("right" of forward_right) tells
    which way the body is turned, which the key triangle alone cannot (None: the
    knees tell, ``guessed_turn``). ``remarks``: frame -> the 16 joints marked
    again there (as ``marks``), each seeding the tracker anew (mocap.track.reseed).
    ``progress(done, total)`` is called after every frame of every pass.
    """
    info = video if isinstance(video, VideoInfo) else open_video(video)
    marks, scale = check_marks(marks, info.width, info.height), processing_scale(info)
    seeds = {f: (check_marks(m, info.width, info.height) + 0.5) * scale - 0.5
             for f, m in (remarks or {}).items() if 0 < f < info.frame_count}
    turn = turn_of(orientation)
    step = (lambda done: progress(done, info.frame_count + max(seeds, default=0))) if progress else None
    frames = (frame for _, frame in iter_frames(info, scale=scale))
    camera = default_camera(info.width, info.height, focal_px)
    joints, similarity, parts, lost = track_frames(frames, (marks + 0.5) * scale - 0.5, step,
                                                   camera.scaled(scale), turn, info.fps, seeds)
    joints = (joints + 0.5) / scale - 0.5
    reliability = joint_reliability(similarity)
    joints, lost = bridged(joints, lost, int(round(GAP_S * info.fps)))
    joints2d = fill_unreliable(joints, reliability)
    turn = turn or guessed_turn(joints2d, info.fps)
    joints3d = to_contract(steady_reconstruction(joints2d, camera, turn, info.fps, ~lost))
    return TrackResult(info, joints2d, reliability, joints3d, camera.focal, joint_confidence(parts), lost)


def guessed_turn(joints2d: np.ndarray, fps: float) -> str:
    """Which way the body is turned ("left" or "right", as the side of an orientation)
    where the user did not say: the way the knees bend over the first TURN_CUE_S
    (orientation.knee_facing). Beyond the paper: the key triangle and hips fit two
    mirror-image turns about equally well (mocap.track.calibration.calibrate)."""
    return knee_facing(joints2d[:max(1, int(round(TURN_CUE_S * fps)))])


def steady_reconstruction(joints2d: np.ndarray, camera: Pinhole, turns: Turns, fps: float,
                          seen: np.ndarray | None = None) -> np.ndarray:
    """(F, 16, 3) pinhole-frame joints (metres) of tracked 2D joints (F, 16, 2): the
    perspective reconstruction of the joints lightly smoothed (``steady_joints``), the
    trunk turned to ``turns`` (one side, or each frame's: keydepths.key_joints), the
    bones measured over the frames ``seen`` (default all: the body not lost),
    every joint's depth then smoothed along its ray (``steady_depths``)."""
    return steady_depths(reconstruct(steady_joints(joints2d, fps), camera, turns, seen=seen), fps)


def steady_joints(joints2d: np.ndarray, fps: float) -> np.ndarray:
    """The 2D joints (F, 16, 2) the 3D is reconstructed from: smoothed over SMOOTH_S."""
    return gaussian_filter1d(joints2d, SMOOTH_S * fps, axis=0, mode="nearest")
