"""The scene behind a performer who stays in place (mocap.silhouette.plate), from the samples that uncover it:
colours alone do not tell which do; the patches' connection to the scene around the performer does."""

from __future__ import annotations

import cv2
import numpy as np

from mocap.silhouette.cleaning import mask_box

AGREEING = 0.25  # of the samples: a group that agrees on a pixel's scene
MIN_GROUP = 3  # samples, whatever the share


def uncovered_scene(
    image: np.ndarray, holds: np.ndarray, frames: np.ndarray, floor: int
) -> tuple[np.ndarray, np.ndarray]:
    """The scene (uint8) where the median ``image`` ``holds`` the performer, and where seen (bool), peeled in
    ring by ring: samples that show the scene at a neighbour and differ from the median are candidates; the scene
    is the median of their largest group agreeing within ``floor``, if AGREEING of the samples."""
    scene = image.copy()
    seen = np.zeros(holds.shape, bool)
    box = mask_box(holds.astype(np.uint8), 1)
    if box is None:
        return scene, seen
    stack = frames[(slice(None), *box)].astype(np.int16)
    median, inside = image[box].astype(np.int16), holds[box]
    shows = _within(stack, median, floor)  # (S, h, w): where the median is the scene
    shows[:, inside] = False
    known = ~inside
    rings = cv2.distanceTransform(inside.astype(np.uint8), cv2.DIST_C, 3)
    for ring in range(1, int(rings.max()) + 1):
        ys, xs = np.nonzero(rings == ring)
        near = _near(shows & known, ys, xs)  # (S, n): shown at a known neighbour
        values = stack[:, ys, xs]  # (S, n, 3)
        near &= ~_within(values, median[ys, xs], floor)
        found, colour = _largest_agreeing(values, near, floor)
        scene[box][ys[found], xs[found]] = colour[found].astype(np.uint8)
        shows[:, ys[found], xs[found]] = _within(values[:, found], colour[found], floor)
        known[ys[found], xs[found]] = True
        seen[box][ys[found], xs[found]] = True
    return scene, seen


def _within(a: np.ndarray, b: np.ndarray, floor: int) -> np.ndarray:
    """Whether colours ``a``, ``b`` (..., 3) differ by at most ``floor`` in every channel."""
    out = np.abs(a[..., 0] - b[..., 0]) <= floor
    for channel in (1, 2):
        out &= np.abs(a[..., channel] - b[..., channel]) <= floor
    return out


def _near(mask: np.ndarray, ys: np.ndarray, xs: np.ndarray) -> np.ndarray:
    """(S, n): whether any 8-neighbour of each pixel (``ys``, ``xs``) is set in the (S, h, w) ``mask``."""
    padded = np.pad(mask, ((0, 0), (1, 1), (1, 1)))
    out = np.zeros((len(mask), len(ys)), bool)
    for dy in (0, 1, 2):
        for dx in (0, 1, 2):
            out |= padded[:, ys + dy, xs + dx]
    return out


def _largest_agreeing(values: np.ndarray, candidates: np.ndarray, floor: int) -> tuple[np.ndarray, np.ndarray]:
    """Per pixel of ``values`` (S, n, 3): whether the largest group of ``candidates`` (S, n) within ``floor`` of
    one has AGREEING of the samples and MIN_GROUP, and its median: (n,) bool, (n, 3) float."""
    agree = _within(values[:, None], values[None], floor)  # (S, S, n)
    agree &= candidates[:, None] & candidates[None]
    best = agree.sum(axis=1).argmax(axis=0)
    members = agree[best, :, np.arange(values.shape[1])].T  # (S, n)
    found = members.sum(axis=0) >= max(MIN_GROUP, AGREEING * len(values))
    grouped = np.where(members[..., None], values, np.nan).astype(np.float32)
    colour = np.zeros((values.shape[1], 3), np.float32)
    if found.any():
        colour[found] = np.round(np.nanmedian(grouped[:, found], axis=0))
    return found, colour
