"""A person model's landmarks (mocap.person) as the lift's first guesses (section 3.4's inputs):
sides, yaw, signs, depths and 2D joints; the user's annotations still override them."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.ndimage import gaussian_filter1d, median_filter

from mocap.body import JOINT_INDEX, LEG_JOINTS, LIMB_JOINTS, MIRROR_JOINTS, SEGMENT_JOINTS, SEGMENT_NAMES
from mocap.lift.taylor import AWAY, TOWARD, UNIT_M, median_width, runs, yaw_of
from mocap.smoothest import smoothest_states, two_state_path

SWITCH = 2.0  # limb lengths of evidence that renaming a limb pair between frames costs
SIDE_MARGIN = 0.05  # limb lengths: evidence below this per frame says nothing
SMOOTH_S = 0.04  # seconds: the spread of the landmarks' smoothing over time, about a frame of 25 fps
MEDIAN_S = 0.1  # seconds: the running median before it (three frames of 25 fps): a slip of a frame dropped
DISAGREE = 0.2  # of the body height: a frame whose landmarks lie this far from the fit's
# joints (median) is one the person model got wrong
MIRRORED_COST_S = 5.0  # what a second of frames read as the model's mirror image costs, in the units of
# Cues.unmirrored's acceleration (radians of facing, limb lengths of limb joints, per frame squared)
SWAPPED_COST_S = MIRRORED_COST_S / 2  # a second of frames whose one limb pair is read exchanged (Cues.limbs_unswapped):
# less than a whole mirror reading, which a model makes more rarely than it names one pair the other way round
UNSIGNED = ("torso",)  # segments whose sign the world landmarks do not give (world_signs): MediaPipe's torso
# leans the wrong way on more frames than the right one (on the development clips' judged frames, 40 % right); its
# |dZ| still helps the solve (world_depths)
LOOK_COST_S = 2 * MIRRORED_COST_S  # what a second of frames costs whose facing the head's look, sure, denies
_J = JOINT_INDEX
_LIMBS = {p: [(f"{j}_l", f"{j}_r") for j in LIMB_JOINTS[k][1:]] for p, k in ((0, "arm"), (1, "leg"))}
_PAIRS = [
    np.array([_J[n] for lr in names for n in lr]) for names in _LIMBS.values()
]  # elbows and wrists, knees and ankles
_LIMB_JOINTS = np.array([_J[n] for pairs in _LIMBS.values() for pair in pairs for n in pair])  # elbows to ankles


@dataclass(frozen=True)
class Cues:
    """A clip's landmarks: ``joints2d`` (F, 16, 2) pixels, anatomical sides, NaN where nobody was seen;
    ``confidence`` (F, 16); ``world`` (F, 16, 3) metres, pelvis-centred, contract axes; ``doubtful`` (F, 16)
    joints the model's two looks placed apart (mocap.person.Landmarks; None: none)."""

    joints2d: np.ndarray
    confidence: np.ndarray
    world: np.ndarray
    doubtful: np.ndarray | None = None

    @classmethod
    def of(cls, landmarks: list, fps: float, away: np.ndarray | None = None) -> "Cues | None":
        """The cues of per-frame ``mocap.person.Landmarks`` (None: nobody), the frames seen as a mirror image put
        right (``unmirrored``, with the head's look ``away``), smoothed over time (``smoothed``); None when none
        has any."""
        if all(m is None for m in landmarks):
            return None
        n = len(landmarks)
        joints, conf, world = np.full((n, 16, 2), np.nan), np.zeros((n, 16)), np.full((n, 16, 3), np.nan)
        doubtful = np.zeros((n, 16), bool)
        for i, m in enumerate(landmarks):
            if m is not None:
                joints[i], conf[i], world[i] = m.joints2d, m.confidence, m.world
                doubtful[i] = False if m.doubtful is None else m.doubtful
        raw = cls(joints, conf, world, doubtful).unmirrored(fps, away).limbs_unswapped(fps)
        return replace(raw, joints2d=smoothed(raw.joints2d, fps), world=smoothed(raw.world, fps))

    def agreeing(self, joints_image: np.ndarray, body_px: np.ndarray) -> "Cues":
        """These cues less frames whose landmarks lie DISAGREE body heights (median, pairs either way)
        from the fit's ``joints_image`` (F, 16, 2): there the model lost the body and the fit answers."""
        distances = unsided_distances(joints_image, self.joints2d)
        off = np.full(len(distances), np.inf)
        both = np.isfinite(distances).all(axis=1)
        off[both] = np.median(distances[both], axis=1) / body_px[both]
        wrong = ~(off <= DISAGREE)
        return replace(
            self,
            joints2d=np.where(wrong[:, None, None], np.nan, self.joints2d),
            confidence=np.where(wrong[:, None], 0.0, self.confidence),
            world=np.where(wrong[:, None, None], np.nan, self.world),
        )

    def unmirrored(self, fps: float, away: np.ndarray | None = None) -> "Cues":
        """These cues with the frames the model saw from the wrong side put right. A person model that takes a
        back for a front sees the depth mirror image, which projects alike: its facing yaw becomes 180 - yaw and
        its left and right are exchanged. Now and then it does so for a stretch of frames, and the body seems to
        make a half turn in a frame and its limbs to jump between sides. Within each run of seen frames each
        frame is read as given or as its mirror image, whichever path is smoothest (``smoothest_states``: the
        least acceleration of the facing direction, in radians, and of the limb joints, in limb lengths); a
        frame read as a mirror image costs MIRRORED_COST_S per second, so only such jumps are undone. A smooth
        turn reads smoothly either way (a yaw passing 180 or bouncing back from 90); there the head's look
        decides: ``away`` (F,) in [-1, 1], the silhouette method's evidence that the performer faces away
        (mocap.silhouette.facing.facing_away), makes a frame whose reading faces the other way cost up to
        LOOK_COST_S per second, by how squarely it faces the camera or its back (|cos yaw|)."""
        seen = self.seen
        if not seen.any():
            return self
        mirrored = np.zeros(len(seen), bool)
        limb = 0.5 * float(np.median(np.ptp(self.joints2d[seen, :, 1], axis=1)))  # half the body's height
        yaw = np.radians(world_yaws(self))
        for r in runs(seen):
            if r.stop - r.start < 3:
                continue
            facing = np.stack([yaw[r], np.pi - yaw[r]], axis=1)
            limbs = self.joints2d[r][:, [_LIMB_JOINTS, MIRROR_JOINTS[_LIMB_JOINTS]]] / max(limb, 1e-6)
            values = np.concatenate(
                [np.stack([np.cos(facing), np.sin(facing)], axis=-1), limbs.reshape(len(facing), 2, -1)], axis=-1
            )
            cost = np.zeros((len(facing), 2))
            cost[:, 1] = MIRRORED_COST_S / fps
            if away is not None:
                cost += LOOK_COST_S / fps * np.maximum(0.0, away[r, None] * np.cos(facing))
            mirrored[r] = smoothest_states(values, cost) == 1
        if not mirrored.any():
            return self
        world = self.world.copy()
        world[mirrored] = world[mirrored][:, MIRROR_JOINTS] * np.array([1.0, 1.0, -1.0])
        joints, confidence = self.joints2d.copy(), self.confidence.copy()
        doubtful = np.zeros(confidence.shape, bool) if self.doubtful is None else self.doubtful.copy()
        for named in (joints, confidence, doubtful):
            named[mirrored] = named[mirrored][:, MIRROR_JOINTS]
        return Cues(joints, confidence, world, doubtful)

    def limbs_unswapped(self, fps: float) -> "Cues":
        """These cues with each limb pair's sides put right where the model named them the other way round for a
        stretch of frames (a profile's far leg taken for the near one as the body turns), the rest of the body
        named right: per pair (arms, legs) and run of seen frames, each frame read as named or with the pair's
        sides exchanged, whichever path moves the pair's joints most smoothly (``smoothest_states``, limb lengths
        per frame squared); a frame read exchanged costs SWAPPED_COST_S per second."""
        seen = self.seen
        if not seen.any():
            return self
        limb = 0.5 * float(np.median(np.ptp(self.joints2d[seen, :, 1], axis=1)))  # half the body's height
        swap = np.zeros(self.confidence.shape, bool)
        for pair in _PAIRS:
            for r in runs(seen):
                if r.stop - r.start < 3:
                    continue
                named = self.joints2d[r][:, [pair, MIRROR_JOINTS[pair]]] / max(limb, 1e-6)
                cost = np.zeros((r.stop - r.start, 2))
                cost[:, 1] = SWAPPED_COST_S / fps
                swap[r][:, pair] = (smoothest_states(named.reshape(len(cost), 2, -1), cost) == 1)[:, None]
        if not swap.any():
            return self
        order = np.where(swap, MIRROR_JOINTS, np.arange(len(MIRROR_JOINTS)))
        doubtful = None if self.doubtful is None else np.take_along_axis(self.doubtful, order, axis=1)
        return Cues(
            np.take_along_axis(self.joints2d, order[..., None], axis=1),
            np.take_along_axis(self.confidence, order, axis=1),
            np.take_along_axis(self.world, order[..., None], axis=1),
            doubtful,
        )

    @property
    def seen(self) -> np.ndarray:
        """(F,) bool: frames where the model saw somebody."""
        return np.isfinite(self.joints2d).all(axis=(1, 2))


def smoothed(points: np.ndarray, fps: float) -> np.ndarray:
    """(F, ...) per-frame points, NaN where unseen, smoothed over time within each run of seen frames: a running
    median over MEDIAN_S (a joint the person model misplaces on one frame is dropped, not spread), then a
    Gaussian of SMOOTH_S seconds, both ways: its per-frame jitter averaged out without the lag of its own one-way
    filter (mocap.person reads each frame alone). A run's ends are extended point-symmetrically, so a steady
    motion keeps its ends."""
    sigma = SMOOTH_S * fps
    width = median_width(MEDIAN_S, fps)
    seen = np.isfinite(points).reshape(len(points), -1).all(axis=1)
    out = points.copy()
    for r in runs(seen):
        run = points[r]
        pad = min(len(run) - 1, max(int(np.ceil(4 * sigma)), width // 2))
        ext = np.concatenate([2 * run[0] - run[pad:0:-1], run, 2 * run[-1] - run[-2 : -pad - 2 : -1]])
        ext = median_filter(ext, size=(width,) + (1,) * (points.ndim - 1), mode="nearest")
        out[r] = gaussian_filter1d(ext, sigma, axis=0, mode="nearest")[pad : pad + len(run)]
    return out


def side_evidence(joints_image: np.ndarray, cues: Cues, limb_px: float) -> np.ndarray:
    """(F, 2) int8 ``known`` for sides.track_sides: 1 where the fit's image-left arm/leg is the
    landmarks' right, 0 left, -1 unknown; confidence-weighted distances in ``limb_px``, a two-state path
    (SWITCH per renaming) against single-frame swaps."""
    out = np.full((len(joints_image), 2), -1, np.int8)
    seen = cues.seen & np.isfinite(joints_image).all(axis=(1, 2))
    if not seen.any():
        return out
    for pair, names in _LIMBS.items():
        margin = np.zeros(len(joints_image))
        for left, right in names:
            w = np.minimum(cues.confidence[:, _J[left]], cues.confidence[:, _J[right]])
            keep, swap = _namings(joints_image, cues.joints2d, left, right)
            margin += np.where(seen, w * (keep - swap) / limb_px, 0.0)
        costs = np.column_stack([np.maximum(margin, 0.0), np.maximum(-margin, 0.0)])
        path = two_state_path(costs, np.full(len(costs) - 1, SWITCH))
        out[:, pair] = np.where(seen & (np.abs(margin) >= SIDE_MARGIN), path, -1)
    return out


def unsided_distances(joints_image: np.ndarray, landmarks: np.ndarray) -> np.ndarray:
    """(F, 16) each joint's distance (pixels) to its landmark, limb pairs named whichever way is nearer."""
    d = _dist(joints_image, landmarks)
    for names in _LIMBS.values():
        for left, right in names:
            kept, crossed = _namings(joints_image, landmarks, left, right)
            better = crossed < kept
            d[better, _J[left]] = d[better, _J[right]] = crossed[better] / 2
    return d


def _namings(joints: np.ndarray, landmarks: np.ndarray, left: str, right: str) -> tuple[np.ndarray, np.ndarray]:
    """(F,) twice: a limb pair's summed joint-landmark distances, landmarks as named and exchanged."""
    l, r = _J[left], _J[right]
    return (
        _dist(joints[:, l], landmarks[:, l]) + _dist(joints[:, r], landmarks[:, r]),
        _dist(joints[:, l], landmarks[:, r]) + _dist(joints[:, r], landmarks[:, l]),
    )


def _dist(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.linalg.norm(a - b, axis=-1)


def world_yaws(cues: Cues) -> np.ndarray:
    """(F,) degrees: each frame's world landmarks' facing yaw (taylor.yaw_of), NaN where nobody."""
    return np.array([yaw_of(w) if ok else np.nan for w, ok in zip(cues.world, cues.seen)])


def world_signs(cues: Cues) -> np.ndarray:
    """(F, 10) int: each segment's sign in the world landmarks (+1 toward, -1 away, 0 nobody or UNSIGNED)."""
    ends = cues.world[:, SEGMENT_JOINTS]
    dz = ends[:, :, 1, 2] - ends[:, :, 0, 2]
    return np.where(np.isfinite(dz) & ~np.isin(SEGMENT_NAMES, UNSIGNED), np.where(dz >= 0, TOWARD, AWAY), 0)


def world_depths(cues: Cues, lengths: np.ndarray) -> np.ndarray:
    """(F, 10) |dZ| per segment in the world landmarks, in model units of the clip's ``lengths`` (10,)
    (scaled by the median length ratio); NaN where nobody."""
    ends = cues.world[:, SEGMENT_JOINTS] / UNIT_M
    vec = ends[:, :, 1] - ends[:, :, 0]
    seen_lengths = np.nanmedian(np.linalg.norm(vec[cues.seen], axis=-1), axis=0)
    ratio = float(np.nanmedian(lengths / np.maximum(seen_lengths, 1e-9)))
    return np.abs(vec[..., 2]) * ratio


def with_landmarks(joints: np.ndarray, cues: Cues) -> np.ndarray:
    """(F, 16, 2) anatomical joints: the landmarks where the model saw the body (a learned joint lies
    nearer the truth than a cylinder's end) but leg joints its two looks placed apart (``doubtful``), the fit's
    elsewhere: a leg ends the silhouette on the floor, and the fit's is the surer where the model hesitates (a
    hand lost against the trunk is not, and its landmark stays)."""
    taken = np.isfinite(cues.joints2d) & np.isfinite(joints)
    if cues.doubtful is not None:
        taken[:, LEG_JOINTS] &= ~cues.doubtful[:, LEG_JOINTS, None]
    return np.where(taken, cues.joints2d, joints)
