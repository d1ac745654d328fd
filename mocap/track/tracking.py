"""The tracking method (Pan, Zhuang and Liu 2000) as one call: frame 0 marked, every frame tracked, unreliable
stretches interpolated, 3D reconstructed under perspective. Frames are streamed at video.processing_scale; results
are in the original frame's pixels. ``track_clip("clip.mp4", marks)`` with marks (16, 2) or {joint: (x, y)}; with a
person model (mocap.person) its landmarks propose the marks, seed a lost body anew and guide the limbs."""

from __future__ import annotations

import itertools
import os
import warnings
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d, percentile_filter

from mocap.body import JOINT_INDEX, JOINT_PARENT, JOINTS, SIDES, STANDING_PERCENTILE, knee_facing, limb
from mocap.camera import Pinhole, default_camera
from mocap.errors import MocapError
from mocap.io.video import VideoInfo, iter_frames, open_video, processing_scale, rescaled
from mocap.person import SURE, Landmarks, PersonModel, PersonView, watched
from mocap.track.keydepths import Turns
from mocap.track.loss import GAP_S, bridged, joint_confidence
from mocap.track.marks import check_marks
from mocap.track.parts import HEAD, LIMBS, PART_JOINTS, PARTS, TORSO
from mocap.track.perspective import reconstruct, steady_depths, to_contract
from mocap.track.reseed import Track, track_seeded

Progress = Callable[[int, int], None]
LOW_RELIABILITY = 0.5  # a part matched this much worse than usual is taken as hidden
# seconds (Gaussian sigma) the 2D joints are smoothed over for the 3D alone: depth sqrt(l^2 - d^2) is steep
# near the image plane, so jitter moves joints along rays
SMOOTH_S = 0.05
# of the body's standing height: a landmark this near a tracked joint reads the same joint (averaged_with_landmarks)
AGREE_SHARE = 0.1
AGREE_BODY = 0.05  # ... and a frame's landmarks this near (median) read the tracked body
STANDING_S = 1.0  # seconds of head-to-ankle heights whose STANDING_PERCENTILE is a frame's standing height
TURN_CUE_S = 1.0  # seconds from frame 0 whose knee bends tell an unsaid turn
# seconds over which a user's correction fades out on the frames around it (spread_corrections)
SPREAD_S = 0.2
# an arm joint a correction also carries by its parent joint (spread_corrections)
CARRIED_BY = {
    JOINT_INDEX[joint]: JOINT_INDEX[JOINT_PARENT[joint]] for side in SIDES for joint in limb("arm", side).joints[1:]
}


def _joint_parts() -> list[tuple[int, ...]]:
    """For every joint, the parts whose match placed it (a limb's middle and end joints: both of its parts)."""
    out = [(TORSO,)] * len(JOINTS)
    out[JOINT_INDEX["head_top"]] = out[JOINT_INDEX["neck"]] = (HEAD,)
    for k in LIMBS:
        out[PART_JOINTS[k, 1]] = out[PART_JOINTS[k + 1, 1]] = (k, k + 1)
    return out


JOINT_PARTS = _joint_parts()


@dataclass(frozen=True, eq=False)
class TrackResult:
    """What the tracking found: ``joints2d`` (F, 16, 2) original pixels, sides as marked, unreliable stretches
    interpolated; ``reliability`` (F, 16) in [0, 1], S over the part's median (1 on frame 0); ``joints3d``
    (F, 16, 3) metres, CONTRACT.md's frame; ``focal_px``; ``confidence`` (F, 16) in [0, 1] (loss.joint_confidence);
    ``lost`` (F,) bool, frames whose joints are no answer; ``facing`` (F,) the person model's facing yaw (degrees,
    NaN where unsure or without one: landmarks.facing_yaw)."""

    info: VideoInfo
    joints2d: np.ndarray
    reliability: np.ndarray
    joints3d: np.ndarray
    focal_px: float
    confidence: np.ndarray
    lost: np.ndarray
    facing: np.ndarray


def track_frames(
    frames: Iterable[np.ndarray],
    marks: np.ndarray | None,
    progress: Callable[[int], None] | None = None,
    camera: Pinhole | None = None,
    turn: str | None = None,
    fps: float = 25.0,
    remarks: dict[int, np.ndarray] | None = None,
    views: Iterable[PersonView | None] | None = None,
) -> Track:
    """Track ``marks`` (16, 2) of frame 0 (None: the person model's ``views``) and ``remarks`` (frame -> marks)
    through BGR ``frames`` (reseed.track_seeded)."""
    seeds = {**(remarks or {}), **({} if marks is None else {0: marks})}
    return track_seeded(frames, seeds, progress, camera, turn, fps, views)


def joint_reliability(similarity: np.ndarray) -> np.ndarray:
    """(F, 16) per joint the least of its parts' S (F, 10) over their clip median, at most 1."""
    tracked = np.where(np.isfinite(similarity[1:]), similarity[1:], np.nan)  # marked frames aside
    usual = np.nanmedian(tracked, axis=0) if np.isfinite(tracked).any() else np.ones(len(PARTS))
    part = np.minimum(similarity / usual, 1.0)
    return np.stack([part[:, list(parts)].min(axis=1) for parts in JOINT_PARTS], axis=1)


def fill_unreliable(joints2d: np.ndarray, reliability: np.ndarray, threshold: float = LOW_RELIABILITY) -> np.ndarray:
    """Joints (F, 16, 2), stretches below ``threshold`` between reliable frames interpolated (self-occlusion)."""
    out = joints2d.copy()
    frames = np.arange(len(joints2d))
    for j in range(joints2d.shape[1]):
        good = np.flatnonzero(reliability[:, j] >= threshold)
        bad = frames[(reliability[:, j] < threshold) & (frames > good[0]) & (frames < good[-1])]
        for c in range(2):
            out[bad, j, c] = np.interp(bad, good, joints2d[good, j, c])
    return out


def spread_corrections(
    joints2d: np.ndarray, corrections: dict[int, dict[str, tuple[float, float]]], fps: float, spread_s: float = SPREAD_S
) -> np.ndarray:
    """Joints (F, 16, 2) with the user's ``corrections`` (frame -> {joint: (x, y)}) put in, their offsets fading over
    ``spread_s`` around each (a tracker off on one frame was off on its neighbours), arm joints ``carried``."""
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


def carried(
    joints2d: np.ndarray, j: int, parent: int, keys: list[int], pins: np.ndarray, moved: np.ndarray, fade: int
) -> np.ndarray:
    """(F, 2) joint ``j`` around its ``pins`` (K, 2) on frames ``keys`` carried by its ``parent``: the interpolated
    pinned vector from the parent, weighted as the ``moved`` pins' offsets fade; a lost arm moves with the body."""
    frames = np.arange(len(joints2d))
    vectors = pins - joints2d[keys, parent]
    along = np.stack([np.interp(frames, keys, vectors[:, c]) for c in range(2)], axis=-1)
    weight = faded_offsets(len(joints2d), keys, [np.full(2, float(m)) for m in moved], fade)[:, :1]
    return weight * (joints2d[:, parent] + along) + (1.0 - weight) * joints2d[:, j]


def faded_offsets(n_frames: int, keys: list[int], offsets: list[np.ndarray], fade: int) -> np.ndarray:
    """(n_frames, 2) ``offsets`` at frames ``keys`` (sorted), interpolated between keys under 2 ``fade`` apart, else
    fading linearly to zero ``fade`` frames away."""
    at, values, zero = [], [], np.zeros(2)
    for n, (key, offset) in enumerate(zip(keys, offsets)):
        alone_before = n == 0 or key - keys[n - 1] >= 2 * fade
        alone_after = n == len(keys) - 1 or keys[n + 1] - key >= 2 * fade
        at += [key - fade] * alone_before + [key] + [key + fade] * alone_after
        values += [zero] * alone_before + [offset] + [zero] * alone_after
    values = np.array(values)
    frames = np.arange(n_frames)
    return np.stack([np.interp(frames, at, values[:, c], left=0.0, right=0.0) for c in range(2)], axis=-1)


def carried_pins(corrections: dict[int, dict[str, tuple[float, float]]], frame: int, fps: float) -> dict[str, int]:
    """joint -> the nearest other frame whose correction moves it on ``frame`` (spread_corrections), frame 0 aside."""
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


def track_clip(
    video: str | os.PathLike | VideoInfo,
    marks,
    progress: Progress | None = None,
    *,
    focal_px: float | None = None,
    orientation: str | None = None,
    remarks: dict | None = None,
    person: PersonModel | None = None,
) -> TrackResult:
    """Track a video (path or VideoInfo) from its 16 joints marked on frame 0 and reconstruct 3D. ``marks``: (16, 2)
    in JOINTS order or joint -> (x, y) (bad ones raise MocapError), None: the ``person`` model's first sure ones;
    ``focal_px`` default the frame width; ``orientation``: CONTRACT.md's word for frame 0, whose side tells the turn
    (None: ``guessed_turn``); ``remarks``: frame -> joints marked again (mocap.track.reseed); ``person``: a fresh
    person model seeding the body where none holds and guiding the limbs; ``progress(done, total)`` after every
    frame."""
    info = video if isinstance(video, VideoInfo) else open_video(video)
    scale = processing_scale(info)
    if marks is not None:
        marks = rescaled(check_marks(marks, info.width, info.height), scale)
    seeds = {
        f: rescaled(check_marks(m, info.width, info.height), scale)
        for f, m in (remarks or {}).items()
        if 0 < f < info.frame_count
    }
    turn = turn_of(orientation)
    step = (lambda done: progress(done, info.frame_count)) if progress else None
    frames, views = _looked_at(person, (frame for _, frame in iter_frames(info, scale=scale)))
    seen: list[Landmarks | None] = []
    camera = default_camera(info.width, info.height, focal_px)
    joints, similarity, parts, lost, facing = track_frames(
        frames, marks, step, camera.scaled(scale), turn, info.fps, seeds, _kept(views, seen)
    )
    joints = rescaled(joints, 1.0 / scale)
    reliability = joint_reliability(similarity)
    joints, lost = bridged(joints, lost, int(round(GAP_S * info.fps)))
    joints2d = averaged_with_landmarks(
        fill_unreliable(joints, reliability), landmark_array(seen, len(joints), scale), info.fps
    )
    turn = turn or guessed_turn(joints2d, info.fps)
    try:
        joints3d = to_contract(steady_reconstruction(joints2d, camera, turn, info.fps, ~lost))
    except MocapError as error:
        if marks is not None:
            raise
        raise MocapError(f"frame 0 as the person model's landmarks placed it: {error}; mark the 16 joints") from None
    return TrackResult(info, joints2d, reliability, joints3d, camera.focal, joint_confidence(parts), lost, facing)


def _looked_at(person: PersonModel | None, frames: Iterator[np.ndarray]) -> tuple[Iterator, Iterator | None]:
    """``frames`` and, in step with them, the ``person`` model's view of each (None: nobody), the model looking
    ahead where it can (person.watched); no views without a model."""
    if person is None:
        return frames, None
    a, b = itertools.tee(watched(person, frames))
    return (frame for frame, _ in a), (view for _, view in b)


def _kept(views: Iterator | None, seen: list) -> Iterator | None:
    """``views`` as they come, each one's landmarks (None: nobody) also appended to ``seen``."""
    if views is None:
        return None
    return (seen.append(None if view is None else view.landmarks) or view for view in views)


def landmark_array(seen: list[Landmarks | None], n_frames: int, scale: float) -> np.ndarray:
    """(n_frames, 16, 2) the sure landmarks (person.SURE) of ``seen`` (frames at processing ``scale``) in the
    original frame's pixels, NaN where the model saw nobody, was unsure or was not asked."""
    out = np.full((n_frames, len(JOINTS), 2), np.nan)
    for f, view in enumerate(seen[:n_frames]):
        if view is not None:
            sure = view.confidence >= SURE
            out[f, sure] = view.scaled(1.0 / scale).joints2d[sure]
    return out


def head_to_ankles(joints2d: np.ndarray) -> np.ndarray:
    """(F,) pixels from the head's top to the ankles' middle of 2D joints (F, 16, 2)."""
    ankles = joints2d[:, [JOINT_INDEX["ankle_l"], JOINT_INDEX["ankle_r"]]].mean(axis=1)
    return np.linalg.norm(joints2d[:, JOINT_INDEX["head_top"]] - ankles, axis=-1)


def standing_heights(joints2d: np.ndarray, fps: float) -> np.ndarray:
    """(F,) pixels: each frame's standing height, the STANDING_PERCENTILE of the head-top-to-ankles distances over
    STANDING_S around it (a bend is shorter; a walk toward the camera grows)."""
    heights = head_to_ankles(joints2d)
    known = np.isfinite(heights)
    if not known.any():
        return heights
    heights = np.interp(np.arange(len(heights)), np.flatnonzero(known), heights[known])
    size = max(1, int(round(STANDING_S * fps))) | 1
    return percentile_filter(heights, STANDING_PERCENTILE, size=size, mode="nearest")


def averaged_with_landmarks(joints2d: np.ndarray, landmarks: np.ndarray, fps: float) -> np.ndarray:
    """(F, 16, 2) each tracked joint averaged with the person model's landmark (F, 16, 2; NaN: none) where the
    two lie within AGREE_SHARE of the standing height (``standing_heights``) on a frame whose landmarks lie
    within AGREE_BODY of the tracked joints (median): the colours' blocks and the learned model read one joint
    with errors of their own, which the mean halves; farther apart, one of them has lost the joint or the body,
    and the tracking keeps its own. Not the head top, which the person model does not see
    (mediapipe_pose.HEAD_TOP_ALONG extends the shoulders -> ears line beyond the ears)."""
    apart = np.linalg.norm(landmarks - joints2d, axis=-1) / standing_heights(joints2d, fps)[:, None]
    apart[:, JOINT_INDEX["head_top"]] = np.nan
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a frame without landmarks: its median is NaN
        same_body = np.nanmedian(apart, axis=1) <= AGREE_BODY
    near = (apart < AGREE_SHARE) & same_body[:, None]
    return np.where(near[..., None], (joints2d + landmarks) / 2, joints2d)


def guessed_turn(joints2d: np.ndarray, fps: float) -> str:
    """ "left" or "right" by the knees' bend over the first TURN_CUE_S (knee_facing): mirror turns fit alike."""
    return knee_facing(joints2d[: max(1, int(round(TURN_CUE_S * fps)))])


def steady_reconstruction(
    joints2d: np.ndarray, camera: Pinhole, turns: Turns, fps: float, seen: np.ndarray | None = None
) -> np.ndarray:
    """(F, 16, 3) pinhole joints (metres) of 2D joints (F, 16, 2): ``reconstruct`` of ``steady_joints`` turned to
    ``turns``, bones over frames ``seen``, depths smoothed (``steady_depths``)."""
    return steady_depths(reconstruct(steady_joints(joints2d, fps), camera, turns, seen=seen), fps)


def steady_joints(joints2d: np.ndarray, fps: float) -> np.ndarray:
    """The 2D joints (F, 16, 2) the 3D is reconstructed from: smoothed over SMOOTH_S."""
    return gaussian_filter1d(joints2d, SMOOTH_S * fps, axis=0, mode="nearest")
