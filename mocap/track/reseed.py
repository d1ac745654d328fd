"""Tracking from the body marked again on later frames, beyond the paper: each seed is tracked forward and backward to
its neighbours, each frame between taking the track that still holds the body (``merged``)."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import NamedTuple

import numpy as np

from mocap.camera import Pinhole
from mocap.track.parts import PARTS
from mocap.track.tracker import BodyTracker


class Track(NamedTuple):
    """One tracker run: (F, 16, 2) joints, (F, 10) S (inf on its seed), (F, 10) confidences, (F,) lost."""

    joints: np.ndarray
    similarity: np.ndarray
    confidence: np.ndarray
    lost: np.ndarray


def run_tracker(
    frames: Iterable[np.ndarray],
    marks: np.ndarray,
    tick: Callable[[], None],
    camera: Pinhole | None,
    turn: str | None,
    fps: float,
) -> Track:
    """The tracker seeded with ``marks`` (16, 2) on the first of ``frames``, run through all (``tick`` each)."""
    it = iter(frames)
    tracker = BodyTracker(next(it), marks, camera, turn, fps)
    rows = [(marks, np.full(len(PARTS), np.inf), np.ones(len(PARTS)), False)]
    for frame in it:
        found, s = tracker.step(frame)
        rows.append((found, s, tracker.confidence, tracker.lost))
        tick()
    return Track(*(np.array(column) for column in zip(*rows)))


def merged(forward: Track, backward: Track) -> Track:
    """Frames a..b tracked ``forward`` from a and ``backward`` from b (in forward order): per frame the track not
    lost, where both hold the body the nearer seed's, where neither the forward one."""
    n = len(forward.lost)
    nearer_back = np.arange(n) > (n - 1) / 2
    take_back = ~backward.lost & (forward.lost | nearer_back)
    take_back[0], take_back[-1] = False, True
    return Track(*(np.where(take_back.reshape(-1, *[1] * (f.ndim - 1)), b, f) for f, b in zip(forward, backward)))


def track_seeded(
    frames: Iterable[np.ndarray],
    seeds: dict[int, np.ndarray],
    progress: Callable[[int], None] | None,
    camera: Pinhole | None,
    turn: str | None,
    fps: float,
) -> Track:
    """Track ``frames`` from every seed (frame -> (16, 2) marks, frame 0 among them), forward and backward between
    seeds, ``merged``; ``progress(done)`` counts every pass's frames."""
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
        forward = run_tracker(kept[a : b + 1], seeds[a], tick, camera, turn, fps)
        backward = run_tracker(kept[b : a - 1 if a else None : -1], seeds[b], tick, camera, turn, fps)
        parts.append(merged(forward, Track(*(x[::-1] for x in backward))))
    rest = run_tracker([kept[-1], *it], seeds[keys[-1]], tick, camera, turn, fps)
    return Track(*(np.concatenate([*(p[i][:-1] for p in parts), rest[i]]) for i in range(4)))
