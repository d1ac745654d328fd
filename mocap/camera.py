"""The camera both methods read: a pinhole with its focal length and principal point in
pixels (the tracking method's perspective; the silhouette method's root depth)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# The pinhole's axes (x right, y down, z away from the camera) against CONTRACT.md's (x right, y up, z toward
# the camera): a point's coordinates times FLIP_YZ are the other frame's, either way.
FLIP_YZ = np.array([1.0, -1.0, -1.0])
FULL_FRAME_DIAGONAL_MM = float(np.hypot(36.0, 24.0))  # a 35 mm film frame's: what "35 mm equivalent" refers to


@dataclass(frozen=True)
class Pinhole:
    """The camera: focal length and principal point in pixels."""

    focal: float
    cx: float
    cy: float

    def rays(self, pixels: np.ndarray) -> np.ndarray:
        """(..., 3) viewing rays (x, y, 1) of pixels (..., 2): the point at depth Z is Z times the ray (Eq. 10)."""
        p = np.asarray(pixels, float)
        return np.stack(
            [(p[..., 0] - self.cx) / self.focal, (p[..., 1] - self.cy) / self.focal, np.ones(p.shape[:-1])], axis=-1
        )

    def project(self, points: np.ndarray) -> np.ndarray:
        """(..., 2) pixels of pinhole-frame points (..., 3)."""
        z = points[..., 2:3]
        return np.array([self.cx, self.cy]) + self.focal * points[..., :2] / z

    def scaled(self, factor: float) -> "Pinhole":
        """The camera of the frames resized by ``factor``."""
        return Pinhole(self.focal * factor, self.cx * factor, self.cy * factor)


@dataclass(frozen=True)
class Focal:
    """A camera's focal length as the user gives it (`--focal`): ``value`` pixels of the video, or with
    ``equivalent`` the lens's 35 mm-equivalent millimetres, which phones and cameras print (a phone's main
    camera: about 26 mm)."""

    value: float
    equivalent: bool = False

    @classmethod
    def parse(cls, text: str) -> "Focal":
        """``"1390"`` (pixels) or ``"26mm"`` (35 mm equivalent); a ValueError saying what is wrong otherwise."""
        number = text.strip().lower()
        equivalent = number.endswith("mm")
        try:
            value = float(number[:-2] if equivalent else number)
        except ValueError:
            raise ValueError(
                f"expected pixels (e.g. 1390) or a 35 mm-equivalent length (e.g. 26mm), got {text!r}"
            ) from None
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"a focal length is a number above 0, got {text!r}")
        return cls(value, equivalent)

    def pixels(self, width: int, height: int) -> float:
        """In pixels of a ``width`` x ``height`` video: a 35 mm-equivalent length is over a 35 mm frame's diagonal
        what the focal length in pixels is over the video's."""
        return self.value * float(np.hypot(width, height)) / FULL_FRAME_DIAGONAL_MM if self.equivalent else self.value


def default_camera(width: int, height: int, focal_px: float | None = None) -> Pinhole:
    """The assumed camera of a video: ``focal_px`` or the frame's width, centred."""
    return Pinhole(float(focal_px or width), width / 2.0, height / 2.0)
