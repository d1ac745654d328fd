"""The silhouette's pixels where body and scene blend: an outline pixel is partly both (lens, antialiasing and
codec blur), so thresholded silhouettes run about a pixel wide and closing bridges slits. As a blend (Porter and
Duff, SIGGRAPH 1984: I = alpha F + (1 - alpha) B, F the body colour beside it) a pixel is kept where the body
covers half of it. That *cover* is written out as masks; the 2D fit keeps the plain thresholded silhouette."""

from __future__ import annotations

import cv2
import numpy as np

from mocap.silhouette.background import (
    Background,
    at_exposure,
    foreground,
    shadow_box,
    shadow_candidates,
    without_shadows,
)
from mocap.silhouette.cleaning import clean_mask

SHADOW_ANGLE = 0.06  # radians: a shadow's mean hue over 5x5 pixels from the scene's (the cover's)
MIN_ALPHA = 0.5  # the share of a pixel the body covers for it to be the body's
CLEAR = 2.0  # thresholds between body and scene colour for an alpha to be read
_SQUARE = np.ones((3, 3), np.uint8)
_REACH = 2  # pixels: the widest window's (5x5) reach around a pixel


def silhouette_and_cover(frame: np.ndarray, background: Background) -> tuple[np.ndarray, np.ndarray]:
    """The 2D fit's silhouette of ``frame`` (``background.extract_silhouette``) and its cover (0/255 each):
    shadows also told by hue (``keeps_hue``), cleaned, less pixels under MIN_ALPHA body (``trim_blends``)."""
    frame = at_exposure(frame, background)
    differs = foreground(frame, background)
    candidates = shadow_candidates(differs, frame, background)
    hued = keeps_hue(candidates, frame, background)
    plain = without_shadows(differs, frame, background, candidates)
    fit = clean_mask(plain, stood=background.stood)
    if cv2.countNonZero(hued) == cv2.countNonZero(candidates):
        return fit, trim_blends(fit, plain, frame, background.image, background.threshold)
    body = without_shadows(differs, frame, background, hued)
    return fit, trim_blends(
        clean_mask(body, stood=background.stood), body, frame, background.image, background.threshold
    )


def keeps_hue(
    candidates: np.ndarray, frame: np.ndarray, background: Background, angle: float = SHADOW_ANGLE
) -> np.ndarray:
    """The shadow ``candidates`` (0/255) whose mean residual from the darkened background over 5x5 pixels is
    within ``angle`` radians of their mean colour (a shadow darkens all channels alike, dark cloth of the scene's
    hue is a few degrees off); all stay where the background is a guess (``held``)."""
    box = shadow_box(candidates, margin=2)  # the rest stays, whatever its hue
    if box is None:
        return candidates
    near = np.ascontiguousarray(candidates[box])
    index = np.flatnonzero(near)
    colour = frame[box].reshape(-1, 3)[index].astype(np.float32)
    behind = background.image[box].reshape(-1, 3)[index].astype(np.float32) + 1.0
    residual = colour - (colour.sum(axis=1) / behind.sum(axis=1))[:, None] * behind
    sums = np.zeros((near.size, 6), np.float32)
    sums[index] = np.concatenate([residual, colour], axis=1)
    sums = cv2.blur(sums.reshape(*near.shape, 6), (5, 5), borderType=cv2.BORDER_CONSTANT).reshape(-1, 6)[index]
    off = np.linalg.norm(sums[:, :3], axis=1) >= angle * np.linalg.norm(sums[:, 3:], axis=1)
    if background.held is not None:
        off &= ~background.held[box].reshape(-1)[index]
    near.reshape(-1)[index[off]] = 0
    out = candidates.copy()
    out[box] = near
    return out


def trim_blends(
    person: np.ndarray, differs: np.ndarray, frame: np.ndarray, scene: np.ndarray, threshold: np.ndarray
) -> np.ndarray:
    """``person`` (0/255) without pixels the body covers under MIN_ALPHA of: those cleaning added (not in
    ``differs``), then the outline, each against body pixels near. ``frame``, ``scene``: BGR at one exposure;
    ``threshold``: grey levels. A pixel stays with no body near, or body and scene within CLEAR thresholds."""
    x, y, w, h = cv2.boundingRect(person)
    if not w:
        return person
    box = (slice(max(0, y - 1), y + h + 1), slice(max(0, x - 1), x + w + 1))
    frame, scene, threshold, near, differs = (  # each window's reach (two) beyond the box: none
        cv2.copyMakeBorder(a[box], _REACH, _REACH, _REACH, _REACH, cv2.BORDER_CONSTANT, value=0)
        for a in (frame, scene, threshold, person, differs)
    )
    frame, scene = frame.astype(np.float32), scene.astype(np.float32)
    near = _drop(near, np.flatnonzero(cv2.subtract(near, differs)), differs, 5, frame, scene, threshold)
    inner = cv2.erode(near, _SQUARE)
    further = cv2.subtract(inner, cv2.erode(inner, _SQUARE))
    out = person.copy()
    out[box] = _drop(near, np.flatnonzero(cv2.subtract(near, inner)), further, 3, frame, scene, threshold)[
        _REACH:-_REACH, _REACH:-_REACH
    ]
    return out


def _drop(
    mask: np.ndarray,
    index: np.ndarray,
    body: np.ndarray,
    window: int,
    frame: np.ndarray,
    scene: np.ndarray,
    threshold: np.ndarray,
) -> np.ndarray:
    """``mask`` less the flat ``index`` pixels (``window`` // 2 from the edges) under MIN_ALPHA of the mean
    ``body`` colour in their window; ``frame``, ``scene`` float32."""
    if not len(index):
        return mask
    count, total = _window_sums(body > 0, frame, index, window)
    index, count, total = index[count > 0], count[count > 0], total[count > 0]
    behind = scene.reshape(-1, 3)[index]
    colour = total / count[:, None] - behind
    reach = (colour * colour).sum(axis=1)
    alpha = ((frame.reshape(-1, 3)[index] - behind) * colour).sum(axis=1) / np.maximum(reach, 1.0)
    clear = reach > (CLEAR * threshold.reshape(-1)[index].astype(np.float32)) ** 2
    out = mask.copy()
    out.reshape(-1)[index[(alpha < MIN_ALPHA) & clear]] = 0
    return out


def _window_sums(
    chosen: np.ndarray, image: np.ndarray, index: np.ndarray, window: int
) -> tuple[np.ndarray, np.ndarray]:
    """How many ``chosen`` (bool) pixels each ``window`` around the flat ``index`` pixels (``window`` // 2 from
    the edges) holds, and the sum of their ``image`` colours."""
    r, width = window // 2, chosen.shape[1]
    around = index[:, None] + (np.arange(-r, r + 1)[:, None] * width + np.arange(-r, r + 1)).ravel()
    weight = chosen.reshape(-1)[around]
    return weight.sum(axis=1).astype(np.float32), (image.reshape(-1, 3)[around] * weight[..., None]).sum(axis=1)
