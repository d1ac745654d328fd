"""Background estimation and silhouette extraction (paper, section 3.2), made robust: the per-pixel temporal
median of samples at one exposure, per-pixel noise thresholds, soft shadows removed, the mask reduced to the one
person-sized region (empty when nobody is there). Masks are in the pixels of the frames given
(`video.processing_scale`)."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from functools import cache, cached_property

import cv2
import numpy as np

from mocap.errors import MocapError
from mocap.image.percentile import percentile, row_medians
from mocap.io.video import VideoInfo, sample_frames
from mocap.silhouette.cleaning import clean_mask, cleaning_disk, mask_box

MAD_TO_SIGMA = 1.4826
_MEDIAN_PER_QUARTILE = 1.41  # median / lower quartile of the largest of three |normal|
_GAIN_SAMPLES = 1000  # pixels (on a regular grid) that estimate an exposure gain
K_SIGMA = 3.0  # noise sigmas a difference must exceed to be foreground
MIN_THRESHOLD = 12.0  # grey levels: compression artefacts of a very clean clip stay out
SHADOW_RATIO = (0.35, 0.95)  # a shadow darkens the background by a factor in this range
SHADOW_CHROMA = 0.12  # and keeps its colour within this share of its brightest channel
SHADOW_NCC = 0.5  # correlation with the background's texture that a shadow keeps


@dataclass(frozen=True)
class Background:
    """The empty scene: `image` (HxWx3 uint8 BGR), per-pixel `threshold` (HxW uint8 grey levels), the clip's
    noise `sigma` (grey levels); `held` (HxW bool or None): pixels the performer never left in the samples, where
    `image` is a guess; `stood` (HxW bool or None): where the clip's median showed the performer (plate)."""

    image: np.ndarray
    threshold: np.ndarray
    sigma: float
    held: np.ndarray | None = None
    stood: np.ndarray | None = None

    @cached_property
    def grey(self) -> np.ndarray:
        """The image in grey levels (the shadow test's texture), computed once."""
        return cv2.cvtColor(self.image, cv2.COLOR_BGR2GRAY)

    @cached_property
    def channel_threshold(self) -> np.ndarray:
        """The threshold for each of the three channels (HxWx3), computed once."""
        return cv2.merge([self.threshold] * 3)


def estimate_background(
    source: VideoInfo | Iterable[np.ndarray],
    n_samples: int = 30,
    scale: float = 1.0,
    k: float = K_SIGMA,
    min_threshold: float = MIN_THRESHOLD,
) -> Background:
    """Per-pixel temporal median (section 3.2) of frames brought to one exposure: `source` is a video
    (`n_samples` frames read at `scale`) or the frames; threshold `k` noise sigmas, at least `min_threshold`."""
    if isinstance(source, VideoInfo):
        frames = [f for _, f in sample_frames(source, n_samples, scale)]
    else:
        frames = list(source)
    stack = _check_frames(frames)
    grid = (slice(None), *_gain_grid(stack.shape[1:3]))  # all exposure_gain looks at
    reference = _median(stack[grid])
    for frame in stack:
        frame[:] = cv2.transform(frame, np.diag(exposure_gain(frame[grid[1:]], reference)))
    background = _median(stack)
    noise, sigma = _noise(stack, background)
    threshold = np.clip(k * noise, min_threshold, 255).astype(np.uint8)
    return Background(background, threshold, sigma)


def noise_floor(sigma: float) -> int:
    """The smallest difference threshold (grey levels) of a clip with noise `sigma`."""
    return int(np.clip(K_SIGMA * sigma, MIN_THRESHOLD, 255))


def _noise(stack: np.ndarray, background: np.ndarray) -> tuple[np.ndarray, float]:
    """Per-pixel noise sigma (HxW float32) of the largest channel difference, from the lower quartile over time
    (>= 5 frames: right where the performer stays), dilated, floored at the global one; and the global one."""
    deviation = np.stack([_largest_channel(cv2.absdiff(f, background)) for f in stack])
    sigma = MAD_TO_SIGMA * median_level(deviation)
    noise = np.full(background.shape[:2], sigma, np.float32)
    if len(stack) >= 5:
        quartile = _quantile(deviation, 0.25)
        local = cv2.dilate(MAD_TO_SIGMA * _MEDIAN_PER_QUARTILE * quartile, np.ones((3, 3)))
        noise = np.maximum(noise, local)
    return noise, sigma


def median_level(values: np.ndarray | list[np.ndarray]) -> float:
    """The median of uint8 images, from histogram counts (even count: the mean of the middle two)."""
    counts = sum(cv2.calcHist([image], [0], None, [256], [0, 256]).ravel().astype(np.int64) for image in values)
    cumulative = np.cumsum(counts)
    n = cumulative[-1]
    return 0.5 * float(np.searchsorted(cumulative, (n - 1) // 2 + 1) + np.searchsorted(cumulative, n // 2 + 1))


def _quantile(stack: np.ndarray, q: float, rows: int = 32) -> np.ndarray:
    """Per-pixel q-quantile over time of a uint8 stack (float32, numpy's interpolation), in row strips."""
    position = q * (len(stack) - 1)
    low = int(position)
    high = min(low + 1, len(stack) - 1)
    out = np.empty(stack.shape[1:], np.float32)
    for y in range(0, stack.shape[1], rows):
        ranked = _sorted(stack[:, y : y + rows])
        below = ranked[low].astype(np.float32)
        out[y : y + rows] = below + (position - low) * (ranked[high].astype(np.float32) - below)
    return out


def _sorted(stack: np.ndarray) -> list[np.ndarray]:
    """A uint8 stack sorted over its first axis pixel by pixel (Batcher's merge sort as cv2.min/max)."""
    size = 1 << (len(stack) - 1).bit_length()
    ranked = [np.ascontiguousarray(f) for f in stack] + [np.full(stack.shape[1:], 255, np.uint8)] * (size - len(stack))
    for a, b in _merge_sort_pairs(size):
        ranked[a], ranked[b] = cv2.min(ranked[a], ranked[b]), cv2.max(ranked[a], ranked[b])
    return ranked


@cache
def _merge_sort_pairs(n: int) -> tuple[tuple[int, int], ...]:
    """The compare-exchange pairs of Batcher's odd-even merge sort of n (a power of two)."""
    pairs = []
    p = 1
    while p < n:
        k = p
        while k >= 1:
            for j in range(k % p, n - k, 2 * k):
                pairs += [
                    (i + j, i + j + k) for i in range(min(k, n - j - k)) if (i + j) // (2 * p) == (i + j + k) // (2 * p)
                ]
            k //= 2
        p *= 2
    return tuple(pairs)


def _median(stack: np.ndarray) -> np.ndarray:
    """Per-pixel median over time of a uint8 frame stack, rounded."""
    return (_quantile(stack, 0.5) + 0.5).astype(np.uint8)


def _largest_channel(image: np.ndarray) -> np.ndarray:
    """The largest of the three channels of each pixel of a uint8 image."""
    b, g, r = cv2.split(image)
    return cv2.max(cv2.max(b, g), r)


def exposure_gain(frame: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Per-channel gains (3,) that bring `frame` to `reference`'s exposure: the median ratio over a grid of
    well-exposed pixels, redone on the three quarters agreeing best (the performer and shadows drop out)."""
    grid = _gain_grid(frame.shape[:2])
    f = _channel_rows(frame[grid].reshape(-1, 3))
    r = _channel_rows(reference[grid].reshape(-1, 3))
    usable = ((f > 8) & (f < 250) & (r > 8) & (r < 250)).all(axis=0)
    if not usable.any():
        return np.ones(3, np.float32)
    f, r = f[:, usable], r[:, usable]
    ratio = r / f
    residual = np.abs(f * row_medians(ratio)[:, None] - r).max(axis=0)
    keep = residual <= percentile(residual, 75)
    return row_medians(ratio[:, keep]).astype(np.float32)


def _gain_grid(shape: tuple[int, ...]) -> tuple[slice, slice]:
    """The regular grid of about _GAIN_SAMPLES pixels that an exposure gain is taken on."""
    stride = max(1, int(np.sqrt(shape[0] * shape[1] / _GAIN_SAMPLES)))
    return slice(None, None, stride), slice(None, None, stride)


def extract_silhouette(
    frame: np.ndarray,
    background: Background,
    shadow_ratio: tuple[float, float] = SHADOW_RATIO,
    shadow_chroma: float = SHADOW_CHROMA,
) -> np.ndarray:
    """The performer's silhouette in `frame` (HxW uint8 0/255, empty if nobody): module doc."""
    frame = at_exposure(frame, background)
    mask = foreground(frame, background)
    return clean_mask(
        remove_shadows(mask, frame, background, ratio=shadow_ratio, chroma=shadow_chroma), stood=background.stood
    )


def at_exposure(frame: np.ndarray, background: Background) -> np.ndarray:
    """`frame` brought to the background's exposure; ValueError if it does not match the background."""
    if frame.shape != background.image.shape or frame.dtype != np.uint8:
        raise ValueError(
            f"frame {frame.shape} {frame.dtype} does not match the background {background.image.shape} uint8"
        )
    return cv2.transform(frame, np.diag(exposure_gain(frame, background.image)))


def foreground(frame: np.ndarray, background: Background) -> np.ndarray:
    """Pixels (0/255) where any channel's difference exceeds the pixel's threshold."""
    over = cv2.compare(cv2.absdiff(frame, background.image), background.channel_threshold, cv2.CMP_GT)
    return cv2.compare(cv2.cvtColor(over, cv2.COLOR_BGR2GRAY), 0, cv2.CMP_GT)


def remove_shadows(mask: np.ndarray, frame: np.ndarray, background: Background, **shade) -> np.ndarray:
    """`mask` without its soft shadows (section 3.2's noted failure); ``shade``: shadow_candidates' ratio, chroma."""
    return without_shadows(mask, frame, background, shadow_candidates(mask, frame, background, **shade))


def shadow_candidates(
    mask: np.ndarray,
    frame: np.ndarray,
    background: Background,
    ratio: tuple[float, float] = SHADOW_RATIO,
    chroma: float = SHADOW_CHROMA,
) -> np.ndarray:
    """Pixels of `mask` (0/255) darker than the background by one factor in `ratio`, hue within `chroma`."""
    candidates = np.zeros_like(mask)
    box = mask_box(mask, 0)  # the work only where `mask` has pixels
    if box is None:
        return candidates
    frame, scene = np.ascontiguousarray(frame[box]), np.ascontiguousarray(background.image[box])
    grey = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    index = np.flatnonzero(cv2.bitwise_and(mask[box], cv2.compare(grey, background.grey[box], cv2.CMP_LT)).view(bool))
    f = _channel_rows(np.take(frame.reshape(-1, 3), index, axis=0))
    b = _channel_rows(np.take(scene.reshape(-1, 3), index, axis=0)) + 1.0
    level = f.sum(axis=0) / b.sum(axis=0)
    like = (
        (level > ratio[0]) & (level < ratio[1]) & (np.abs(f - level * b).max(axis=0) < chroma * level * b.max(axis=0))
    )
    inside = np.zeros(grey.shape, np.uint8)
    inside.reshape(-1)[index[like]] = 255
    candidates[box] = inside
    return candidates


def without_shadows(mask: np.ndarray, frame: np.ndarray, background: Background, candidates: np.ndarray) -> np.ndarray:
    """`mask` without the solid areas of shadow `candidates` that keep the background's texture."""
    box = shadow_box(candidates)
    if box is None:
        return mask
    grey = cv2.cvtColor(frame[box], cv2.COLOR_BGR2GRAY)
    shadow = np.zeros_like(mask)
    shadow[box] = cv2.morphologyEx(
        _textured_alike(candidates[box], grey, background.grey[box], background.sigma, mask.shape),
        cv2.MORPH_OPEN,
        cleaning_disk(mask.shape),
        borderType=cv2.BORDER_CONSTANT,
        borderValue=0,
    )
    return cv2.bitwise_and(mask, cv2.bitwise_not(shadow))


def shadow_box(candidates: np.ndarray, margin: int = 0) -> tuple[slice, slice] | None:
    """The box (slices) of the candidates' solid areas, plus the vote's reach and `margin`; None if none."""
    disk = cleaning_disk(candidates.shape)
    near = mask_box(candidates, disk.shape[0])  # the opening keeps nothing outside the candidates' box
    if near is None:
        return None
    x, y, w, h = cv2.boundingRect(cv2.morphologyEx(candidates[near], cv2.MORPH_OPEN, disk))
    if not w:
        return None
    x, y = x + near[1].start, y + near[0].start
    pad = 2 + _vote_size(candidates.shape) // 2 + margin
    return slice(max(0, y - pad), y + h + pad), slice(max(0, x - pad), x + w + pad)


def _textured_alike(
    candidates: np.ndarray, grey: np.ndarray, grey_bg: np.ndarray, sigma: float, frame_shape: tuple[int, ...]
) -> np.ndarray:
    """The shadow `candidates` (0/255) that keep the background's texture: a shadow scales it, so over 5x5 pixels
    the frame correlates with the background (over SHADOW_NCC) with at least half the darkened contrast, which
    cloth over a pattern does not. Only where that contrast clears K_SIGMA noise does it tell, so candidates vote
    within _vote_size (where none tells, over their connected piece)."""
    frame, bg = grey.astype(np.float32), grey_bg.astype(np.float32)
    frame_mean, frame_spread = _local_spread(frame)
    bg_mean, bg_spread = _local_spread(bg)
    covariance = cv2.blur(frame * bg, (5, 5)) - frame_mean * bg_mean
    expected = frame_mean / (bg_mean + 1.0) * bg_spread
    telling = (candidates > 0) & (expected > K_SIGMA * sigma)
    kept = telling & (covariance > SHADOW_NCC * frame_spread * bg_spread) & (frame_spread >= 0.5 * expected)
    keeps = kept.astype(np.float32)
    loses = (telling & ~kept & (frame_spread < expected)).astype(np.float32)
    size = (_vote_size(frame_shape),) * 2
    near_keeps = cv2.boxFilter(keeps, -1, size, normalize=False)
    near_loses = cv2.boxFilter(loses, -1, size, normalize=False)
    count, label = cv2.connectedComponents(cv2.morphologyEx(candidates, cv2.MORPH_OPEN, cleaning_disk(frame_shape)))
    piece = (np.bincount(label.ravel(), keeps.ravel(), count) >= np.bincount(label.ravel(), loses.ravel(), count))[
        label
    ]
    shadow = np.where(near_keeps + near_loses > 0, near_keeps >= near_loses, piece)
    return np.where(shadow & (candidates > 0), np.uint8(255), np.uint8(0))


def _vote_size(shape: tuple[int, ...]) -> int:
    """The side of the texture vote's window: about 5% of the frame height, odd."""
    return max(5, round(shape[0] / 20) | 1)


def _local_spread(image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation over 5x5 neighbourhoods."""
    mean = cv2.blur(image, (5, 5))
    return mean, np.sqrt(np.maximum(cv2.blur(image * image, (5, 5)) - mean * mean, 0.0))


def _check_frames(frames: list[np.ndarray]) -> np.ndarray:
    if not frames:
        raise MocapError("no frames to estimate the background from")
    shape = frames[0].shape
    if len(shape) != 3 or shape[2] != 3 or any(f.shape != shape or f.dtype != np.uint8 for f in frames):
        raise ValueError(f"background frames must all be HxWx3 uint8 BGR like the first, {shape} {frames[0].dtype}")
    return np.stack(frames)


def _channel_rows(pixels: np.ndarray) -> np.ndarray:
    """(N, 3) uint8 pixels as a C-ordered (3, N) float32 array: fast per-channel rows."""
    return np.ascontiguousarray(pixels.T, dtype=np.float32)
