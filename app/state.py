"""The app's one truth: a video, its sessions, the user's annotations, their undo history.

One ``AppState`` serves every tab and callback thread behind a re-entrant lock; an edit is saved
beside the video before it is shown (``app.edits``, ``app.saving``); fitting and tracking run in
``app.preprocess``. The methods are reached only through mocap.session and mocap.pipeline."""

from __future__ import annotations

import os
import threading
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from app import saving
from app.edits import Edits, placed
from app.history import History
from app.preprocess import Preprocessing
from mocap.errors import MocapError
from mocap.io.annotations import Annotations
from mocap.io.video import open_video, processing_scale
from mocap.pipeline import Focal, Progress, person_model
from mocap.session import FrameFit, Session, Silhouette, SilhouetteSession, TrackSession, remarks_of
from mocap.session.review import Doubt


@dataclass(frozen=True, eq=False)
class FrameView:
    """Everything the page shows of one frame, read at one moment from one state."""

    index: int
    n_frames: int
    version: int
    progress: Progress
    silhouette: Silhouette | None  # processing pixels; None: none yet or nobody
    silhouette_ready: bool
    fitted: bool  # the 2D fit of this frame exists
    overrides: dict[str, tuple[float, float]]
    keyframe: bool
    joints2d: np.ndarray | None = None  # (16, 2) video pixels; anatomical when sides_known
    sides_known: bool = False
    score: float | None = None
    pose3d: np.ndarray | None = None  # (16, 3) metres, contract frame
    signs: tuple[int, ...] | None = None  # +1 toward, -1 away, per SEGMENT_NAMES
    sign_notes: tuple[str, ...] = ()  # where each sign comes from (Session.sign_sources)
    depths: tuple[float, ...] = ()  # |dZ| / length per segment (0: in the image plane)
    orientation: str | None = None
    orientation_note: str = ""
    doubts: tuple[str, ...] = ()
    method: str = "silhouette"  # whose joints and 3D these are ("track": tracking's)
    carried: dict[str, int] = field(default_factory=dict)  # joint -> frame of the pin moving it


class AppState(Preprocessing, Edits):
    """A video, its preprocessing, its sessions and annotations, the current frame."""

    def __init__(
        self,
        video: str | os.PathLike,
        annotations: str | os.PathLike | None = None,
        person: str | None = None,
        focal: Focal | None = None,
    ):
        """``person``: the silhouette method's person model (mocap.person's name; "none": silhouettes
        alone; None: the default where installed, else a MocapWarning and none); ``focal``: the camera's
        focal length, the silhouette method's 3D solved through it (None: scaled orthography)."""
        self.info = open_video(video)
        self.scale = processing_scale(self.info)
        self.path = Path(annotations) if annotations else saving.annotations_path(video)
        n = self.info.frame_count
        self._annotations = saving.load(self.path, n)
        self._lock = threading.RLock()
        self._silhouettes: list[Silhouette | None] = [None] * n
        self._silhouettes_done = 0
        self._fits: list[FrameFit | None] = [None] * n
        self._progress = Progress(0, 2 * n, "waiting")
        self._person = person_model(person)
        self.focal = focal
        self._fitted: SilhouetteSession | None = None  # the silhouette method's
        self._tracked: TrackSession | None = None  # the tracking method's, once tracked
        self._tracked_from: dict | None = None  # the marks it was tracked from
        self._track_progress = Progress(0, n, "waiting for the 16 marks on frame 0")
        self._tracking = False
        self._history = History()
        self._frame = 0
        self._reviewed: int | None = None  # the frame next_doubtful returned last
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
        """The tracking's far arm, "l" or "r" (TrackSession.far_arm); None if there is none to give."""
        with self._lock:
            return self._tracked.far_arm() if self.method == "track" and self._tracked else None

    @property
    def tracking(self) -> bool:
        """Whether a tracking runs now."""
        return self._tracking

    @property
    def marks_changed(self) -> bool:
        """Whether frame 0's marks or the re-marks (remarks_of) differ from those the tracking used."""
        with self._lock:
            marks = (placed(self._annotations, 0), remarks_of(self._annotations))
            return self._tracked is not None and marks != self._tracked_from

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

    # -- reading ------------------------------------------------------------------

    def view(self, frame: int | None = None) -> FrameView:
        """The current (or given) frame as the page shows it."""
        with self._lock:
            i = self._frame if frame is None else frame
            fit = self._fits[i]
            base = FrameView(
                i,
                self.n_frames,
                self._version,
                self.progress,
                self._silhouettes[i],
                self._silhouettes_done > i,
                fit is not None,
                placed(self._annotations, i),
                i in self._annotations.keyframe_indices(self.n_frames),
                method=self.method,
            )
            if self.method == "track":
                if self._tracked is None:
                    return replace(base, fitted=False)
                return lifted_view(
                    replace(base, fitted=True, carried=self._tracked.carried(i), score=float(self._tracked.scores[i])),
                    self._tracked,
                )
            if fit is None or fit.joints2d is None:
                return base
            if self._fitted is None:
                return replace(base, joints2d=fit.joints2d, score=fit.score)
            return lifted_view(replace(base, score=fit.score), self._fitted)

    def review_queue(self) -> list[Doubt]:
        """Doubtful frames, most doubtful first (empty until the fit is done)."""
        with self._lock:
            return [] if self._session is None else self._session.review_queue()

    def review_stops(self, at_once: bool = False) -> list[Doubt]:
        """The frames the review visits, most doubtful first (Session.review_stops; ``at_once``: what a page
        shows the moment an edit is made, the settling showing the current ones)."""
        with self._lock:
            return [] if self._session is None else self._session.review_stops(at_once)

    @property
    def made_from(self) -> tuple:
        """What the animation and the pictures are made from: the annotations and the sessions (a refit,
        with the person model switched or the same stage given again, makes new ones)."""
        return self._annotations, self._fitted, self._tracked

    def animation(self) -> tuple[np.ndarray, float]:
        """The current animation: (F, 16, 3) pelvis-centred joints and the frame rate."""
        with self._lock:
            motion = self._require_session().motion()
        return motion.joints3d, motion.fps

    def export(self, key: str, foot_lock: bool = False) -> tuple[str, bytes]:
        """(file name, content) in a format of mocap.session.FORMATS; ``foot_lock`` keeps planted feet."""
        with self._lock:
            return self._require_session().export(key, foot_lock)

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
        """The review stop after the one last returned (by its rank now), the first at first; None
        when the queue is empty."""
        with self._lock:
            frames = [d.frame for d in self.review_stops()]
            if not frames:
                return None
            at = frames.index(self._reviewed) + 1 if self._reviewed in frames else 0
            self._reviewed = frames[at % len(frames)]
            return self._reviewed


def lifted_view(base: FrameView, session: Session) -> FrameView:
    """``base`` with its session's 3D: anatomical 2D joints, pose, signs and sources, orientation, doubts."""
    i, inputs = base.index, session.inputs
    doubt = next((d.reasons for d in session.review_queue(at_once=True) if d.frame == i), ())
    orientation, said = session.orientation_shown(i)
    return replace(
        base,
        joints2d=inputs.joints2d[i].copy(),
        sides_known=True,
        pose3d=session.pose3d(i).copy(),
        signs=tuple(int(s) for s in inputs.signs[i]),
        sign_notes=session.sign_sources(i),
        depths=session.depths(i),
        orientation=orientation,
        orientation_note=said,
        doubts=doubt,
    )
