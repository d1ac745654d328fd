"""The app's background work: the silhouette method's two passes over the video
(``mocap.pipeline``) from the start, and the tracking once frame 0 is marked. Each
frame's silhouette and fit are kept as they come (the pipeline's Progress carries
them), so the page shows them at once; the page hears at each whole percent."""

from __future__ import annotations

import sys
import threading
import traceback
from dataclasses import replace
from typing import Callable

from mocap.errors import MocapError
from mocap.pipeline import FITTING, SILHOUETTES, TRACKING, Progress, open_session
from mocap.session import Annotations, check_tracking_marks, marks_of


class Throttle:
    """Passes (done, stage) on at each whole percent of ``total`` and at a new stage."""

    def __init__(self, report: Callable[[int, str], None], total: int):
        self.report, self.total, self.last = report, max(total, 1), (-1, "")

    def __call__(self, done: int, stage: str) -> None:
        key = (100 * done // self.total, stage)
        if key != self.last:
            self.last = key
            self.report(done, stage)


class Preprocessing:
    """AppState's background runs (a mixin: the state's lock, video, sessions, progress)."""

    def start(self, progress: Callable[[int, int], None] | None = None) -> threading.Thread:
        """Preprocess in a daemon thread; ``progress(done, total)`` reports each step.
        With the tracking method chosen and frame 0 marked, tracking starts too."""
        thread = threading.Thread(target=self._preprocess, args=(progress,), daemon=True,
                                  name="mocap-preprocess")
        thread.start()
        if self.method == "track":
            try:
                self.start_tracking()
            except MocapError:
                pass    # the marks are not complete: the page says what is missing
        return thread

    def _preprocess(self, progress: Callable[[int, int], None] | None) -> None:
        try:
            self._run_passes(progress or (lambda done, total: None))
        except MocapError as exc:
            self._fail(str(exc))
        except Exception as exc:  # the page must say so; the terminal gets the traceback
            traceback.print_exc(file=sys.stderr)
            self._fail(f"preprocessing failed: {exc!r}")
        finally:
            self.ready.set()

    def _run_passes(self, progress: Callable[[int, int], None]) -> None:
        report = Throttle(self._step, 2 * self.n_frames)

        def step(p: Progress) -> None:
            with self._lock:
                if p.stage == SILHOUETTES:
                    self._silhouettes[p.frame], self._silhouettes_done = p.product, p.frame + 1
                elif p.stage == FITTING:
                    self._fits[p.frame] = p.product
            progress(p.done, p.total)
            report(p.done, p.stage)

        session = open_session(self.info, self._annotations, method="silhouette", progress=step)
        with self._lock:
            session.annotate(self._annotations)     # edits made while fitting
            self._fitted = session
            self._progress = Progress(2 * self.n_frames, 2 * self.n_frames, "ready")
        self._changed()

    def _step(self, done: int, stage: str) -> None:
        with self._lock:
            self._progress = Progress(min(done, self._progress.total - 1), self._progress.total, stage)
        self._changed()

    def _fail(self, message: str) -> None:
        with self._lock:
            self._progress = replace(self._progress, stage="stopped", error=message)
        self._changed()

    def start_tracking(self) -> threading.Thread:
        """Track from frame 0's marks in a daemon thread. Refused at once (a
        MocapError naming the joint) while a mark is missing or outside the frame, or
        when the shoulders, chest and hips fit no view of a trunk."""
        with self._lock:
            if self._tracking:
                raise MocapError("already tracking; wait for it to finish")
            notes = self._annotations
            check_tracking_marks(self.info, notes)
            self._tracking = True
            self._track_progress = Progress(0, self.n_frames, TRACKING)
        thread = threading.Thread(target=self._track, args=(notes,), daemon=True, name="mocap-track")
        thread.start()
        self._changed()
        return thread

    def _track(self, notes: Annotations) -> None:
        report = Throttle(lambda done, stage: self._track_step(done), self.n_frames)
        try:
            session = open_session(self.info, notes, method="track",
                                   progress=lambda p: report(p.done, "tracking"))
            session.inputs      # the 3D, before the lock
            with self._lock:
                if self._annotations != notes:      # edits made while tracking
                    session.annotate(self._annotations)
                self._tracked, self._tracked_from = session, marks_of(notes)
                self._track_progress = Progress(self.n_frames, self.n_frames, "tracked")
        except Exception as exc:  # the page must say so; the terminal gets the traceback
            if not isinstance(exc, MocapError):
                traceback.print_exc(file=sys.stderr)
            with self._lock:
                self._track_progress = replace(self._track_progress, stage="stopped",
                                               error=f"tracking failed: {exc}")
        finally:
            with self._lock:
                self._tracking = False
            self._changed()

    def _track_step(self, done: int) -> None:
        with self._lock:
            self._track_progress = Progress(min(done, self.n_frames - 1), self.n_frames, TRACKING)
        self._changed()
