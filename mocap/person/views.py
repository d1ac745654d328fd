"""What a person model sees (``PersonView``: a mask and ``Landmarks``) and the interface a model keeps
(``PersonModel``), apart from the registry that opens one (mocap.person)."""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass, replace
from typing import Protocol

import numpy as np

from mocap.io.video import rescaled


@dataclass(frozen=True)
class Landmarks:
    """A person model's 16 contract joints on one frame, sides anatomical: ``joints2d`` (16, 2) pixels of the
    frame given; ``confidence`` (16,) in [0, 1], that the joint is where it says (visible or not); ``world`` (16,
    3) metres, pelvis at the origin, x image-right, y up, z toward the camera (CONTRACT.md's 3D); ``doubtful``
    (16,) bool, joints the model's two looks place apart, ``crossed`` (16,) bool, those of the limb pairs the two
    name the other way round (person.mirrored; None: looked at once)."""

    joints2d: np.ndarray
    confidence: np.ndarray
    world: np.ndarray
    doubtful: np.ndarray | None = None
    crossed: np.ndarray | None = None

    def scaled(self, factor: float) -> "Landmarks":
        """The same landmarks with the 2D in pixels of a frame ``factor`` times as large."""
        return replace(self, joints2d=rescaled(self.joints2d, factor))


@dataclass(frozen=True)
class PersonView:
    """What a person model sees on a frame: ``mask`` (H, W) float32 performer probabilities (None from a model
    opened unmasked), ``landmarks``; ``looked_back``: seen by a model following the body backward from where it
    was found (person.steady)."""

    mask: np.ndarray | None
    landmarks: Landmarks
    looked_back: bool = False


class PersonModel(Protocol):
    """A person model over one video: ``observe`` each BGR uint8 frame in order (None: nobody seen); ``filtered``
    and ``with_mirror`` as opened (``open_person_model``)."""

    name: str
    filtered: bool
    with_mirror: bool

    def observe(self, frame: np.ndarray) -> PersonView | None: ...

    def close(self) -> None: ...


def watched(model: PersonModel | None, frames: Iterable[np.ndarray]) -> Iterator[tuple[np.ndarray, PersonView | None]]:
    """Each frame with the ``model``'s view of it (None: nobody, or no model); a model that can look ahead
    (``watch``) is sent frames before their views are awaited."""
    if model is None:
        yield from ((frame, None) for frame in frames)
    elif hasattr(model, "watch"):
        yield from model.watch(frames)
    else:
        yield from ((frame, model.observe(frame)) for frame in frames)
