"""Play: moves the state's current frame at the video's frame rate (``AppState.go_to``), so every tab
shows what stepping would. Paced by the wall clock (a late tick skips frames); moving the frame plays
on from there; playing stops at the last frame (Play there restarts from the first). Between ticks the
frames to come are prepared (``ahead``), and each tick shows the frame ``pick`` gives for the clock's."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

import numpy as np

from app.state import AppState


class Player:
    """Plays ``state`` in a thread; ``refresh(force)`` redraws the page when playing starts or stops;
    ``pick(frame)``: the frame to show when the clock says ``frame``; ``ahead(frame, until)``: prepare
    the frames after ``frame`` until the monotonic time ``until``."""

    def __init__(
        self,
        state: AppState,
        refresh: Callable[[bool], None],
        pick: Callable[[int], int],
        ahead: Callable[[int, float], None],
    ):
        self.state, self._refresh, self._pick, self._ahead = state, refresh, pick, ahead
        self._lock = threading.Lock()  # start and stop come from any tab's callback thread
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._playing = False
        self._animation: tuple[tuple, np.ndarray] | None = None  # (state.made_from, joints3d)

    @property
    def playing(self) -> bool:
        return self._playing

    def toggle(self) -> None:
        with self._lock:
            if self._playing:
                self._halt()
            else:
                self._start()
        self._refresh(True)

    def stop(self) -> None:
        """Stop playing (the current frame stays where playing got to)."""
        with self._lock:
            self._halt()
        self._refresh(True)

    def pose(self, frame: int) -> np.ndarray | None:
        """The animation's (16, 3) joints on ``frame``, made again after an edit."""
        made = self.state.made_from
        if self._animation is None or any(a is not b for a, b in zip(self._animation[0], made)):
            self._animation = (made, self.state.animation()[0])
        joints = self._animation[1][frame]
        return None if not np.isfinite(joints).all() else joints

    def _start(self) -> None:
        self.pose(self.state.frame)  # refused (MocapError) before every frame is fitted
        if self.state.frame >= self.state.n_frames - 1:
            self.state.go_to(0)
        self._stop.clear()
        self._playing = True
        self._thread = threading.Thread(target=self._run, daemon=True, name="mocap-player")
        self._thread.start()

    def _halt(self) -> None:
        self._stop.set()
        thread, self._thread = self._thread, None
        if thread is not None and thread is not threading.current_thread():
            thread.join()
        self._playing = False

    def _run(self) -> None:
        state, period = self.state, 1.0 / self.state.info.fps
        start, origin = time.monotonic(), state.frame
        shown = origin
        while True:
            if state.frame != shown:  # the user moved the frame: play on from there
                start, origin = time.monotonic(), state.frame
            frame = origin + int((time.monotonic() - start) / period)
            if not state.ready.is_set():  # fitting again (a new empty stage): no animation
                break
            if frame >= state.n_frames:
                state.go_to(state.n_frames - 1)
                break
            shown = self._pick(frame)
            state.go_to(shown)
            tick = start + (frame + 1 - origin) * period
            self._ahead(frame, tick)
            if self._stop.wait(max(tick - time.monotonic(), 0.0)):
                return
        # not under the lock: a Pause holding it may be joining this thread right now
        if not self._stop.is_set():
            self._playing = False
        self._refresh(True)
