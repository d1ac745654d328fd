"""A background that does not hold a performer who stays in place: the temporal median (section 3.2's "regions
that do not change") shows them wherever they stand over half the clip. ``performer_free``: (1) evidence, each
sample's difference from the median; (2) the region with evidence within a body part's radius on HALF the
samples, to its convex hull; (3) GrabCut (Rother et al., SIGGRAPH 2004) splits the median there; (4) pieces whose
colours are likelier in the evidence than the scene, grown by such colours, less steady pieces bordered by scene;
(5) there, the scene the samples uncover (``uncover``), else scene-coloured samples, else inpainted (``held``);
(6) the noise floor as threshold; (7) the pixels kept as ``stood``. Or the user's empty scene (``clean_plate``)."""

from __future__ import annotations

import os
from dataclasses import replace

import cv2
import numpy as np

from mocap.errors import MocapError
from mocap.io.video import VideoInfo, open_video, read_frame, sample_frames
from mocap.silhouette.background import (
    MAD_TO_SIGMA,
    Background,
    estimate_background,
    exposure_gain,
    foreground,
    median_level,
    noise_floor,
    remove_shadows,
)
from mocap.silhouette.uncover import uncovered_scene

HALF = 0.5  # evidence on at least this fraction of samples: the performer stays
RADIUS = 0.07  # of the evidence's height: a body part's reach around evidence
GRABCUT_ITERATIONS = 4
COLOUR_BINS = 16  # per channel, of the colour histograms that validate the pieces
BACKGROUND_FRAMES = 30  # frames whose median is the background (of the clip, or of the scene)
MIN_UNCOVERED = 3  # samples showing the scene before a pixel's scene is taken from them


def clip_background(
    info: VideoInfo, scale: float, source: str | os.PathLike | tuple[int, int] | None = None
) -> Background:
    """A clip's background: the user's empty scene (``clean_plate``) if `source` is given, else the median of
    BACKGROUND_FRAMES samples without the performer who stays (``performer_free``)."""
    if source is not None:
        return clean_plate(source, info, scale)
    samples = [f for _, f in sample_frames(info, BACKGROUND_FRAMES, scale)]
    return performer_free(estimate_background(samples), samples)


def performer_free(background: Background, frames: list[np.ndarray]) -> Background:
    """``background`` without the performer who stays in place (module doc); ``frames``: its samples."""
    frames = [cv2.transform(f, np.diag(exposure_gain(f, background.image))) for f in frames]
    masks = [_evidence(f, background) for f in frames]
    radius = _radius(masks)
    region = performer_region(masks, radius)
    if region is None:
        return background
    held_in_median, odds = _median_holds(background.image, region, radius, frames, masks)
    stood = held_in_median
    steady = _steady(background.image, frames, background.sigma)
    held_in_median = _without_steady_scene(held_in_median, steady)
    mixed = _mixed_around(held_in_median, steady, radius)
    image, held = _replate(
        background.image,
        held_in_median,
        mixed,
        np.stack(frames),
        np.stack(masks),
        radius,
        odds,
        noise_floor(background.sigma),
    )
    threshold = background.threshold.copy()
    threshold[dilated(region | held_in_median, _disk(radius)) > 0] = noise_floor(background.sigma)
    return replace(background, image=image, threshold=threshold, held=held, stood=stood)


def _evidence(frame: np.ndarray, background: Background) -> np.ndarray:
    """Pixels that differ from the background, shadows and speckle removed (0/255)."""
    mask = remove_shadows(foreground(frame, background), frame, background)
    return cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))


def _radius(masks: list[np.ndarray]) -> int:
    """A body part's reach: RADIUS of the median height of the samples' evidence."""
    heights = []
    for mask in masks:
        rows = np.flatnonzero(mask.any(axis=1))
        if len(rows):
            heights.append(rows[-1] - rows[0] + 1)
    return max(2, round(RADIUS * float(np.median(heights)))) if heights else 2


def performer_region(masks: list[np.ndarray], radius: int) -> np.ndarray | None:
    """The convex hull (0/1 uint8) of pixels with evidence within ``radius`` on HALF the samples, or None."""
    disk = _disk(radius)
    count = np.zeros(masks[0].shape, np.float32)
    for mask in masks:
        count += dilated(mask, disk) > 0
    points = cv2.findNonZero((count >= HALF * len(masks)).astype(np.uint8))
    if points is None:
        return None
    region = np.zeros(masks[0].shape, np.uint8)
    cv2.fillConvexPoly(region, cv2.convexHull(points), 1)
    return region


def _median_holds(
    image: np.ndarray, region: np.ndarray, radius: int, frames: list[np.ndarray], masks: list[np.ndarray]
) -> np.ndarray:
    """Pixels (bool) where the median image shows the performer (steps 3-4), and the colour odds."""
    disk = _disk(radius)
    around = dilated(region, disk)
    cut = np.full(region.shape, cv2.GC_BGD, np.uint8)
    cut[around > 0] = cv2.GC_PR_BGD
    cut[region > 0] = cv2.GC_PR_FGD
    x, y, w, h = cv2.boundingRect(dilated(around, disk))
    cut_fg = np.zeros(region.shape, np.uint8)
    cut_fg[y : y + h, x : x + w] = _grabcut(image[y : y + h, x : x + w], cut[y : y + h, x : x + w])
    near = dilated(cut_fg, disk) > 0
    performer = np.concatenate([f[(m > 0) & ~near] for f, m in zip(frames, masks)])
    odds = _colour_odds(performer, image[around == 0])
    if not cut_fg.any():
        return cut_fg > 0, odds
    like = _odds_of(image, odds) > 1.0
    return _joined(_majority_pieces(cut_fg, like), like), odds


def _grabcut(image: np.ndarray, cut: np.ndarray) -> np.ndarray:
    """GrabCut's foreground (0/1 uint8) of ``image`` seeded by ``cut`` (its GC_* labels)."""
    cut = cut.copy()
    models = (np.zeros((1, 65)), np.zeros((1, 65)))
    cv2.setRNGSeed(0)  # GrabCut's colour models start from k-means: the same clip, the same cut
    cv2.grabCut(np.ascontiguousarray(image), cut, None, *models, GRABCUT_ITERATIONS, cv2.GC_INIT_WITH_MASK)
    return ((cut == cv2.GC_FGD) | (cut == cv2.GC_PR_FGD)).astype(np.uint8)


def _colour_odds(performer: np.ndarray, scene: np.ndarray) -> np.ndarray:
    """A COLOUR_BINS^3 table: how much likelier each colour is among ``performer`` than ``scene`` pixels."""
    return _histogram(performer) / _histogram(scene)


def _histogram(samples: np.ndarray) -> np.ndarray:
    hist = np.ones(COLOUR_BINS**3)
    if len(samples):
        hist += np.bincount(_colour_code(samples), minlength=COLOUR_BINS**3)
    return hist / hist.sum()


def _odds_of(pixels: np.ndarray, odds: np.ndarray) -> np.ndarray:
    """The colour odds of each pixel of an (..., 3) array."""
    return odds[_colour_code(pixels.reshape(-1, 3))].reshape(pixels.shape[:-1])


def _colour_code(pixels: np.ndarray) -> np.ndarray:
    """The COLOUR_BINS^3 histogram bin of each (N, 3) uint8 pixel."""
    q = pixels // np.uint8(256 // COLOUR_BINS)
    return (q[:, 0].astype(np.uint16) * COLOUR_BINS + q[:, 1]) * COLOUR_BINS + q[:, 2]


def _majority_pieces(pieces: np.ndarray, like: np.ndarray) -> np.ndarray:
    """The connected pieces (bool) of which more than half the pixels are ``like``."""
    n, label = cv2.connectedComponents(pieces)
    inside = pieces > 0
    votes = np.bincount(label[inside], weights=like[inside], minlength=n)
    sizes = np.maximum(np.bincount(label[inside], minlength=n), 1)
    return inside & (votes / sizes > 0.5)[label]


def _joined(holds: np.ndarray, like: np.ndarray) -> np.ndarray:
    """``holds`` and the performer-coloured ``like`` pixels connected to it (legs under jabbing arms)."""
    n, label = cv2.connectedComponents((holds | like).astype(np.uint8))
    joined = np.zeros(n, bool)
    joined[label[holds]] = True
    joined[0] = False
    return joined[label]


def _steady(image: np.ndarray, frames: list[np.ndarray], sigma: float) -> np.ndarray:
    """Pixels (bool) where HALF of the ``frames`` show the median within the noise floor: a stable view."""
    floor = noise_floor(sigma)
    agree = np.zeros(image.shape[:2], np.float32)
    for frame in frames:
        agree += cv2.absdiff(frame, image).max(axis=2) <= floor
    return agree >= HALF * len(frames)


def _without_steady_scene(holds: np.ndarray, steady: np.ndarray) -> np.ndarray:
    """``holds`` without its steady 4-connected pieces bordered mostly outside it: scene taken in by its colour,
    as a still part of the performer is bordered by moving parts the held region takes in too."""
    n, label = cv2.connectedComponents((holds & steady).astype(np.uint8), connectivity=4)
    if n < 2:
        return holds
    border = cv2.dilate(label.astype(np.float32), np.ones((3, 3), np.uint8)).astype(np.int32)
    ring = (border > 0) & (label == 0)
    outside = np.bincount(border[ring], weights=~holds[ring], minlength=n)
    total = np.maximum(np.bincount(border[ring], minlength=n), 1)
    drop = outside / total > HALF
    drop[0] = False
    return holds & ~drop[label]


def _mixed_around(holds: np.ndarray, steady: np.ndarray, radius: int) -> np.ndarray:
    """Pixels (bool) joined to ``holds`` within ``radius`` that no steady view covers (a mix there)."""
    near = dilated(holds.astype(np.uint8), _disk(radius)) > 0
    return _joined(holds, near & ~steady) & ~holds


def _replate(
    image: np.ndarray,
    holds: np.ndarray,
    mixed: np.ndarray,
    frames: np.ndarray,
    masks: np.ndarray,
    radius: int,
    odds: np.ndarray,
    floor: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Step 5: the median image with the scene put back where it ``holds`` the performer or is ``mixed`` (there
    only where uncovered), and the pixels left to inpainting (bool)."""
    scene, seen = uncovered_scene(image, holds | mixed, frames, floor)
    image = np.where((mixed & seen)[..., None], scene, image)
    seen &= holds
    coloured, by_colour = _scene_coloured(image, holds & ~seen, frames, masks, odds)
    plate = np.where(seen[..., None], scene, coloured)
    held = holds & ~seen & ~by_colour
    if held.any():
        plate = cv2.inpaint(plate, held.astype(np.uint8), radius, cv2.INPAINT_TELEA)
    return plate, held


def _scene_coloured(
    image: np.ndarray, holds: np.ndarray, frames: np.ndarray, masks: np.ndarray, odds: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``image`` with the median of the scene-coloured samples that differ from it (``masks``) where it ``holds``
    the performer and MIN_UNCOVERED do, and where they do (bool)."""
    index = np.flatnonzero(holds)
    plate = image.copy()
    seen = np.zeros(holds.shape, bool)
    if not len(index):
        return plate, seen
    values = frames.reshape(len(frames), -1, 3)[:, index]
    uncovered = (masks.reshape(len(masks), -1)[:, index] > 0) & (_odds_of(values, odds) < 1.0)
    found = uncovered.sum(axis=0) >= MIN_UNCOVERED
    values = values.astype(np.float32)
    values[~uncovered] = np.nan
    plate.reshape(-1, 3)[index[found]] = np.round(np.nanmedian(values[:, found], axis=0)).astype(np.uint8)
    seen.reshape(-1)[index[found]] = True
    return plate, seen


def _disk(radius: int) -> np.ndarray:
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))


def dilated(mask: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """``cv2.dilate`` of a mask by a centred ``kernel``, computed only within reach of the mask's box."""
    x, y, w, h = cv2.boundingRect(mask)
    out = np.zeros_like(mask)
    if not w:
        return out
    ry, rx = kernel.shape[0] // 2, kernel.shape[1] // 2
    box = slice(max(0, y - ry), y + h + ry), slice(max(0, x - rx), x + w + rx)
    out[box] = cv2.dilate(mask[box], kernel)
    return out


# -- the empty scene given by the user -----------------------------------------------


def clean_plate(source: str | os.PathLike | tuple[int, int], info: VideoInfo, scale: float) -> Background:
    """The background from the user's empty scene (a photo, a video's median, or clip frames (first, last)) in
    the clip's size and tones (``scene_image``); threshold: the noise floor of the clip against it."""
    if isinstance(source, tuple):
        first, last = source
        if not 0 <= first <= last < info.frame_count:
            raise MocapError(f"background frames {first}..{last} are not within the video's {info.frame_count} frames")
        indices = np.unique(np.linspace(first, last, min(BACKGROUND_FRAMES, last - first + 1)).round())
        image = _median([read_frame(info, int(i), scale) for i in indices])
    else:
        image = _plate_image(str(source), (info.width, info.height))
    samples = [f for _, f in sample_frames(info, BACKGROUND_FRAMES, scale)]
    if samples[0].shape != image.shape:
        image = cv2.resize(image, samples[0].shape[1::-1], interpolation=cv2.INTER_AREA)
    image = scene_image(image, estimate_background(samples))
    deviation = [cv2.absdiff(cv2.transform(f, np.diag(exposure_gain(f, image))), image).max(axis=2) for f in samples]
    sigma = MAD_TO_SIGMA * median_level(deviation)
    return Background(image, np.full(image.shape[:2], noise_floor(sigma), np.uint8), sigma)


def scene_image(plate: np.ndarray, median: Background) -> np.ndarray:
    """The clip's ``median`` where it shows the scene (it has the frames' camera, blur and encoding), the
    ``plate`` in the clip's tones where they differ by over the noise floor (opened 3x3, grown two pixels)."""
    plate = match_tones(plate, median.image)
    differs = cv2.compare(cv2.absdiff(plate, median.image).max(axis=2), noise_floor(median.sigma), cv2.CMP_GT)
    holds = cv2.dilate(cv2.morphologyEx(differs, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8)), _disk(2)) > 0
    image = median.image.copy()
    image[holds] = plate[holds]
    return image


def match_tones(plate: np.ndarray, scene: np.ndarray, rounds: int = 3) -> np.ndarray:
    """``plate`` mapped per channel onto the tones of ``scene`` (the clip's median) by a gain and offset, least
    squares refitted ``rounds`` times within 2.5 robust sigmas."""
    out = []
    for p, s in zip(cv2.split(plate), cv2.split(scene)):
        p, s = p.ravel().astype(np.float32), s.ravel().astype(np.float32)
        keep = np.ones(p.size, bool)
        for _ in range(rounds):
            gain, offset = np.polyfit(p[keep], s[keep], 1)
            residual = np.abs(gain * p + offset - s)
            keep = residual <= max(2.0, 2.5 * MAD_TO_SIGMA * float(np.median(residual)))
        lut = np.clip(gain * np.arange(256.0) + offset + 0.5, 0, 255).astype(np.uint8)
        out.append(cv2.LUT(p.reshape(plate.shape[:2]).astype(np.uint8), lut))
    return cv2.merge(out)


def _plate_image(path: str, size: tuple[int, int]) -> np.ndarray:
    """A photo of the empty scene or a video's median; MocapError unless of the clip's frame shape."""
    if os.path.isdir(path):
        raise MocapError(f"{path}: is a folder, not a background image or video")
    if not os.path.isfile(path):
        raise MocapError(f"{path}: no such background image or video")
    if cv2.haveImageReader(path):
        image = cv2.imread(path, cv2.IMREAD_COLOR)
        if image is None:
            raise MocapError(f"{path}: the background image cannot be read")
    else:
        plate_video = open_video(path)
        image = _median([f for _, f in sample_frames(plate_video, BACKGROUND_FRAMES)])
    h, w = image.shape[:2]
    if abs(w * size[1] - h * size[0]) > max(w, h):
        raise MocapError(f"{path}: the background is {w}x{h}, the video {size[0]}x{size[1]}: not the same shape")
    return image


def _median(frames: list[np.ndarray]) -> np.ndarray:
    return np.median(np.stack(frames), axis=0).round().astype(np.uint8)
