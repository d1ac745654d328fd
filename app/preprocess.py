"""The app's background work: the silhouette passes (``mocap.pipeline``, streamed together) from the
start, the tracking once frame 0 is marked. Each frame's silhouette and fit is shown as it comes; a
new person model (mocap.person) or empty stage fits the clip again."""

from __future__ import annotations

import os
import re
import sys
import threading
import traceback
from collections.abc import Callable
from dataclasses import replace

from app.edits import placed
from mocap.errors import MocapError
from mocap.io.annotations import Annotations
from mocap.person import NONE, available, check_name, install_hint
from mocap.pipeline import FITTING, SILHOUETTES, TRACKING, Progress, open_session
from mocap.session import check_tracking_marks, remarks_of


class Throttle:
    """Passes (done, stage) on at each whole percent of ``total`` and at a new stage."""

    def __init__(self, report: Callable[[int, str], None], total: int):
        self.report, self.total, self.last = report, max(total, 1), (-1, "")

    def __call__(self, done: int, stage: str) -> bool:
        """Whether it passed this step on."""
        key = (100 * done // self.total, stage)
        if key == self.last:
            return False
        self.last = key
        self.report(done, stage)
        return True


def stage_of(text: str, n_frames: int) -> str | tuple[int, int] | None:
    """The empty stage typed: (A, B) for frames "A-B", a file name (beside the annotation file), or
    None for nothing (estimated from the clip)."""
    text = text.strip()
    frames = re.fullmatch(r"(\d+)\s*(?:-|\.\.)\s*(\d+)", text)
    if not frames:
        return text or None
    first, last = int(frames.group(1)), int(frames.group(2))
    if not first <= last < n_frames:
        raise MocapError(f"frames {first}-{last} are not a range within the video's {n_frames} frames")
    return first, last


class Preprocessing:
    """AppState's background runs (a mixin: the state's lock, video, sessions, progress)."""

    def start(self, progress: Callable[[int, int], None] | None = None) -> threading.Thread:
        """Preprocess in a daemon thread; ``progress(done, total)`` reports each step.
        With the tracking method chosen and frame 0 marked (or unmarked with a person model: ``tracks_unmarked``),
        tracking starts too."""
        thread = threading.Thread(target=self._preprocess, args=(progress,), daemon=True, name="mocap-preprocess")
        thread.start()
        if self.method == "track":
            try:
                self.start_tracking()
            except MocapError:
                pass  # the marks are not complete: the page says what is missing
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
            self._changed()  # what waits for it (the learned eyes' switch) is offered again

    def _run_passes(self, progress: Callable[[int, int], None]) -> None:
        report = Throttle(self._step, 2 * self.n_frames)

        def step(p: Progress) -> None:
            with self._lock:
                if p.stage == SILHOUETTES:
                    self._silhouettes[p.frame], self._silhouettes_done = p.product, p.frame + 1
                elif p.stage == FITTING and (p.final or self._fits[p.frame] is None):
                    self._fits[p.frame] = p.product  # a first look until the legs are chosen
                # the passes run together: the page names the silhouettes' until all are in
                stage = SILHOUETTES if self._silhouettes_done < self.n_frames else FITTING
                shown = p.frame == self._frame
            progress(p.done, p.total)
            if not report(p.done, stage) and shown:
                self._changed()  # the frame on the page has its silhouette or fit now

        with self._lock:
            notes, person = self._annotations, self._person
        session = open_session(
            self.info,
            notes,
            method="silhouette",
            progress=step,
            background=notes.background_source(self.path),
            person=person,
            focal=self.focal,
        )
        with self._lock:
            session.annotate(self._annotations)  # edits made while fitting
            self._fitted = session
            self._propose_keyframes(session)
            self._progress = Progress(2 * self.n_frames, 2 * self.n_frames, "ready")
        self._changed()

    def set_background(self, text: str) -> None:
        """Use the empty stage the user names (``stage_of``), saved in the annotations, and refit.
        Refused while fitting, and for frames or estimate already in use (a file may have changed)."""
        background = stage_of(text, self.n_frames)
        with self._lock:
            if not self.ready.is_set():
                raise MocapError("the fit is still running: set the empty stage when it is done")
            if background == self._annotations.background and not isinstance(background, str):
                used = "estimated from the clip" if background is None else "frames {}-{}".format(*background)
                raise MocapError(f"the empty stage is already {used}: nothing to refit")
            notes = self._annotations.with_background(background)
            source = notes.background_source(self.path)
            if isinstance(source, str) and not os.path.isfile(source):
                raise MocapError(f"{source}: no such photo or video of the empty stage")
            self._apply(notes)
            self._forget_fit()
        self._changed()
        self.start()

    def set_person_model(self, name: str) -> None:
        """Refit looking through the person model ``name`` ("none": silhouettes alone, the paper's path).
        Refused while fitting, for the one in use, and when not installed (saying how to install)."""
        check_name(name)
        with self._lock:
            if not self.ready.is_set():
                raise MocapError("the fit is still running: switch the learned eyes when it is done")
            if name == self._person:
                used = "the silhouettes alone" if name == NONE else f"the person model {name!r}"
                raise MocapError(f"the fit already looks through {used}: nothing to refit")
            if not available(name):
                raise MocapError(install_hint(name))
            self._person = name
            self._forget_fit()
        self._changed()
        self.start()

    def _forget_fit(self) -> None:
        """(Under the lock) drop the silhouettes and fits before the passes run again."""
        n = self.n_frames
        self._silhouettes, self._silhouettes_done, self._fits = [None] * n, 0, [None] * n
        self._fitted, self._progress = None, Progress(0, 2 * n, "waiting")
        self.ready.clear()

    @property
    def person_model(self) -> str:
        """The person model the silhouette method looks through ("none": the silhouettes alone)."""
        return self._person

    def eyes_seen(self) -> tuple[int, int, int]:
        """(frames where the person model saw somebody, those of them where only the figure cut out from the
        scene, frames whose silhouette is in)."""
        with self._lock:
            done = self._silhouettes_done
            seen = [s for s in self._silhouettes[:done] if s is not None and s.landmarks is not None]
            return len(seen), sum(s.cut_out for s in seen), done

    @property
    def background_warning(self) -> str | None:
        """The fit's warning when the background holds the performer (else None)."""
        with self._lock:
            return None if self._fitted is None else self._fitted.background_warning

    def _step(self, done: int, stage: str) -> None:
        with self._lock:
            self._progress = Progress(min(done, self._progress.total - 1), self._progress.total, stage)
        self._changed()

    def _fail(self, message: str) -> None:
        with self._lock:
            self._progress = replace(self._progress, stage="stopped", error=message)
        self._changed()

    def start_tracking(self) -> threading.Thread:
        """Track from frame 0's marks (none: the person model's, ``tracks_unmarked``) in a daemon thread; a
        MocapError naming the joint at once if a mark is missing or outside the frame, or the trunk fits no view."""
        with self._lock:
            if self._tracking:
                raise MocapError("already tracking; wait for it to finish")
            notes = self._annotations
            if not self.tracks_unmarked:
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
            session = open_session(
                self.info, notes, method="track", progress=lambda p: report(p.done, "tracking"), person=self._person
            )
            session.inputs  # noqa: B018 (the 3D worked out before the lock)
            with self._lock:
                if self._annotations != notes:  # edits made while tracking
                    session.annotate(self._annotations)
                self._tracked, self._tracked_from = session, (placed(notes, 0), remarks_of(notes))
                self._track_progress = Progress(self.n_frames, self.n_frames, "tracked")
        except Exception as exc:  # the page must say so; the terminal gets the traceback
            if not isinstance(exc, MocapError):
                traceback.print_exc(file=sys.stderr)
            with self._lock:
                self._track_progress = replace(self._track_progress, stage="stopped", error=f"tracking failed: {exc}")
        finally:
            with self._lock:
                self._tracking = False
            self._changed()

    def _track_step(self, done: int) -> None:
        with self._lock:
            self._track_progress = Progress(min(done, self.n_frames - 1), self.n_frames, TRACKING)
        self._changed()
