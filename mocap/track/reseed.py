"""Tracking from several seeds, beyond the paper: the body marked again on later frames, or seen by the person model
where the tracker has none yet or lost it (landmarks.seed_marks); each seed is tracked forward and backward to the
frames before it, each frame taking the track that still holds the body (``merged``)."""

from __future__ import annotations

import copy
from collections.abc import Callable, Iterable
from itertools import repeat
from typing import NamedTuple

import numpy as np

from mocap.camera import Pinhole
from mocap.errors import MocapError
from mocap.person import Landmarks, PersonView
from mocap.track.keydepths import side_of
from mocap.track.landmarks import facing_yaw, proposed, seed_marks
from mocap.track.parts import PARTS
from mocap.track.tracker import BodyTracker

STRANGER_S = 0.5  # seconds on end the person model is sure of a body in clothes the tracker never saw, to seed it
NOBODY = "the person model sees nobody to track in the video: mark the 16 joints on a frame that shows the body"


class Track(NamedTuple):
    """One tracker run: (F, 16, 2) joints, (F, 10) S (inf on its seed), (F, 10) confidences, (F,) lost, and (F,)
    the person model's facing yaw (degrees, NaN where unsure or unseen: landmarks.facing_yaw)."""

    joints: np.ndarray
    similarity: np.ndarray
    confidence: np.ndarray
    lost: np.ndarray
    facing: np.ndarray


Row = tuple[np.ndarray, np.ndarray, np.ndarray, bool]  # a frame's joints, S, confidences, lost


def seed_row(marks: np.ndarray) -> Row:
    """The row of a seed frame: its marks, S infinite, confident."""
    return marks, np.full(len(PARTS), np.inf), np.ones(len(PARTS)), False


def merged(forward: list[Row | None], backward: list[Row | None]) -> list[Row]:
    """Frames a..b tracked ``forward`` from a (None: untracked) and ``backward`` from b (in forward order): per frame
    the row not lost, where both hold the body the nearer seed's, where neither the forward one; b's own row back.
    Frame a keeps a forward row it has: its backward one is not looked at then (None: not tracked back)."""
    n = len(forward)
    out = []
    for i, (f, b) in enumerate(zip(forward, backward)):
        take_back = f is None or i == n - 1 or (i > 0 and not b[3] and (f[3] or i > (n - 1) / 2))
        out.append(b if take_back else f)
    return out


class _Run:
    """The seeds' trackers over frames fed in order (``add``): kept frames for the next backward pass, the rows."""

    def __init__(
        self, seeds: dict[int, np.ndarray], camera: Pinhole | None, turn: str | None, fps: float, guided: bool
    ):
        self.seeds, self.camera, self.turn, self.fps, self.guided = seeds, camera, turn, fps, guided
        self.rows: list[Row | None] = []
        self.facing: list[float] = []
        self.kept: list[tuple[int, np.ndarray, Landmarks | None]] = []
        self.tracker: BodyTracker | None = None
        self.sure_for = 0  # frames on end up to the one before that the person model was sure of a body (seed_marks)

    def add(self, i: int, frame: np.ndarray, view: PersonView | None) -> None:
        """Track frame ``i`` as the person model sees it (``view``, None: unseen): from a user's seed there, else
        on from the frame before, seeded anew by the landmarks where that lost the body (or by their ``proposed``
        marks where none held it yet) and the model has seen it long enough (``_seen_enough``)."""
        seen = None if view is None else view.landmarks
        self.facing.append(facing_yaw(seen))
        row = None
        if i not in self.seeds and self.tracker is not None:
            found, s = self.tracker.step(frame, seen)
            row = (found, s, self.tracker.confidence, self.tracker.lost)
        seed, turn = self.seeds.get(i), self.turn
        sure = seed_marks(seen if self.tracker is not None else proposed(view), frame.shape)
        if seed is None and (row is None or row[3]) and self._seen_enough(frame, sure):
            seed, turn = sure, side_of(self.facing[-1])
        self.sure_for = self.sure_for + 1 if sure is not None else 0
        tracker = None if seed is None else self._seeded(frame, seed, turn, i in self.seeds)
        if tracker is not None:
            self._backward(copy.deepcopy(tracker), seed)
            self.tracker = tracker
            self.rows.append(seed_row(seed))
            self.kept = [(i, frame, seen)]
            return
        self.rows.append(row)
        self.kept.append((i, frame, seen))
        if row is not None and not row[3] and not any(f > i for f in self.seeds):
            self.kept = self.kept[-1:]  # the body held: a later seed's backward pass stops here

    def _seen_enough(self, frame: np.ndarray, sure: np.ndarray | None) -> bool:
        """Whether landmarks' marks ``sure`` on ``frame`` may seed the body anew: the model sure of a body on the frame
        before too (its first sight after a gap is a rough one), for STRANGER_S where the body does not wear the
        clothes of the one the tracker lost (BodyTracker.dressed_alike): a person model can make a body of the
        background for a moment, while a performer back in other clothes stays."""
        if sure is None or self.sure_for == 0:
            return False
        return self.tracker is None or self.sure_for >= STRANGER_S * self.fps or self.tracker.dressed_alike(frame, sure)

    def _seeded(self, frame: np.ndarray, seed: np.ndarray, turn: str | None, marked: bool) -> BodyTracker | None:
        """A tracker seeded on ``frame``; None for landmarks no trunk fits (a user's ``marked`` seed raises)."""
        try:
            return BodyTracker(frame, seed, self.camera, turn, self.fps, self.guided)
        except MocapError:
            if marked:
                raise
            return None

    def _backward(self, tracker: BodyTracker, seed: np.ndarray) -> None:
        """The kept frames tracked back by a fresh ``tracker`` from ``seed`` and merged with their forward rows; the
        first of them, where the body was last held or seeded, keeps its forward row (merged), so it is tracked back
        only where it has none (before any seed)."""
        if not self.kept:
            return
        first = self.kept[0][0]
        tracked_back = self.kept[self.rows[first] is not None :]
        back: list[Row | None] = [seed_row(seed)]
        for _, earlier, view in tracked_back[::-1]:
            found, s = tracker.step(earlier, view)
            back.append((found, s, tracker.confidence, tracker.lost))
        back += [None] * (len(self.kept) - len(tracked_back))
        rows = merged([*self.rows[first:], seed_row(seed)], back[::-1])
        self.rows[first:] = rows[:-1]

    def track(self) -> Track:
        """The rows so far as a Track; a MocapError (NOBODY) where no seed was ever found."""
        if self.tracker is None:
            raise MocapError(NOBODY)
        columns = [np.array(column) for column in zip(*self.rows)]
        return Track(*columns, np.array(self.facing))


def track_seeded(
    frames: Iterable[np.ndarray],
    seeds: dict[int, np.ndarray],
    progress: Callable[[int], None] | None,
    camera: Pinhole | None,
    turn: str | None,
    fps: float,
    views: Iterable[PersonView | None] | None = None,
) -> Track:
    """Track ``frames`` from every seed (frame -> (16, 2) marks) and where the person model's ``views`` (each
    frame's mask and landmarks, None: nobody; None: no model) seed a body none holds, forward and backward between
    seeds, ``merged``; ``progress(done)`` after every frame."""
    run = _Run(seeds, camera, turn, fps, views is not None)
    for i, (frame, view) in enumerate(zip(frames, repeat(None) if views is None else views)):
        run.add(i, frame, view)
        if progress:
            progress(i + 1)
    return run.track()
