"""The app's one truth: a video's session, the user's annotations, their undo history.

Every browser tab and every callback thread goes through one ``AppState``; a
re-entrant lock guards it, so concurrent clicks apply one after the other. An edit
is saved atomically to the annotation file beside the video *before* it is applied
and shown, so a page never shows an edit that a crash could lose. Preprocessing runs
in a background thread (``start``); each frame's silhouette and fit can be looked at
as soon as it exists, the 3D lifting once every frame is fitted.

The annotations' method chooses what the page shows and exports: the silhouette
method's session, or the tracking method's (mocap.session.tracking), tracked in a
background thread (``start_tracking``) from the 16 joints marked on frame 0, which
are frame 0's joint overrides. Both sessions take every edit.
"""

from __future__ import annotations

import os
import sys
import threading
import traceback
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np

from app.preprocess import Throttle
from mocap.review import Doubt, covering, review_queue
from mocap.io.annotations import Annotations, FrameNote, load_annotations, save_annotations
from mocap.body import JOINTS, SEGMENT_INDEX, SEGMENT_NAMES
from mocap.errors import MocapError
from mocap.lift.taylor import depth_fractions
from mocap.track.marks import check_marks, shoulders_as_hips
from mocap.lift.motion import Motion
from mocap.track.perspective import calibrate, default_camera
from mocap.pipeline import FITTING, SILHOUETTES, Progress, open_session
from mocap.session import Session, SilhouetteSession, TrackSession, marks_of
from mocap.silhouette.passes import FrameFit, Silhouette
from mocap.track.tracking import carried_pins, turn_of
from mocap.io.video import open_video, processing_scale

Change = Callable[[Annotations], Annotations]


def annotations_path(video: str | os.PathLike) -> Path:
    """Where a video's annotations live: beside it, VIDEO.annotations.json."""
    return Path(video).with_suffix(".annotations.json")


def toggled_keyframe(notes: Annotations, frame: int, n_frames: int) -> Annotations:
    """The annotations with ``frame`` marked as a keyframe or unmarked; all frames
    marked is written as no list (the contract's default)."""
    keys = set(notes.keyframe_indices(n_frames)) ^ {frame}
    if not keys:
        raise MocapError("the last keyframe cannot be unmarked: the animation needs one")
    return replace(notes, keyframes=None if len(keys) == n_frames else tuple(sorted(keys)))


def entry_frame(notes: Annotations, frame: int, has: Callable) -> int | None:
    """The latest frame at or before ``frame`` whose note satisfies ``has`` (sticky entries)."""
    return max((k for k, note in notes.frames.items() if k <= frame and has(note)), default=None)


def sign_note(notes: Annotations, frame: int, segment: str, sign: int) -> str:
    """Where a segment's sign on ``frame`` comes from: the user's latest entry while
    it holds (it lapses where the segment passes through the image plane), else the guess."""
    entry = entry_frame(notes, frame, lambda n: segment in n.foreshortening)
    if entry is None or (notes.frames[entry].foreshortening[segment] == "toward") != (sign > 0):
        return "guessed"
    return source_note(entry, frame)


def source_note(entry: int | None, frame: int) -> str:
    """Where a sticky value of ``frame`` comes from, for the page."""
    if entry is None:
        return "guessed"
    return "set here" if entry == frame else f"held from frame {entry}"


def shown_orientation(notes: Annotations, frame: int, used: str, method: str) -> tuple[str, str]:
    """The orientation the page shows on ``frame`` and where it comes from. The
    silhouette method uses the user's held entry (``used``); the tracking method's 3D
    shows its own facing (``used``), turned to the side of the user's held entry: on
    the entry's own frame the page shows the entry."""
    if method != "track":
        return used, source_note(entry_frame(notes, frame, lambda n: n.orientation), frame)
    own = notes.frames[frame].orientation if frame in notes.frames else None
    return (own, "set here") if own is not None else (used, "seen in the tracked 3D")


@dataclass(frozen=True, eq=False)
class FrameView:
    """Everything the page shows of one frame, read at one moment from one state."""

    index: int
    n_frames: int
    version: int
    progress: Progress
    silhouette: Silhouette | None       # processing pixels; None: none yet or nobody
    silhouette_ready: bool
    fitted: bool                        # the 2D fit of this frame exists
    overrides: dict[str, tuple[float, float]]
    keyframe: bool
    joints2d: np.ndarray | None = None  # (16, 2) video pixels; anatomical when sides_known
    sides_known: bool = False
    score: float | None = None
    pose3d: np.ndarray | None = None    # (16, 3) metres, contract frame
    signs: tuple[int, ...] | None = None    # +1 toward, -1 away, per SEGMENT_NAMES
    sign_notes: tuple[str, ...] = ()    # where each sign comes from (source_note)
    depths: tuple[float, ...] = ()      # |dZ| / length per segment (0: in the image plane)
    orientation: str | None = None
    orientation_note: str = ""
    doubts: tuple[str, ...] = ()
    method: str = "silhouette"          # whose joints and 3D these are ("track": tracking's)
    carried: dict[str, int] = field(default_factory=dict)   # joint -> frame of the pin moving it


@dataclass
class _History:
    """Undo and redo stacks of (annotations before, annotations after, frame)."""

    undo: list[tuple[Annotations, Annotations, int]] = field(default_factory=list)
    redo: list[tuple[Annotations, Annotations, int]] = field(default_factory=list)


class AppState:
    """A video, its preprocessing, its session and annotations, the current frame."""

    def __init__(self, video: str | os.PathLike, annotations: str | os.PathLike | None = None):
        self.info = open_video(video)
        self.scale = processing_scale(self.info)
        self.path = Path(annotations) if annotations else annotations_path(video)
        n = self.info.frame_count
        self._annotations = load_annotations(self.path, n) if self.path.exists() else Annotations()
        self._lock = threading.RLock()
        self._silhouettes: list[Silhouette | None] = [None] * n
        self._silhouettes_done = 0
        self._fits: list[FrameFit | None] = [None] * n
        self._progress = Progress(0, 2 * n, "waiting")
        self._fitted: SilhouetteSession | None = None    # the silhouette method's
        self._tracked: TrackSession | None = None    # the tracking method's, once tracked
        self._tracked_from: dict | None = None       # the marks it was tracked from
        self._track_progress = Progress(0, n, "waiting for the 16 marks on frame 0")
        self._tracking = False
        self._queue: list[Doubt] | None = None
        self._history = _History()
        self._frame = 0
        self._reviewed: int | None = None      # the frame next_doubtful returned last
        self._version = 0
        self._listeners: list[Callable[[], None]] = []
        self.ready = threading.Event()

    @property
    def n_frames(self) -> int:
        return self.info.frame_count

    @property
    def frame(self) -> int:
        return self._frame

    @property
    def annotations(self) -> Annotations:
        return self._annotations

    @property
    def method(self) -> str:
        """The method the page shows: "silhouette" or "track" (the annotations')."""
        return self._annotations.method or "silhouette"

    @property
    def progress(self) -> Progress:
        """How far the shown method's work is (the fit, or the tracking)."""
        return self._track_progress if self.method == "track" else self._progress

    @property
    def _session(self) -> Session | None:
        """The shown method's session (None until fitted, or tracked)."""
        return self._tracked if self.method == "track" else self._fitted

    def far_arm(self) -> str | None:
        """The tracking's far arm, "l" or "r" (TrackSession.far_arm); None with the
        silhouette method, before the tracking, or for a body facing the camera."""
        with self._lock:
            return self._tracked.far_arm() if self.method == "track" and self._tracked else None

    @property
    def tracking(self) -> bool:
        """Whether a tracking runs now."""
        return self._tracking

    @property
    def marks_changed(self) -> bool:
        """Whether frame 0's marks differ from those the tracking used."""
        with self._lock:
            first = self._annotations.frames.get(0, FrameNote())
            return self._tracked is not None and dict(first.joints2d) != self._tracked_from

    @property
    def undo_depth(self) -> int:
        """How many edits undo can take back."""
        return len(self._history.undo)

    def on_change(self, listener: Callable[[], None]) -> None:
        """Call ``listener`` (outside the lock) after every change of the state."""
        self._listeners.append(listener)

    def _changed(self) -> None:
        with self._lock:
            self._version += 1
        for listener in list(self._listeners):
            listener()

    # -- preprocessing ------------------------------------------------------------

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
            self._progress = Progress(session.n_frames * 2, session.n_frames * 2, "ready")
        self._changed()

    def _step(self, done: int, stage: str) -> None:
        with self._lock:
            self._progress = Progress(min(done, self._progress.total - 1), self._progress.total, stage)
        self._changed()

    def _fail(self, message: str) -> None:
        with self._lock:
            self._progress = replace(self._progress, stage="stopped", error=message)
        self._changed()

    # -- tracking -----------------------------------------------------------------

    def start_tracking(self) -> threading.Thread:
        """Track from frame 0's marks in a daemon thread. Refused at once (a
        MocapError naming the joint) while a mark is missing or outside the frame, or
        when the shoulders, chest and hips fit no view of a trunk."""
        with self._lock:
            if self._tracking:
                raise MocapError("already tracking; wait for it to finish")
            notes = self._annotations
            marks = marks_of(notes)
            checked = check_marks(marks, self.info.width, self.info.height)
            calibrate(checked, default_camera(self.info.width, self.info.height),
                      turn_of(notes.orientations(1)[0]))
            self._tracking = True
            self._track_progress = Progress(0, self.n_frames, "following the marked joints")
        thread = threading.Thread(target=self._track, args=(notes, marks), daemon=True,
                                  name="mocap-track")
        thread.start()
        self._changed()
        return thread

    def _track(self, notes: Annotations, marks: dict) -> None:
        report = Throttle(lambda done, stage: self._track_step(done), self.n_frames)
        try:
            session = open_session(self.info, notes, method="track",
                                   progress=lambda p: report(p.done, "tracking"))
            session.inputs      # the 3D, before the lock
            with self._lock:
                if self._annotations != notes:      # edits made while tracking
                    session.annotate(self._annotations)
                self._tracked, self._tracked_from, self._queue = session, marks, None
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
            self._track_progress = Progress(min(done, self.n_frames - 1), self.n_frames,
                                            "following the marked joints")
        self._changed()

    # -- reading ------------------------------------------------------------------

    def view(self, frame: int | None = None) -> FrameView:
        """The current (or given) frame as the page shows it."""
        with self._lock:
            i = self._frame if frame is None else frame
            fit = self._fits[i]
            base = FrameView(i, self.n_frames, self._version, self.progress, self._silhouettes[i],
                             self._silhouettes_done > i, fit is not None,
                             dict(self._annotations.frames.get(i, FrameNote()).joints2d),
                             i in self._annotations.keyframe_indices(self.n_frames),
                             method=self.method)
            if self.method == "track":
                if self._tracked is None:
                    return replace(base, fitted=False)
                carried = carried_pins(self._annotations.overrides(), i, self.info.fps)
                return self._lifted_view(replace(base, fitted=True, carried=carried,
                                                 score=float(self._tracked.scores[i])))
            if fit is None or fit.joints2d is None:
                return base
            if self._session is None:
                return replace(base, joints2d=fit.joints2d, score=fit.score)
            return self._lifted_view(replace(base, score=fit.score))

    def _lifted_view(self, base: FrameView) -> FrameView:
        i, notes, inputs = base.index, self._annotations, self._session.inputs
        signs = tuple(int(s) for s in inputs.signs[i])
        sign_notes = tuple(sign_note(notes, i, s, sign) for s, sign in zip(SEGMENT_NAMES, signs))
        doubt = next((d.reasons for d in self.review_queue() if d.frame == i), ())
        pose = self._session.pose3d(i).copy()
        orientation, said = shown_orientation(notes, i, inputs.orientation[i], base.method)
        return replace(base, joints2d=inputs.joints2d[i].copy(), sides_known=True, pose3d=pose,
                       signs=signs, sign_notes=sign_notes,
                       depths=tuple(float(d) for d in depth_fractions(pose)),
                       orientation=orientation, orientation_note=said, doubts=doubt)

    def review_queue(self) -> list[Doubt]:
        """Doubtful frames, most doubtful first (empty until the fit is done)."""
        with self._lock:
            if self._session is None:
                return []
            if self._queue is None:
                self._queue = review_queue(self._session)
            return self._queue

    def review_stops(self) -> list[Doubt]:
        """The frames the review visits, most doubtful first: the queue; with the
        tracking method one frame in every stretch its pins cover (review.covering)."""
        with self._lock:
            queue = self.review_queue()
            if self._session is None or not self._session.review_spacing:
                return queue
            return covering(queue, self.n_frames, self._session.review_spacing)

    def motion(self) -> Motion:
        """The animation of the current annotations (keyframes lifted, others interpolated)."""
        with self._lock:
            return self._require_session().motion()

    def export(self, key: str) -> tuple[str, bytes]:
        """(file name, content) of the animation in a format of mocap.session.FORMATS."""
        with self._lock:
            return self._require_session().export(key)

    def _require_session(self) -> Session:
        if self._session is not None:
            return self._session
        if self.method == "silhouette":
            raise MocapError("the video is still being fitted; this needs every frame fitted")
        if self._tracking:
            raise MocapError("the video is still being tracked; this needs every frame tracked")
        raise MocapError("nothing tracked yet: mark the 16 joints on frame 0, then press Track")

    # -- navigation ---------------------------------------------------------------

    def go_to(self, frame: int) -> bool:
        """Make ``frame`` (clamped to the video) the current frame; False if it was."""
        frame = int(np.clip(frame, 0, self.n_frames - 1))
        with self._lock:
            if frame == self._frame:
                return False
            self._frame = frame
        self._changed()
        return True

    def keyframe_after(self, frame: int, step: int) -> int | None:
        """The nearest keyframe after (step +1) or before (step -1) ``frame``."""
        keys = self._annotations.keyframe_indices(self.n_frames)
        later = [k for k in keys if (k - frame) * step > 0]
        return min(later, key=lambda k: abs(k - frame)) if later else None

    def next_doubtful(self) -> int | None:
        """The next frame down the review queue: its first at first, then the one after
        the frame this last returned (by its place in the queue as ranked now); None
        when the queue is empty."""
        with self._lock:
            frames = [d.frame for d in self.review_stops()]
            if not frames:
                return None
            at = frames.index(self._reviewed) + 1 if self._reviewed in frames else 0
            self._reviewed = frames[at % len(frames)]
            return self._reviewed

    # -- editing ------------------------------------------------------------------

    def edit(self, frame: int, change: Change) -> bool:
        """Apply ``change`` to the annotations on behalf of ``frame``: saved, applied,
        undoable, shown. False when it changes nothing."""
        with self._lock:
            before = self._annotations
            after = change(before)
            if after == before:
                return False
            self._apply(after)
            self._history.undo.append((before, after, frame))
            self._history.redo.clear()
            self._frame = frame
        self._changed()
        return True

    def _apply(self, notes: Annotations) -> None:
        """Save first (atomically), then use: what is shown is on disk."""
        try:
            save_annotations(self.path, notes)
        except OSError as exc:
            raise MocapError(f"cannot save annotations to {self.path}: {exc.strerror or exc}") from None
        self._annotations, self._queue = notes, None
        for session in (self._fitted, self._tracked):
            if session is not None:
                session.annotate(notes)

    def undo(self) -> int | None:
        """Undo the last edit; returns its frame (now current), None if nothing to undo."""
        return self._travel(self._history.undo, self._history.redo, 0)

    def redo(self) -> int | None:
        """Redo the last undone edit; returns its frame, None if nothing to redo."""
        return self._travel(self._history.redo, self._history.undo, 1)

    def _travel(self, source: list, target: list, restore: int) -> int | None:
        with self._lock:
            if not source:
                return None
            step = source[-1]
            self._apply(step[restore])
            target.append(source.pop())
            self._frame = step[2]
        self._changed()
        return step[2]

    def flip_sign(self, frame: int, segment: str) -> bool:
        """Set a segment's foreshortening on ``frame`` to the opposite of what it is."""
        def change(notes: Annotations) -> Annotations:
            signs = self._session_signs(frame)
            value = "away" if signs[SEGMENT_INDEX[segment]] > 0 else "toward"
            return notes.with_foreshortening(frame, segment, value)
        return self.edit(frame, change)

    def _session_signs(self, frame: int) -> np.ndarray:
        session = self._require_session()
        if not session.person[frame]:
            raise MocapError("foreshortening needs the 3D pose of this frame (nobody found)")
        return session.inputs.signs[frame]

    def set_orientation(self, frame: int, orientation: str | None) -> bool:
        """Say (or with None unsay) which way the performer faces from ``frame`` on."""
        return self.edit(frame, lambda n: n.with_orientation(frame, orientation))

    def set_override(self, frame: int, joint: str, xy: tuple[float, float] | None) -> bool:
        """Fix (or with None release) a joint's 2D position on ``frame``."""
        return self.edit(frame, lambda n: n.with_joint(frame, joint, xy))

    def clear_overrides(self, frame: int, joint: str | None = None) -> bool:
        """Release ``joint`` on ``frame``, or with None every joint placed there (one edit)."""
        def change(notes: Annotations) -> Annotations:
            placed = notes.frames.get(frame, FrameNote()).joints2d
            if not placed or joint is not None and joint not in placed:
                raise MocapError(f"no override of {joint or 'any joint'} on frame {frame}")
            for name in ([joint] if joint else list(placed)):
                notes = notes.with_joint(frame, name, None)
            return notes
        return self.edit(frame, change)

    def set_method(self, method: str) -> bool:
        """Choose the silhouette ("silhouette") or the tracking ("track") method."""
        return self.edit(self._frame, lambda n: n.with_method(method))

    def marks_from_fit(self) -> bool:
        """Place all 16 marks on frame 0 where the silhouette method's fit has them
        (sides resolved, overrides kept, the shoulders in the hips' order:
        mocap.track.marks.shoulders_as_hips): a start for the user to correct."""
        with self._lock:
            if self._fitted is None or self._fits[0].joints2d is None:
                raise MocapError("frame 0 has no silhouette fit to take the marks from"
                                 + (" yet" if self._fitted is None else ""))
            joints = shoulders_as_hips(self._fitted.inputs.joints2d[0])
        def change(notes: Annotations) -> Annotations:
            for name, (x, y) in zip(JOINTS, joints):
                notes = notes.with_joint(0, name, (round(float(x), 1), round(float(y), 1)))
            return notes
        return self.edit(0, change)

    def unmarked(self) -> list[str]:
        """The joints not yet marked on frame 0, in JOINTS order."""
        placed = self._annotations.frames.get(0, FrameNote()).joints2d
        return [j for j in JOINTS if j not in placed]

    def toggle_keyframe(self, frame: int) -> bool:
        """Mark ``frame`` as a keyframe, or unmark it."""
        return self.edit(frame, lambda n: toggled_keyframe(n, frame, self.n_frames))

