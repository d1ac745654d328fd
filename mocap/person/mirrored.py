"""A person model that looks at each frame twice, as it comes and mirrored left to right, and answers the mean of
the two views (test-time flip augmentation, as pose estimators are commonly evaluated): a learned model's errors
are partly those of the side it faces, and the two views' errors partly cancel. The frame's own view decides
whether anybody is there and how the limbs are named: a body found only in the mirror image is one the model
is unsure of (seen in profile it names the sides either way from frame to frame)."""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Iterator
from dataclasses import replace

import numpy as np

from mocap.body import JOINT_INDEX, JOINTS, LIMB_JOINTS, MIRROR_JOINTS
from mocap.person.views import Landmarks, PersonModel, PersonView, watched

# the joints of each limb pair, the arms' then the legs', left and right in turn
LIMB_PAIRS = [[JOINT_INDEX[f"{part}_{side}"] for part in parts for side in "lr"] for parts in LIMB_JOINTS.values()]

EVEN = 1e-3  # added to both confidences of a joint: two that are both about 0 weigh alike
DOUBT = 0.2  # trunk lengths (neck to pelvis) the two views may place a joint apart before it is doubtful
_NECK, _PELVIS = JOINT_INDEX["neck"], JOINT_INDEX["pelvis"]


class WithMirror:
    """``straight`` fed the frames as they come, ``mirror`` (a MirrorImage of a second instance of the same model)
    fed them too; one PersonModel whose view is the two's mean (``merged``)."""

    with_mirror = True

    def __init__(self, straight: PersonModel, mirror: PersonModel):
        self.straight, self.mirror = straight, mirror
        self.name, self.filtered = straight.name, straight.filtered

    def observe(self, frame: np.ndarray) -> PersonView | None:
        """The mean view of the frame and of its mirror image, None where the frame's own shows nobody."""
        return merged(self.straight.observe(frame), self.mirror.observe(frame))

    def watch(self, frames: Iterable[np.ndarray]) -> Iterator[tuple[np.ndarray, PersonView | None]]:
        """Each frame with its merged view, both models sent frames ahead (``watched``): in processes of their own,
        they look at the same frame at once."""
        as_come, again = itertools.tee(frames)
        for (frame, view), (_, mirrored) in zip(watched(self.straight, as_come), watched(self.mirror, again)):
            yield frame, merged(view, mirrored)

    def close(self) -> None:
        self.straight.close()
        self.mirror.close()


class MirrorImage:
    """A person model fed each frame's mirror image, its views turned back to the frame's (``unmirrored``)."""

    with_mirror = False

    def __init__(self, model: PersonModel):
        self.model = model
        self.name, self.filtered = model.name, model.filtered

    def observe(self, frame: np.ndarray) -> PersonView | None:
        """The model's view of the frame's mirror image, in the frame's pixels and anatomical sides."""
        return unmirrored(self.model.observe(frame[:, ::-1]), frame.shape[1])

    def close(self) -> None:
        self.model.close()


def unmirrored(view: PersonView | None, width: int) -> PersonView | None:
    """A view of a mirrored frame ``width`` pixels wide turned back: mask and x mirrored, sides renamed."""
    if view is None:
        return None
    marks = view.landmarks
    joints2d = marks.joints2d[MIRROR_JOINTS].copy()
    joints2d[:, 0] = width - 1 - joints2d[:, 0]
    world = marks.world[MIRROR_JOINTS] * np.array([-1.0, 1.0, 1.0])
    return PersonView(
        None if view.mask is None else view.mask[:, ::-1], Landmarks(joints2d, marks.confidence[MIRROR_JOINTS], world)
    )


def merged(one: PersonView | None, other: PersonView | None) -> PersonView | None:
    """The mean of the frame's own view (``one``) and its mirror image's (``other``) (``mean_landmarks``), the mask
    ``one``'s; ``one`` as it is where ``other`` is None, None where ``one`` is."""
    if one is None or other is None:
        return one
    return replace(one, landmarks=mean_landmarks(one.landmarks, other.landmarks))


def mean_landmarks(a: Landmarks, b: Landmarks) -> Landmarks:
    """The mean of two looks at one body, ``a`` the one whose naming holds: each joint's 2D and world weighted by
    the two's confidences, the confidences averaged. Where the two name a limb pair's sides the other way round
    (``crossed_joints``), ``a``'s naming holds: the 2D means are taken with ``b``'s sides swapped to it, and that
    limb pair's world and confidences are ``a``'s (a depth read as from the other side is no mean's part), and
    its joints ``crossed``. Joints the two place ``apart`` are ``doubtful``, and those either look doubted."""
    crossed = crossed_joints(a.joints2d, b.joints2d)
    order = np.where(crossed, MIRROR_JOINTS, np.arange(len(JOINTS)))
    b_conf = b.confidence[order]
    share = (b_conf + EVEN) / (a.confidence + b_conf + 2 * EVEN)  # b's, by confidence
    depth_share = np.where(crossed, 0.0, share)
    doubtful = apart(a.joints2d, b.joints2d[order])
    for look, named in ((a, np.arange(len(JOINTS))), (b, order)):
        if look.doubtful is not None:
            doubtful |= look.doubtful[named]
    return Landmarks(
        a.joints2d + share[:, None] * (b.joints2d[order] - a.joints2d),
        np.where(crossed, a.confidence, (a.confidence + b_conf) / 2),
        a.world + depth_share[:, None] * (b.world[order] - a.world),
        doubtful,
        crossed,
    )


def apart(one: np.ndarray, other: np.ndarray) -> np.ndarray:
    """(16,) bool: the joints two 2D readings (16, 2, the same naming) place more than DOUBT trunks apart."""
    trunk = max(float(np.hypot(*(one[_NECK] - one[_PELVIS]))), 1e-9)
    return np.hypot(*(one - other).T) > DOUBT * trunk


def crossed_joints(one: np.ndarray, other: np.ndarray) -> np.ndarray:
    """(16,) bool: the joints of each limb pair (arms, legs) that two 2D readings (16, 2) place with the sides
    swapped: the pair lies nearer the other reading's with left and right exchanged than as named."""
    crossed = np.zeros(len(JOINTS), bool)
    for limbs in LIMB_PAIRS:
        as_named = np.linalg.norm(one[limbs] - other[limbs], axis=1).sum()
        exchanged = np.linalg.norm(one[limbs] - other[MIRROR_JOINTS[limbs]], axis=1).sum()
        crossed[limbs] = exchanged < as_named
    return crossed


def renamed(landmarks: Landmarks, swap: np.ndarray) -> Landmarks:
    """``landmarks`` with the joints ``swap`` (16,) bool named by the other side (their 2D, confidence, world and
    doubt exchanged with their mirror joints'; a limb pair's joints are swapped together)."""
    order = np.where(swap, MIRROR_JOINTS, np.arange(len(JOINTS)))
    doubtful = None if landmarks.doubtful is None else landmarks.doubtful[order]
    return replace(
        landmarks,
        joints2d=landmarks.joints2d[order],
        confidence=landmarks.confidence[order],
        world=landmarks.world[order],
        doubtful=doubtful,
    )


def disputed(landmarks: Landmarks) -> bool:
    """Whether the two looks named a limb pair the other way round (``crossed``) whose two limbs lie more than DOUBT
    trunk lengths apart: a naming that moves a joint by more than the looks' doubt."""
    if landmarks.crossed is None or not landmarks.crossed.any():
        return False
    return bool((landmarks.crossed & apart(landmarks.joints2d, landmarks.joints2d[MIRROR_JOINTS])).any())
