"""Playback's pictures. The page replaces an image's texture only once its new picture is decoded, and
a newer picture cancels that: one image per panel changed every frame shows no new picture while
playing. So each image panel has a reel of hidden image slots, each loaded a little ahead of the clock
with a frame to come; when its frame is shown the slot is made visible, in the same update as the
frame's 3D pose, its picture long decoded."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable

import numpy as np

from app.views import caption_image

LEAD_S = 0.15  # a picture sent this long ago is taken as decoded by the page
AHEAD_S = 0.4  # how far ahead of the clock the reel is loaded
LATE = 2  # frames a frame shown may trail the clock, where the next is not decoded yet


class Reel:
    """Hidden image slots on the video and silhouette panels (``SceneView.add_image``); frame k
    goes to slot k % slots."""

    def __init__(self, view, scene, fps: float, n_frames: int):
        self.view, self.n_frames, self.fps = view, n_frames, fps
        self.slots = max(4, math.ceil(AHEAD_S * fps)) + LATE + 1
        blank = caption_image(view.size, "")
        self.images = [
            [view.add_image(scene, f"/{panel}/reel/{k}", blank, visible=False) for k in range(self.slots)]
            for panel in ("video", "silhouette")
        ]
        self._held: list[tuple[int, object, float] | None] = [None] * self.slots  # (frame, key, sent)
        self._shown: int | None = None  # the slot on view
        self._lock = threading.Lock()
        self.key: object = None  # what the pictures depend on beside the frame (edits, marks)

    @property
    def shown_frame(self) -> int | None:
        """The frame whose slot is on view (None: the panels' own images are)."""
        held = None if self._shown is None else self._held[self._shown]
        return None if held is None else held[0]

    def ready(self, frame: int) -> bool:
        """Whether ``frame``'s pictures were sent at least LEAD_S ago, for what is shown now."""
        held = self._held[frame % self.slots]
        return held is not None and held[:2] == (frame, self.key) and time.monotonic() - held[2] >= LEAD_S

    def latest_ready(self, frame: int) -> int:
        """``frame`` if ready, else the latest of the LATE before it that is; else ``frame``."""
        return next((f for f in range(frame, max(frame - LATE, 0) - 1, -1) if self.ready(f)), frame)

    def load_ahead(self, frame: int, until: float, pictures: Callable[[int], tuple[np.ndarray, np.ndarray]]) -> None:
        """Load frames after ``frame`` not yet held until the monotonic time ``until`` (at least one,
        never into the slot on view): first those still LEAD_S or more ahead, which can be ready in
        time, nearest first; ``pictures(k)``: frame k's video and silhouette images."""
        soon = frame + 1 + math.ceil(LEAD_S * self.fps)
        ahead = range(frame + 1, min(frame + self.slots - LATE, self.n_frames))
        loaded = False
        for k in sorted(ahead, key=lambda k: (k < soon, k)):
            slot = k % self.slots
            held = self._held[slot]
            if held is not None and held[:2] == (k, self.key) or slot == self._shown:
                continue
            if loaded and time.monotonic() >= until:
                return
            key, images = self.key, pictures(k)
            with self._lock:
                for panel, image in zip(self.images, images):
                    panel[slot].image = image
                self._held[slot] = (k, key, time.monotonic())
            loaded = True

    def show(self, frame: int | None, keep: bool = False) -> bool:
        """Put ``frame``'s slot on view if ready (True); else the panels' own images (None: those), or
        with ``keep`` the slot on view stays (playing: a frame not ready keeps the last one)."""
        with self._lock:
            slot = frame % self.slots if frame is not None and self.ready(frame) else None
            if slot is None and keep:
                return False
            if slot != self._shown:
                for panel, still in zip(self.images, (self.view.video, self.view.silhouette)):
                    if slot is not None:
                        panel[slot].visible = True
                    if self._shown is not None:
                        panel[self._shown].visible = False
                    still.visible = slot is None
                self._shown = slot
            return slot is not None
