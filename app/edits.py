"""The app's edits: each turns a click into new annotations (``Change``), which
``Edits.edit`` saves, applies to both methods' sessions and records for undo."""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import replace

from app import saving
from mocap.body import JOINT_INDEX, JOINTS, LIMB_JOINTS, SEGMENT_INDEX
from mocap.errors import MocapError
from mocap.io.annotations import Annotations
from mocap.person import NONE
from mocap.session import marks_from_fit, propose_keyframes
from mocap.session.tracking import proposed_marks

Change = Callable[[Annotations], Annotations]


def toggled_keyframe(notes: Annotations, frame: int, n_frames: int) -> Annotations:
    """``notes`` with ``frame``'s keyframe mark toggled; all frames marked is written as no list."""
    keys = set(notes.keyframe_indices(n_frames)) ^ {frame}
    if not keys:
        raise MocapError("the last keyframe cannot be unmarked: the animation needs one")
    return replace(notes, keyframes=None if len(keys) == n_frames else tuple(sorted(keys)))


def keyed(notes: Annotations, frame: int) -> Annotations:
    """``notes`` with ``frame`` among the keyframes (an edited frame is lifted, not interpolated)."""
    if notes.keyframes is None or frame in notes.keyframes:
        return notes
    return replace(notes, keyframes=tuple(sorted({*notes.keyframes, frame})))


def with_marks(notes: Annotations, marks: dict[str, tuple[float, float]]) -> Annotations:
    """``notes`` with ``marks`` (joint -> (x, y)) placed on frame 0, the tracking method's marks."""
    for name, xy in marks.items():
        notes = notes.with_joint(0, name, xy)
    return notes


def pixel(xy) -> tuple[float, float]:
    """A point as the annotations keep a placed joint: (x, y) to 0.1 px."""
    return round(float(xy[0]), 1), round(float(xy[1]), 1)


def placed(notes: Annotations, frame: int) -> dict[str, tuple[float, float]]:
    """The joint overrides of a frame (frame 0's: the tracking method's marks)."""
    return dict(notes.frames[frame].joints2d) if frame in notes.frames else {}


class Edits:
    """AppState's edits (a mixin: the state's lock, annotations, sessions, history)."""

    def edit(self, frame: int, change: Change, key: bool = False) -> bool:
        """Apply ``change`` on behalf of ``frame``: saved, applied, undoable, shown; False if a no-op.
        ``key``: the frame becomes a keyframe too (in the same edit)."""
        with self._lock:
            before = self._annotations
            after = change(before)
            if after == before:
                return False
            if key:
                after = keyed(after, frame)
            self._apply(after, frame)
            self._history.record(before, after, frame)
            self._frame = frame
        self._changed()
        self._settle_soon()
        return True

    def _apply(self, notes: Annotations, focus: int | None = None) -> None:
        """Save first (atomically), then use: what is shown is on disk."""
        saving.save(self.path, notes)
        self._use(notes, focus)

    def _use(self, notes: Annotations, focus: int | None = None) -> None:
        """(Under the lock) make ``notes`` the annotations the sessions work from, resolved around ``focus``
        (the edited frame) first: the rest waits for ``_settle_soon``."""
        self._annotations = notes
        for session in (self._fitted, self._tracked):
            if session is not None:
                session.annotate(notes, focus)

    _settler: threading.Thread | None = None

    def _settle_soon(self) -> None:
        """What an edit left for later (the clip solve's windows away from its frame) solved on a thread of its
        own, the page shown again once it is done."""
        self._settler = threading.Thread(target=self._settle, daemon=True, name="mocap-settle")
        self._settler.start()

    def wait_settled(self, timeout: float | None = None) -> None:
        """Return once what the last edit left for later is solved (or ``timeout`` seconds passed)."""
        if self._settler is not None:
            self._settler.join(timeout)

    def _settle(self) -> None:
        """Settle the sessions a piece at a time, the lock let go between pieces (a frame change waits for one
        piece at most), then their review queues (the page showed the last ones), then show the page again."""
        changed = False
        while True:
            with self._lock:
                pieces = [session.settle(most=1) for session in self._sessions()]
            if not any(pieces):
                break
            changed = True
        with self._lock:
            shown = self._session
            if shown is not None and shown.queue_stale:
                shown.review_queue()
                changed = True
        if changed:
            self._changed()

    def _sessions(self) -> list:
        """Both methods' sessions that exist."""
        return [session for session in (self._fitted, self._tracked) if session is not None]

    def undo(self) -> int | None:
        """Undo the last edit; returns its frame (now current), None if nothing to undo."""
        return self._travel(back=True)

    def redo(self) -> int | None:
        """Redo the last undone edit; returns its frame, None if nothing to redo."""
        return self._travel(back=False)

    def _travel(self, back: bool) -> int | None:
        with self._lock:
            step = self._history.peek(back)
            if step is None:
                return None
            self._apply(step[0], step[1])
            self._history.move(back)
            self._frame = step[1]
        self._changed()
        self._settle_soon()
        return step[1]

    def flip_sign(self, frame: int, segment: str) -> bool:
        """Set a segment's foreshortening on ``frame`` to the opposite of what it is."""

        def change(notes: Annotations) -> Annotations:
            session = self._require_session()
            if not session.person[frame]:
                raise MocapError("foreshortening needs the 3D pose of this frame (nobody found)")
            value = "away" if session.inputs.signs[frame, SEGMENT_INDEX[segment]] > 0 else "toward"
            return notes.with_foreshortening(frame, segment, value)

        return self.edit(frame, change, key=True)

    def set_orientation(self, frame: int, orientation: str | None) -> bool:
        """Say (or with None unsay) which way the performer faces from ``frame`` on."""
        return self.edit(frame, lambda n: n.with_orientation(frame, orientation), key=True)

    def set_override(self, frame: int, joint: str, xy: tuple[float, float] | None) -> bool:
        """Fix (or with None release) a joint's 2D position on ``frame``."""
        return self.edit(frame, lambda n: n.with_joint(frame, joint, xy), key=xy is not None)

    def swap_sides(self, frame: int, limb: str) -> bool:
        """Exchange the performer's left and right ``limb`` ("arm" or "leg") on ``frame`` in one edit: each of its
        joints placed where the other side's is shown, the frame a keyframe. The fix for a pair named the wrong
        way round (the review's "hands / feet may have swapped sides"), in one click instead of six."""

        def change(notes: Annotations) -> Annotations:
            view = self.view(frame)
            if not view.sides_known:
                raise MocapError(f"swapping sides needs the 3D pose of frame {frame} (not fitted yet, or nobody found)")
            for name in LIMB_JOINTS[limb]:
                left, right = (view.joints2d[JOINT_INDEX[f"{name}_{side}"]] for side in "lr")
                notes = notes.with_joint(frame, f"{name}_l", pixel(right)).with_joint(frame, f"{name}_r", pixel(left))
            return notes

        return self.edit(frame, change, key=True)

    def clear_overrides(self, frame: int, joint: str | None = None) -> bool:
        """Release ``joint`` on ``frame``, or with None every joint placed there (one edit)."""

        def change(notes: Annotations) -> Annotations:
            there = placed(notes, frame)
            if not there or joint is not None and joint not in there:
                raise MocapError(f"no override of {joint or 'any joint'} on frame {frame}")
            for name in [joint] if joint else list(there):
                notes = notes.with_joint(frame, name, None)
            return notes

        return self.edit(frame, change)

    def set_method(self, method: str) -> bool:
        """Choose the silhouette ("silhouette") or the tracking ("track") method; tracking chosen with frame 0
        unmarked places the marks the person model proposes there (proposed_marks; where it is unsure there, the
        silhouette fit's), to correct and confirm."""
        with self._lock:
            fresh = method == "track" and self._fitted is not None and not placed(self._annotations, 0)
            marks = (proposed_marks(self._fitted, self._person != NONE) if fresh else None) or {}

        def change(notes: Annotations) -> Annotations:
            return with_marks(notes.with_method(method), marks)

        return self.edit(self._frame, change)

    def marks_from_fit(self) -> bool:
        """Place all 16 marks on frame 0 where the silhouette fit has them (mocap.session.marks_from_fit)."""
        with self._lock:
            if self._fitted is None:
                raise MocapError("frame 0 has no silhouette fit to take the marks from yet")
            marks = marks_from_fit(self._fitted)

        return self.edit(0, lambda notes: with_marks(notes, marks))

    @property
    def silhouette_fitted(self) -> bool:
        """Whether the silhouette method's fit of every frame exists (marks_from_fit needs it)."""
        return self._fitted is not None

    def unmarked(self, frame: int = 0) -> list[str]:
        """The joints not yet marked on ``frame`` (frame 0's: the tracking's marks), in JOINTS order."""
        there = placed(self._annotations, frame)
        return [j for j in JOINTS if j not in there]

    @property
    def tracks_unmarked(self) -> bool:
        """Whether Track starts with frame 0 unmarked: a person model looks on, and its landmarks mark the body
        where it is first sure of it, tracked back to frame 0 from there (mocap.session.tracking.tracked_video),
        as `mocap fit --method track` without marks does; frame 0 partly marked asks for the rest."""
        return self._person != NONE and not placed(self._annotations, 0)

    def marking_frame(self) -> int:
        """The frame the tracking's joints are marked on: 0 until all 16 are marked there, then the
        current frame (a re-mark where the tracking lost the body seeds it anew)."""
        return self._frame if not self.unmarked(0) else 0

    def _propose_keyframes(self, session) -> None:
        """(Under the lock) a clip without keyframes takes the session's proposal
        (mocap.session.propose_keyframes), saved as what the page shows: the state the clip opens
        in, not an edit to undo (kept unsaved where the folder takes no file)."""
        if self._annotations.keyframes is not None or not (keys := propose_keyframes(session)):
            return
        notes = replace(self._annotations, keyframes=tuple(keys))
        try:
            self._apply(notes)
        except MocapError:
            self._use(notes)

    def toggle_keyframe(self, frame: int) -> bool:
        """Mark ``frame`` as a keyframe, or unmark it."""
        return self.edit(frame, lambda n: toggled_keyframe(n, frame, self.n_frames))
