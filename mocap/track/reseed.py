"""Tracking from the body marked again on any frame: every frame where the user marked
all 16 joints seeds the tracker (mocap.track.tracker) anew, forward to the next seed
and backward to the one before; each frame between two seeds then takes the track
that still holds the body there (``merged``).

Beyond the tracking paper (Pan, Zhuang and Liu, *Video motion capture in VBA*,
2000), which marks frame 0 only: a tracker that lost the body (mocap.track.loss)
does not find it again by itself on every clip, and a user who marks it again where
it was lost mends the frames after the mark and before it.

Frames are streamed while there is one seed; with more, the frames between the
first and the last seed are kept in memory for the backward passes.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import NamedTuple

import numpy as np

from mocap.track.calibration import Pinhole
from mocap.track.tracker import BodyTracker
from mocap.track.parts import PARTS


class Track(NamedTuple):
    """One run of the tracker over consecutive frames: (F, 16, 2) joints, (F, 10)
    similarities S (inf on its seed), (F, 10) confidences, (F,) lost."""

    joints: np.ndarray
    similarity: np.ndarray
    confidence: np.ndarray
    lost: np.ndarray


def run_tracker(frames: Iterable[np.ndarray], marks: np.ndarray, tick: Callable[[], None],
                camera: Pinhole | None, turn: str | None, fps: float) -> Track:
    """The tracker seeded with ``marks`` (16, 2) on the first of ``frames``, run
    through them all (``tick`` after each tracked frame)."""
    it = iter(frames)
    tracker = BodyTracker(next(it), marks, camera, turn, fps)
    rows = [(marks, np.full(len(PARTS), np.inf), np.ones(len(PARTS)), False)]
    for frame in it:
        found, s = tracker.step(frame)
        rows.append((found, s, tracker.confidence, tracker.lost))
        tick()
    return Track(*(np.array(column) for column in zip(*rows)))


def merged(forward: Track, backward: Track) -> Track:
    """Frames a..b tracked forward from a seed on a and backward from one on b
    (``backward`` in the forward order): on every frame the track whose body is not
    lost, where both hold it the one from the nearer seed, where neither the forward
    one (lost)."""
    n = len(forward.lost)
    nearer_back = np.arange(n) > (n - 1) / 2
    take_back = ~backward.lost & (forward.lost | nearer_back)
    take_back[0], take_back[-1] = False, True
    return Track(*(np.where(take_back.reshape(-1, *[1] * (f.ndim - 1)), b, f)
                   for f, b in zip(forward, backward)))


def track_seeded(frames: Iterable[np.ndarray], seeds: dict[int, np.ndarray],
                 progress: Callable[[int], None] | None, camera: Pinhole | None,
                 turn: str | None, fps: float) -> Track:
    """Track the body through ``frames`` from every seed (frame -> checked (16, 2)
    marks; frame 0 among them): forward from each seed to the next, backward from
    each seed after the first to the one before, merged (``merged``).
    ``progress(done)`` counts the seed and the tracked frames of every pass: the
    frame count and the last seed's frame in all."""
    keys = sorted(seeds)
    done = [0]

    def tick() -> None:
        done[0] += 1
        if progress:
            progress(done[0] + 1)
    it = iter(frames)
    if len(keys) == 1:
        return run_tracker(it, seeds[0], tick, camera, turn, fps)
    kept = [next(it) for _ in range(keys[-1] + 1)]
    parts = []
    for a, b in zip(keys, keys[1:]):
        forward = run_tracker(kept[a:b + 1], seeds[a], tick, camera, turn, fps)
        backward = run_tracker(kept[b:a - 1 if a else None:-1], seeds[b], tick, camera, turn, fps)
        parts.append(merged(forward, Track(*(x[::-1] for x in backward))))
    rest = run_tracker([kept[-1], *it], seeds[keys[-1]], tick, camera, turn, fps)
    return Track(*(np.concatenate([*(p[i][:-1] for p in parts), rest[i]]) for i in range(4)))

