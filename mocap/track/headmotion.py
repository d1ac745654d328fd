"""The head's motion between frames by image difference (Pan, Zhuang and Liu 2000, "Feature tracking", "1. Head",
Eq. 1-5, Fig. 3-5): the calvaria's predicted place before the morph-block match refines it."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

DIRECTIONS = np.radians(90.0 + 5.0 * np.arange(36))  # alpha_0 = 90, alpha_n+1 = alpha_n + 5
P_START, P_STEP, P_RANGE = 0.5, 0.05, (0.2, 0.9)  # the adaptive threshold p


@dataclass(frozen=True)
class Displacement:
    """The head's predicted motion: ``vector`` (2,) in pixels and its length."""

    vector: np.ndarray

    @property
    def length(self) -> float:
        return float(np.hypot(*self.vector))


def difference_lines(
    prev: np.ndarray, cur: np.ndarray, centre: np.ndarray, diameter: float
) -> tuple[np.ndarray, np.ndarray]:
    """(t (S,), diff (36, S)): |dR| + |dG| + |dB| (Eq. 1-3) along the 36 lines through the head centre ``centre`` of
    the region Omega (radius 2L, L = ``diameter``), t the signed distance along (cos alpha, -sin alpha)."""
    t = np.arange(-2 * diameter, 2 * diameter + 0.5, 1.0, dtype=np.float32)
    x = centre[0] + np.cos(DIRECTIONS)[:, None] * t
    y = centre[1] - np.sin(DIRECTIONS)[:, None] * t
    x, y = x.astype(np.float32), y.astype(np.float32)
    a = cv2.remap(prev, x, y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    b = cv2.remap(cur, x, y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return t, cv2.absdiff(a, b).astype(np.float32).sum(axis=2)


def two_peak_displacement(t: np.ndarray, profile: np.ndarray, p: float) -> float:
    """Signed displacement along a line from its two-peak curve (Fig. 5): the mean width of the two strongest runs
    above Y = a p (a the mean), toward the one farther from O; 0 without runs."""
    above = np.r_[False, profile > profile.mean() * p, False]
    edges = np.flatnonzero(np.diff(above.astype(np.int8)))
    starts, stops = edges[::2], edges[1::2]
    if not len(starts):
        return 0.0
    mass = np.array([profile[a:b].sum() for a, b in zip(starts, stops)])
    keep = np.sort(np.argsort(mass)[-2:])
    widths = (stops - starts)[keep]
    centres = (t[starts[keep]] + t[stops[keep] - 1]) / 2
    far = centres[np.argmax(np.abs(centres))]
    return float(np.sign(far) * widths.mean())


def head_displacement(
    prev: np.ndarray, cur: np.ndarray, calvaria: np.ndarray, neck: np.ndarray, p: float
) -> Displacement:
    """The calvaria's motion (Eq. 1-5): direction of the largest Sum_n (Eq. 4-5), length from its two-peak curve."""
    diameter = max(float(np.hypot(*(calvaria - neck))), 2.0)
    t, diff = difference_lines(prev, cur, (calvaria + neck) / 2, diameter)
    n = int(np.argmax(diff.sum(axis=1)))
    length = np.clip(two_peak_displacement(t, diff[n], p), -diameter, diameter)
    alpha = DIRECTIONS[n]
    return Displacement(length * np.array([np.cos(alpha), -np.sin(alpha)]))


def adapt_threshold(p: float, predicted: float, found: float) -> float:
    """Threshold p raised where the image difference over-estimated the displacement found, else lowered."""
    p = p + P_STEP if predicted > found else p - P_STEP
    return float(np.clip(p, *P_RANGE))
