"""A second look at a performer the person model does not find on the whole frame: the silhouette's box cut out
and the scene around the silhouette greyed, so that the model sees one figure on a plain ground. A
learned model misses a small figure or one over a busy scene (a body bent over among a photo's shapes); the
silhouette method's background subtraction finds it there, and the model then names its joints."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import cv2
import numpy as np

from mocap.person.mirrored import crossed_joints, mean_landmarks, renamed
from mocap.person.views import Landmarks, PersonModel

SIDE = 256  # pixels of the square the figure is shown in
REACH = 2.0  # the square's side in the silhouette box's longer sides: the figure with room around it
GREY = 128  # the level the scene is greyed to


class IsolatedLook:
    """A person model shown isolated figures (``landmarks``): opened by ``opening(with_mirror)`` when first needed
    each way, looking at them once or also at their mirror images (person.mirrored); None: no model, no look."""

    def __init__(self, opening: Callable[[bool], PersonModel] | None):
        self._opening = opening
        self._models: dict[bool, PersonModel] = {}

    @property
    def able(self) -> bool:
        return self._opening is not None

    def landmarks(self, frame: np.ndarray, silhouette: np.ndarray, with_mirror: bool = True) -> Landmarks | None:
        """The model's landmarks of the figure the ``silhouette`` (uint8, nonzero inside) outlines in the BGR
        ``frame``, in the frame's pixels; None where it finds nobody there or the silhouette is empty. (Its mask
        of the figure is not asked for: the silhouette is the figure's outline.)"""
        placing = placed(silhouette)
        if placing is None:
            return None
        if with_mirror not in self._models:
            self._models[with_mirror] = self._opening(with_mirror)
        seen = self._models[with_mirror].observe(isolated(frame, silhouette, placing))
        return None if seen is None else in_frame(seen.landmarks, placing)

    def second_opinion(self, landmarks: Landmarks, frame: np.ndarray, silhouette: np.ndarray) -> Landmarks:
        """``landmarks`` with this look at the figure the ``silhouette`` outlines as a third opinion: each limb pair
        the model's two looks (person.mirrored) named the other way round (``crossed``) named as this look names
        it, the majority's, then the two averaged (person.mirrored.mean_landmarks); as given without a model or
        where this look finds nobody. For a look that followed the body backward (person.steady), which follows
        one it could not have found, and for the limb pairs whose sides the frame's own look and its mirror
        image's dispute."""
        cut_out = self.landmarks(frame, silhouette, with_mirror=False) if self.able else None
        if cut_out is None:
            return landmarks
        if landmarks.crossed is not None:
            landmarks = renamed(landmarks, landmarks.crossed & crossed_joints(landmarks.joints2d, cut_out.joints2d))
        return mean_landmarks(landmarks, cut_out)

    def close(self) -> None:
        for model in self._models.values():
            model.close()


def placed(silhouette: np.ndarray) -> np.ndarray | None:
    """(2, 3) the affine map of frame pixels onto the SIDE square centred on the silhouette's box, REACH times
    its longer side; None for an empty silhouette."""
    x, y, w, h = cv2.boundingRect((silhouette > 0).astype(np.uint8))
    if w == 0 or h == 0:
        return None
    scale = SIDE / (REACH * max(w, h))
    centre = np.array([x + (w - 1) / 2, y + (h - 1) / 2])
    middle = (SIDE - 1) / 2  # pixel centres
    return np.array([[scale, 0.0, middle - scale * centre[0]], [0.0, scale, middle - scale * centre[1]]])


def isolated(frame: np.ndarray, silhouette: np.ndarray, placing: np.ndarray) -> np.ndarray:
    """The SIDE square ``placing`` maps the frame onto, the scene outside the silhouette greyed. (Not even a band
    of the scene around it: the model takes a rim of it for limbs.)"""
    shown = np.where(silhouette[..., None] > 0, frame, np.uint8(GREY))
    return cv2.warpAffine(shown, placing, (SIDE, SIDE), flags=cv2.INTER_LINEAR, borderValue=(GREY,) * 3)


def in_frame(landmarks: Landmarks, placing: np.ndarray) -> Landmarks:
    """Landmarks seen on the square ``placing`` made, in the frame's pixels."""
    back = cv2.invertAffineTransform(placing)
    return replace(landmarks, joints2d=landmarks.joints2d @ back[:, :2].T + back[:, 2])
