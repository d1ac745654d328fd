"""What the image panels show of a frame: the video frame with its joint marks, the silhouette with the
fitted model, the tracked joints over the frame (OpenCV), and the decoded frames they are drawn on."""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Iterator

import cv2
import numpy as np

from app.words import joint_label
from mocap.image.draw import LANDMARK_BGR, LEARNED_BGR, draw_landmarks, draw_skeleton, silhouette_view
from mocap.io.video import VideoInfo, iter_frames
from mocap.session import Silhouette

DISPLAY_HEIGHT = 480  # px: smaller frames are shown enlarged to this height
MARK_BGR = (0, 230, 255)  # joint overrides and the joint being placed
UNSIDED_BGR = (90, 200, 90)  # the 2D model before left and right are known
UNSEEN_BGR = (170, 170, 170)  # the legend's line where the person model saw nobody


def display_factor(height: int) -> float:
    """How much an image ``height`` px tall is enlarged for display (up to DISPLAY_HEIGHT), so that
    rings, names and skeleton lines stay thin against the body."""
    return max(1.0, DISPLAY_HEIGHT / height)


def for_display(image: np.ndarray, scale: float) -> tuple[np.ndarray, float]:
    """A copy of ``image`` to draw on and show, enlarged by ``display_factor``, and
    ``scale`` (video pixels to the image's) to draw with."""
    factor = display_factor(image.shape[0])
    if factor == 1.0:
        return image.copy(), scale
    return cv2.resize(image, None, fx=factor, fy=factor, interpolation=cv2.INTER_LINEAR), scale * factor


def caption_image(size: tuple[int, int], text: str) -> np.ndarray:
    """A grey RGB image of ``size`` (width, height), enlarged by ``display_factor``, saying ``text``."""
    factor = display_factor(size[1])
    size = (round(size[0] * factor), round(size[1] * factor))
    image = np.full((size[1], size[0], 3), 60, np.uint8)
    scale = size[1] / 400
    (tw, th), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, 2)
    cv2.putText(
        image,
        text,
        ((size[0] - tw) // 2, (size[1] + th) // 2),
        cv2.FONT_HERSHEY_SIMPLEX,
        scale,
        (230, 230, 230),
        2,
        cv2.LINE_AA,
    )
    return image


def mark_joints(image: np.ndarray, points: dict[str, tuple[float, float]], scale: float) -> np.ndarray:
    """Ring and name each joint of ``points`` (video pixels) on a BGR image at ``scale``."""
    radius = max(4, image.shape[0] // 60)
    for name, (x, y) in points.items():
        centre = (int(round(x * scale)), int(round(y * scale)))
        cv2.circle(image, centre, radius, MARK_BGR, 2, cv2.LINE_AA)
        cv2.putText(
            image,
            joint_label(name),
            (centre[0] + radius + 2, centre[1] - radius),
            cv2.FONT_HERSHEY_SIMPLEX,
            image.shape[0] / 800,
            MARK_BGR,
            1,
            cv2.LINE_AA,
        )
    return image


def video_image(frame_bgr: np.ndarray, marks: dict[str, tuple[float, float]], scale: float) -> np.ndarray:
    """The video frame (RGB, ``for_display``) with the joints of ``marks`` ringed."""
    image, scale = for_display(frame_bgr, scale)
    return cv2.cvtColor(mark_joints(image, marks, scale), cv2.COLOR_BGR2RGB)


def silhouette_image(
    silhouette: Silhouette | None,
    joints2d: np.ndarray | None,
    sides_known: bool,
    overrides: dict[str, tuple[float, float]],
    scale: float,
    size: tuple[int, int],
    landmarks: bool = True,
    eyes: bool = False,
) -> np.ndarray:
    """The silhouette in grey with the fitted model over it (RGB, ``for_display``; ``size``: processed
    (w, h)); limbs in one colour until sides are known. With ``eyes``, the person model's mask-only
    pixels teal, its joints magenta dots (``landmarks``), and a legend."""
    mask = np.zeros((size[1], size[0]), np.uint8)
    learned = None
    if silhouette is not None:
        x0, y0, x1, y1 = silhouette.box
        mask[y0:y1, x0:x1] = silhouette.mask()
        only = silhouette.learned_mask()
        if only is not None:
            learned = np.zeros_like(mask)
            learned[y0:y1, x0:x1] = only
    view, scale = for_display(silhouette_view(mask, None, learned), scale)
    factor = view.shape[0] / size[1]  # processing pixels to the image's
    if joints2d is not None:
        thickness = max(2, view.shape[0] // 240)
        draw_skeleton(view, joints2d * scale, thickness, None if sides_known else UNSIDED_BGR)
    seen = silhouette is not None and silhouette.landmarks is not None
    if landmarks and seen:
        marks = silhouette.landmarks.scaled(factor)
        draw_landmarks(view, marks.joints2d, marks.confidence, max(2.0, view.shape[0] / 160))
    if joints2d is not None:
        mark_joints(view, overrides, scale)
    if eyes and silhouette is not None:
        if not seen:
            legend(view, [("person model saw nobody here", UNSEEN_BGR, None)])
        else:
            legend(
                view,
                [("person model's mask only", LEARNED_BGR, "box")]
                + ([("person model's joints", LANDMARK_BGR, "dot")] if landmarks else []),
            )
    return cv2.cvtColor(view, cv2.COLOR_BGR2RGB)


def legend(image: np.ndarray, entries: list[tuple[str, tuple[int, int, int], str | None]]) -> np.ndarray:
    """Lines of (text, BGR colour, swatch: "box", "dot" or None) at the image's top
    left, each text in its colour outlined in black (drawn in place, returned)."""
    font = image.shape[0] / 700
    line = max(12, round(image.shape[0] / 28))
    for k, (text, colour, swatch) in enumerate(entries):
        y = line * (k + 1)
        x = round(line * 0.4)
        if swatch == "box":
            cv2.rectangle(image, (x, y - line * 2 // 3), (x + line * 2 // 3, y), colour, -1)
        elif swatch == "dot":
            cv2.circle(image, (x + line // 3, y - line // 3), max(2, line // 5), colour, -1, cv2.LINE_AA)
        x += line if swatch else 0
        cv2.putText(image, text, (x, y), cv2.FONT_HERSHEY_SIMPLEX, font, (0, 0, 0), 3, cv2.LINE_AA)
        cv2.putText(image, text, (x, y), cv2.FONT_HERSHEY_SIMPLEX, font, colour, 1, cv2.LINE_AA)
    return image


def tracked_image(
    frame_bgr: np.ndarray, joints2d: np.ndarray, overrides: dict[str, tuple[float, float]], scale: float
) -> np.ndarray:
    """The video frame dimmed, the tracked joints (anatomical sides) over it (RGB, ``for_display``)."""
    view, scale = for_display((frame_bgr * 0.55).astype(np.uint8), scale)
    draw_skeleton(view, joints2d * scale, max(2, view.shape[0] // 240))
    return cv2.cvtColor(mark_joints(view, overrides, scale), cv2.COLOR_BGR2RGB)


class FrameCache:
    """Recent decoded video frames at the processing scale; the frame after the last read is decoded
    on rather than sought (a seek decodes from the keyframe before it)."""

    def __init__(self, info: VideoInfo, scale: float, size: int = 48):
        self.info, self.scale, self.size = info, scale, size
        self._frames: OrderedDict[int, np.ndarray] = OrderedDict()
        self._lock = threading.Lock()
        self._reader: Iterator[tuple[int, np.ndarray]] | None = None
        self._next = -1  # the frame the reader decodes next

    def get(self, index: int) -> np.ndarray:
        with self._lock:
            if index not in self._frames:
                self._frames[index] = self._read(index)
                if len(self._frames) > self.size:
                    self._frames.popitem(last=False)
            self._frames.move_to_end(index)
            return self._frames[index]

    def _read(self, index: int) -> np.ndarray:
        if index != self._next or self._reader is None:
            self._reader = iter_frames(self.info, start=index, scale=self.scale)
        self._next = index + 1
        return next(self._reader)[1]
