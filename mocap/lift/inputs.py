"""What the lifting needs per frame: the user's annotations laid over the first guess
(orientation, sides, signs) and the joint overrides put in (section 3.4)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import median_filter

from mocap.body import BODY_HEIGHT, BODY_HEIGHT_M, JOINT_INDEX, LIMB_JOINTS, SEGMENT_NAMES, SIDES, segment_kind
from mocap.camera import default_camera
from mocap.lift.cues import Cues, side_evidence, with_landmarks, world_depths, world_signs, world_yaws
from mocap.lift.orientation import (
    facing_evidence,
    guess_orientations,
    guess_signs,
    held_user_signs,
    legs_crossed,
    looks_away,
    rule_evidence,
    yaws,
)
from mocap.lift.sides import known_sides, track_sides
from mocap.lift.taylor import (
    LENGTH,
    anatomical_joints,
    clip_lengths,
    exchange_legs,
    median_width,
    orientation_of_yaw,
    runs,
)

# Segment lengths for Eq. 5 from the fitted clip: the median projected length (a high
# percentile would measure the fit's scatter); the torso and head, mostly upright, where
# Eq. 5 turns a length read long into a lean: the 25th percentile.
FIT_LENGTH_PERCENTILE = np.where(np.isin(SEGMENT_NAMES, ("torso", "head")), 25.0, 50.0)
# ... and where the person model's landmarks give most frames' 2D: a standing leg lies in the
# image plane, and the landmarks do not scatter as the fit's cylinders do, so a high percentile
# of their image lengths measures the legs (taylor.clip_lengths' for clean 2D)
LEGS = np.isin([segment_kind(s) for s in SEGMENT_NAMES], ("upper_leg", "lower_leg"))
LANDMARK_LENGTH_PERCENTILE = np.where(LEGS, 90.0, FIT_LENGTH_PERCENTILE)
# The fit's limbs slip on single frames (an arm in front of the trunk fits anywhere
# inside it, a leg behind the other); the lifting reads their elbows, wrists, knees and
# ankles through a running median, the legs' shorter: a foot's strike and lift-off are
# sharper than an arm's swing, and the contacts are timed by them.
ARM_MEDIAN_S = 0.2
LEG_MEDIAN_S = 0.1


@dataclass(frozen=True, eq=False)
class Inputs:
    """Everything the lifting needs per frame; frames without a person: orientation None, NaN joints."""

    orientation: list[str | None]
    yaw: np.ndarray  # (F,) degrees, see lift.facing_yaw
    swap: np.ndarray  # (F, 2) bool: image-left arms, legs are the right ones
    joints2d: np.ndarray  # (F, 16, 2) anatomical pixels, joint overrides applied
    px_per_unit: np.ndarray  # (F,) pixels per model unit (body height / 175)
    signs: np.ndarray  # (F, 10) +1 toward, -1 away: the first guess under the held signs (or a 3D's)
    lengths: np.ndarray  # (10,) segment lengths in model units
    held: np.ndarray | None = None  # (F, 10) the user's signs where they hold, 0 elsewhere
    depths: np.ndarray | None = None  # (F, 10) |dZ| a person model sees (cues.world_depths), NaN where none


@dataclass(frozen=True, eq=False)
class Said:
    """What the user said, as arrays over F frames (mocap.io.annotations.Annotations holds
    it as written): each frame's orientation (None: not said), the joint overrides
    {frame: {joint: (x, y)}}, and each segment's latest sign (F, 10; +1 toward, -1 away,
    0 none) with the frame it was said on (-1 none)."""

    orientation: list[str | None]
    overrides: dict[int, dict[str, tuple[float, float]]]
    signs: np.ndarray
    since: np.ndarray

    @classmethod
    def nothing(cls, n: int) -> "Said":
        return cls([None] * n, {}, np.zeros((n, len(SEGMENT_NAMES)), np.int8), np.full((n, len(SEGMENT_NAMES)), -1))


@dataclass(frozen=True, eq=False)
class Named:
    """What of the inputs the user's signs leave alone (``name_limbs``): ``orientation`` (F,) the user's over the
    guess, ``yaw`` (F,) degrees, ``names`` (F, 3) the limbs' naming (sides.track_sides), ``cues`` the person
    model's landmarks on the frames they agree with the fit (None: no person model)."""

    orientation: list[str | None]
    yaw: np.ndarray
    names: np.ndarray
    cues: Cues | None


def name_limbs(
    joints_image: np.ndarray,
    body_px: np.ndarray,
    spread: np.ndarray,
    fps: float,
    said: Said,
    guessed: list[str | None] | None = None,
    away: np.ndarray | None = None,
    near: np.ndarray | None = None,
    cues: Cues | None = None,
    facing: np.ndarray | None = None,
) -> Named:
    """The orientation, yaw and limb naming of every frame, as ``resolve_inputs`` takes them: the user's sticky
    orientation over ``guessed`` (None: guessed here) or the person model's yaw, sides by sides.track_sides.
    They read the user's orientations and joint overrides, never their signs, so a sign click keeps them."""
    n = len(joints_image)
    person = np.isfinite(joints_image).all(axis=(1, 2)) & np.isfinite(body_px)
    if cues is not None:
        cues = cues.agreeing(joints_image, body_px)
    if guessed is None:
        guessed = guess_orientations(joints_image, body_px, spread, fps, away)
    world_yaw = np.full(n, np.nan) if cues is None else world_yaws(cues)
    guessed = [g if np.isnan(y) else orientation_of_yaw(y) for g, y in zip(guessed, world_yaw)]
    orientation = [(s or g) if person[i] else None for i, (s, g) in enumerate(zip(said.orientation, guessed))]
    overrides = {i: o for i, o in said.overrides.items() if i < n and person[i]}
    facing_x = np.array([-1.0 if o and o.endswith("left") else 1.0 for o in orientation])
    if facing is None:
        facing = facing_evidence(joints_image, body_px, fps, away)
    rule = rule_evidence(orientation, spread, facing)
    rule = np.where([s is None for s in said.orientation], rule, 0.0)
    known = known_sides(said.orientation, overrides, joints_image)
    if cues is not None:
        known = np.where(known >= 0, known, side_evidence(joints_image, cues, 0.5 * np.nanmedian(body_px)))
    names = track_sides(joints_image, known, facing_x, fps, looks_away(away, fps, n), near, rule)
    yaw = yaws(orientation, np.where(np.isfinite(spread), spread, 1.0))
    yaw = np.where(np.isfinite(world_yaw) & np.array([s is None for s in said.orientation]), world_yaw, yaw)
    return Named(orientation, yaw, names, cues)


def resolve_inputs(
    joints_image: np.ndarray,
    body_px: np.ndarray,
    spread: np.ndarray,
    fps: float,
    said: Said,
    lengths: np.ndarray | None = None,
    guessed: list[str | None] | None = None,
    away: np.ndarray | None = None,
    near: np.ndarray | None = None,
    cues: Cues | None = None,
    facing: np.ndarray | None = None,
    named: Named | None = None,
) -> Inputs:
    """Per-frame lifting inputs: the orientation, yaw and sides (``named``, else ``name_limbs``), legs crossed
    (orientation.legs_crossed); arms steadied; overrides put in; ``lengths`` (None: the clip's); signs under
    the user's held ones. ``away`` (F,) the heads' look, ``near`` (F, 2) the near limbs
    (mocap.silhouette.facing); ``cues``: person-model landmarks, first guesses where seen; ``facing`` the
    clip's orientation.facing_evidence (None: worked out here; it needs no annotation)."""
    named = named or name_limbs(joints_image, body_px, spread, fps, said, guessed, away, near, cues, facing)
    orientation, yaw, names, cues = named.orientation, named.yaw, named.names, named.cues
    n = len(joints_image)
    person = np.isfinite(joints_image).all(axis=(1, 2)) & np.isfinite(body_px)
    overrides = {i: o for i, o in said.overrides.items() if i < n and person[i]}
    swap = names[:, :2]
    ppu = body_px / BODY_HEIGHT
    values, since = said.signs, said.since
    joints = exchange_legs(anatomical_joints(joints_image, swap), names[:, 2])
    if person.any():
        seen = clip_lengths(joints_image[person], ppu[person], FIT_LENGTH_PERCENTILE, pool=True)
        held = _held_signs(values, since, person)
        placed = np.array(
            [any(j.startswith(LIMB_JOINTS["leg"][1:]) for j in overrides.get(i, ())) for i in range(n)], bool
        )
        crossed = np.zeros(n, bool)
        crossed[person] = legs_crossed(joints[person], held[person], yaw[person], ppu[person], seen, placed[person])
        joints = exchange_legs(joints, crossed)
    joints = steadied_limbs(joints, person, fps)
    if cues is not None:
        joints = with_landmarks(joints, cues)
    for i, points in overrides.items():
        for joint, xy in points.items():
            joints[i, JOINT_INDEX[joint]] = xy
    if lengths is None:
        lengths = segment_lengths(joints, ppu, person, None if cues is None else cues.seen)
    # signs are judged on the longer 90th-percentile lengths: where the fit's noise
    # makes a segment look unforeshortened they still keep the two depths apart
    judged = clip_lengths(joints[person], ppu[person]) if person.any() else lengths
    signs = np.ones((n, len(SEGMENT_NAMES)), int)
    fixed = _held_signs(values, since, person)
    for r in runs(person):
        signs[r] = guess_signs(joints[r], ppu[r], yaw[r], np.maximum(judged, lengths), fixed[r], fps)
    depths = None
    if cues is not None:
        seen = world_signs(cues)
        signs = np.where((fixed == 0) & (seen != 0), seen, signs)
        depths = world_depths(cues, lengths)
    return Inputs(orientation, yaw, swap, joints, ppu, signs, lengths, fixed, depths)


def segment_lengths(joints: np.ndarray, ppu: np.ndarray, person: np.ndarray, seen: np.ndarray | None) -> np.ndarray:
    """(10,) model units: the clip's segment lengths for Eq. 5, pairs pooled, from 2D ``joints`` (F, 16, 2) on the
    ``person`` frames (F,) at ``ppu`` (F,) pixels per unit: FIT_LENGTH_PERCENTILE of the image lengths, or
    LANDMARK_LENGTH_PERCENTILE's on the frames the person model's landmarks give (``seen`` (F,); None: none)
    where they are most of them; the model's where nobody is."""
    if not person.any():
        return LENGTH.copy()
    landmarks = person if seen is None else person & seen
    if seen is not None and 2 * landmarks.sum() > person.sum():
        return clip_lengths(joints[landmarks], ppu[landmarks], LANDMARK_LENGTH_PERCENTILE, pool=True)
    return clip_lengths(joints[person], ppu[person], FIT_LENGTH_PERCENTILE, pool=True)


def steadied_limbs(joints: np.ndarray, person: np.ndarray, fps: float) -> np.ndarray:
    """(F, 16, 2) with elbows and wrists a running median over ARM_MEDIAN_S, knees and ankles over LEG_MEDIAN_S,
    within each person stretch (anatomical sides: in a profile the image sides change as limbs pass the trunk)."""
    out, stretches = joints.copy(), runs(person)
    for kind, seconds in (("arm", ARM_MEDIAN_S), ("leg", LEG_MEDIAN_S)):
        size = (median_width(seconds, fps), 1, 1)
        limbs = [JOINT_INDEX[f"{n}_{s}"] for n in LIMB_JOINTS[kind][1:] for s in SIDES]
        for r in stretches:
            out[r, limbs] = median_filter(joints[r, limbs], size=size, mode="nearest")
    return out


def _held_signs(values: np.ndarray, since: np.ndarray, person: np.ndarray) -> np.ndarray:
    """(F, 10) the user's signs where they hold (orientation.held_user_signs) and a person is, 0 elsewhere."""
    return np.where(person[:, None], held_user_signs(values, since), 0).astype(int)


def root_track(
    joints2d: np.ndarray, px_per_unit: np.ndarray, size: tuple[int, int], focal_px: float | None = None
) -> np.ndarray:
    """(F, 3) pelvis in metres, camera frame (x right, y up, z toward it; NaN: nobody), by scaled
    orthography: depth = focal * metres-per-unit / ``px_per_unit``; ``size`` (width, height) pixels;
    ``focal_px`` default ``default_camera``'s (the frame width): it scales the depth, not its shape."""
    focal = default_camera(*size, focal_px).focal
    per_m = px_per_unit * BODY_HEIGHT / BODY_HEIGHT_M
    pelvis = joints2d[:, JOINT_INDEX["pelvis"]]
    return np.stack(
        [(pelvis[:, 0] - size[0] / 2) / per_m, (size[1] / 2 - pelvis[:, 1]) / per_m, -focal / per_m], axis=-1
    )
