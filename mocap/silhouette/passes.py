"""The silhouette method's two streamed passes over a video: silhouettes (section 3.2), kept as bit-packed crops,
then the 2D fit (section 3.3) on each crop normalised to the model's size, the body's height taken from the
silhouettes around each frame (so a performer walking toward the camera keeps a right scale)."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, replace
from functools import partial

import cv2
import numpy as np

from mocap.body import BODY_HEIGHT, JOINTS, STANDING_PERCENTILE, reported_joints
from mocap.image.percentile import nanpercentile, percentile
from mocap.io.video import VideoInfo, iter_frames
from mocap.person import Landmarks, PersonModel, PersonView, open_person_model, watched
from mocap.person.isolated import IsolatedLook
from mocap.person.mirrored import disputed
from mocap.person.steady import short_runs_dropped, steadied
from mocap.silhouette.background import Background, extract_silhouette
from mocap.silhouette.eyes import centred_on, crowned, fit_targets, fused_mask, soled
from mocap.silhouette.fit2d import FIT_BODY_PX, FIT_SCALE, Fit2D, fit_frame
from mocap.silhouette.legchain import LAG_S, LegChain
from mocap.silhouette.plate import clip_background
from mocap.silhouette.torso import head_top_row, torso_spread, torso_width_readable

MIN_PERSON_FRACTION = 0.002  # of the frame's area: smaller blobs are nobody
SCALE_WINDOW_S = 1.0  # half-width of the body height's window, seconds
MARGIN = 0.25  # of the body height, around the silhouette's box when fitting
SPREAD_PERCENTILE = 5  # of torso foreshortening estimates around a frame: the fit's
LIFT_SPREAD_PERCENTILE = 20  # of the readable ones around a frame: the lift's
SPREAD_FALLBACK_PERCENTILE = 50  # of all of them, the lift's where none is readable
SPREAD_WINDOW_S = 0.5  # half-width of that window, seconds
MIN_TRACK_SCORE = 0.5  # a previous fit below this is not used as a search centre


@dataclass(frozen=True)
class Silhouette:
    """A frame's silhouette: ``box`` (processing pixels) and the packed mask ``bits`` in it, the frame's ``grey``
    levels there (mocap.image.edges); with a person model, its ``landmarks`` and the pixels its mask gave
    (``learned``, packed like ``bits``)."""

    box: tuple[int, int, int, int]  # x0, y0, x1, y1 in processing pixels
    bits: np.ndarray
    grey: np.ndarray | None = None
    landmarks: Landmarks | None = None
    learned: np.ndarray | None = None

    @classmethod
    def from_mask(
        cls,
        mask: np.ndarray,
        frame: np.ndarray | None = None,
        landmarks: Landmarks | None = None,
        learned: np.ndarray | None = None,
    ) -> "Silhouette | None":
        if not holds_person(mask):
            return None
        x, y, w, h = cv2.boundingRect(mask if mask.dtype == np.uint8 else (mask > 0).astype(np.uint8))
        grey = None if frame is None else cv2.cvtColor(frame[y : y + h, x : x + w], cv2.COLOR_BGR2GRAY)
        learned = None if learned is None else np.packbits(learned[y : y + h, x : x + w])
        return cls((x, y, x + w, y + h), np.packbits(mask[y : y + h, x : x + w] > 0), grey, landmarks, learned)

    @property
    def height(self) -> int:
        return self.box[3] - self.box[1]

    def mask(self) -> np.ndarray:
        return self._unpacked(self.bits)

    @property
    def cut_out(self) -> bool:
        """Whether the person model named the joints only when shown the figure cut out (person.isolated): its
        landmarks without its mask's pixels."""
        return self.landmarks is not None and self.learned is None

    def learned_mask(self) -> np.ndarray | None:
        """(h, w) 0/1 in the box: the pixels the person model's mask gave; None without it."""
        return None if self.learned is None else self._unpacked(self.learned)

    def _unpacked(self, bits: np.ndarray) -> np.ndarray:
        x0, y0, x1, y1 = self.box
        return np.unpackbits(bits, count=(x1 - x0) * (y1 - y0)).reshape(y1 - y0, x1 - x0)


def holds_person(mask: np.ndarray) -> bool:
    """Whether a mask (nonzero = inside) is somebody: at least MIN_PERSON_FRACTION of the frame."""
    count = np.count_nonzero(mask)
    return count > 0 and count >= MIN_PERSON_FRACTION * mask.size


@dataclass(frozen=True)
class FrameFit:
    """The fit of one frame: joints (16, 2) in video pixels (image sides); None where nobody was found."""

    index: int
    joints2d: np.ndarray | None
    score: float | None
    fit: Fit2D | None = None
    body_px: float | None = None  # video pixels of the model's 175-unit body height
    spread: float | None = None  # the torso's spread as the lift reads it (lift_spread)
    landmarks: Landmarks | None = None  # a person model's (mocap.person), in video pixels


def iter_silhouettes(
    info: VideoInfo, scale: float, background: Background | None = None, person: PersonModel | None = None
) -> Iterator[Silhouette | None]:
    """Pass one (section 3.2): each frame's Silhouette or None (background: ``plate.clip_background`` unless
    given); with a ``person`` model, fused with its mask and landmarks (``eyes.fused_mask``), its sight steadied
    (``person.steady.steadied``), a look at the figure cut out where it sees nobody or wavers (``silhouette_seen``;
    runs of such looks shorter than ``steady.MIN_RUN_S`` dropped), the landmarks' head top and ankles placed on the
    silhouette (``eyes.crowned``, ``eyes.soled``)."""
    background = background or clip_background(info, scale)
    seen = watched(person, (frame for _, frame in iter_frames(info, scale=scale)))
    if person is not None:
        seen = steadied(seen, info.fps, partial(fresh_model, person, person.with_mirror))
    second = IsolatedLook(None if person is None else partial(fresh_model, person))
    try:
        silhouettes = (silhouette_seen(frame, view, background, second) for frame, view in seen)
        yield from short_runs_dropped(silhouettes, info.fps, _named, _without_cut_out)
    finally:
        second.close()


def fresh_model(person: PersonModel, with_mirror: bool) -> PersonModel:
    """A fresh instance of the ``person`` model, looking also at mirror images ``with_mirror``."""
    return open_person_model(person.name, person.filtered, with_mirror=with_mirror)


def _named(silhouette: Silhouette | None) -> bool:
    return silhouette is not None and silhouette.landmarks is not None


def _without_cut_out(silhouette: Silhouette) -> Silhouette:
    """The silhouette without the landmarks of a look at it cut out (Silhouette.cut_out)."""
    return replace(silhouette, landmarks=None) if silhouette.cut_out else silhouette


def silhouette_seen(
    frame: np.ndarray, view: PersonView | None, background: Background, second: IsolatedLook
) -> Silhouette | None:
    """A frame's Silhouette: background subtraction's, fused with the person model's ``view`` of the frame, its
    ``second`` look at the figure cut out (person.isolated) a further opinion where the view is a look back's or its
    two looks dispute a limb pair's naming (person.mirrored.disputed); where it saw nobody, that look at the figure
    background subtraction found alone."""
    classical = extract_silhouette(frame, background)
    fused = None if view is None else fused_mask(classical, view.mask, background.held)
    if fused is not None:
        mask, learned = fused
        marks = view.landmarks
        if view.looked_back or disputed(marks):
            marks = second.second_opinion(marks, frame, mask)
        return Silhouette.from_mask(mask, frame, soled(crowned(marks, mask), mask), learned)
    named = second.landmarks(frame, classical) if second.able and holds_person(classical) else None
    if named is None:
        return Silhouette.from_mask(classical, frame)
    return Silhouette.from_mask(classical, frame, soled(crowned(named, classical), classical))


def body_heights(silhouettes: list[Silhouette | None], fps: float) -> np.ndarray:
    """The standing body height in pixels around each frame (NaN where nobody is): a high percentile within
    SCALE_WINDOW_S of the heights from the head's top (``head_to_feet``, not a raised hand's)."""
    half = half_window(SCALE_WINDOW_S, fps)
    h = np.array([np.nan if s is None else s.height for s in silhouettes], float)
    rough = rolling_percentile(h, half, STANDING_PERCENTILE)
    for i, sil in enumerate(silhouettes):
        if sil is not None:
            h[i] = head_to_feet(sil, rough[i])
    return rolling_percentile(h, half, STANDING_PERCENTILE)


def head_to_feet(sil: Silhouette, rough: float) -> float:
    """A silhouette's height from the head's top to the feet, given a rough body height in pixels."""
    return sil.height - head_top_row(sil.mask(), rough * FIT_SCALE / FIT_BODY_PX)


def normalise(sil: Silhouette, body_px: float) -> tuple[np.ndarray, np.ndarray, float]:
    """The silhouette cropped with a MARGIN and resized so that ``body_px`` becomes FIT_BODY_PX; returns (mask,
    origin in processing pixels, processing pixels per fit pixel)."""
    pad = int(np.ceil(MARGIN * body_px))
    small = _fit_sized(sil.mask() * 255, pad, FIT_BODY_PX / body_px) > 127
    origin = np.array([sil.box[0] - pad, sil.box[1] - pad], float)
    return small.astype(np.uint8), origin, (sil.box[2] - sil.box[0] + 2 * pad) / small.shape[1]


def normalised_grey(sil: Silhouette, body_px: float) -> np.ndarray | None:
    """The silhouette's grey levels cropped and resized as ``normalise`` does its mask."""
    if sil.grey is None:
        return None
    return _fit_sized(sil.grey, int(np.ceil(MARGIN * body_px)), FIT_BODY_PX / body_px)


def _fit_sized(image: np.ndarray, pad: int, factor: float) -> np.ndarray:
    """An image with a black margin of ``pad`` pixels, resized by ``factor``."""
    padded = cv2.copyMakeBorder(image, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=0)
    h, w = padded.shape
    size = (max(1, round(w * factor)), max(1, round(h * factor)))
    return cv2.resize(padded, size, interpolation=cv2.INTER_AREA if factor < 1 else cv2.INTER_LINEAR)


def rolling_percentile(values: np.ndarray, half: int, q: float) -> np.ndarray:
    """The q-th percentile of the finite values within +-half of each finite entry."""
    out = np.full(len(values), np.nan)
    for i in np.flatnonzero(np.isfinite(values)):
        out[i] = window_percentile(values, i, half, q)
    return out


def window_percentile(values, i: int, half: int, q: float) -> float:
    """The q-th percentile of the finite values within +-half of entry i."""
    return nanpercentile(np.asarray(values[max(0, i - half) : i + half + 1], float), q)


def torso_reads(sil: Silhouette, height: float, small: np.ndarray | None = None) -> tuple[float, float, bool]:
    """A frame's torso spread as the fit reads it (normalised to ``height``) and as the lift does (at the
    processing resolution, finer), and whether its width is readable; ``small``: ``normalise``'s mask if at hand."""
    small = normalise(sil, height)[0] if small is None else small
    return (
        torso_spread(small, FIT_SCALE),
        torso_spread(sil.mask(), height * FIT_SCALE / FIT_BODY_PX),
        torso_width_readable(small, FIT_SCALE, FIT_BODY_PX),
    )


def lift_spread(spreads, readable, i: int, half: int) -> float:
    """A frame's torso spread (section 3.4, |cos yaw|) for the lift: a low percentile of the readable ones within
    +-half, the median of all where none is (the fit's percentile of all reads arms up or a crouch as profile)."""
    lo, hi = max(0, i - half), i + half + 1
    values = np.asarray(spreads[lo:hi], float)
    good = values[np.asarray(readable[lo:hi], bool) & np.isfinite(values)]
    if len(good):
        return percentile(good, LIFT_SPREAD_PERCENTILE)
    return nanpercentile(values, SPREAD_FALLBACK_PERCENTILE)


def half_window(seconds: float, fps: float) -> int:
    """Frames in a half-window of ``seconds``."""
    return max(1, int(round(seconds * fps)))


def iter_fits(silhouettes: list[Silhouette | None], scale: float, fps: float) -> Iterator[FrameFit]:
    """Pass two (section 3.3) over a whole clip's silhouettes: each frame's fit (``FitStream``)."""
    stream = FitStream(scale, fps)
    for sil in silhouettes:
        yield from stream.push(sil)
    yield from stream.finish()


class Fitter:
    """Pass two's frames in order, searches centred on the previous fit, legs chosen LAG_S later."""

    def __init__(self, scale: float, fps: float):
        self.scale, self.chain = scale, LegChain(half_window(LAG_S, fps))
        self.latest: FrameFit | None = None  # the last frame fitted, legs not yet chosen

    def fit(
        self,
        index: int,
        sil: Silhouette | None,
        height: float,
        spread: float,
        lift_spread: float,
        normalised: tuple | None = None,
    ) -> list[FrameFit]:
        """Fit a frame with the torso's ``spread`` (``normalised``: ``normalise(sil, height)`` if at hand);
        returns the fits now decided, ``latest`` holding this frame's fit with the best path's legs until then."""
        self.latest = None
        if sil is None:
            return list(_frame_fits(self.chain.push(index, None), self.scale))
        small, origin, step = normalised or normalise(sil, height)
        best = self.chain.current
        prev = best.pose if best is not None and best.score >= MIN_TRACK_SCORE else None
        targets = fit_targets(sil.landmarks, origin, step, FIT_SCALE, prev)
        fit = fit_frame(small, FIT_SCALE, centred_on(prev, targets), spread, normalised_grey(sil, height), targets)
        landmarks = None if sil.landmarks is None else sil.landmarks.scaled(1.0 / self.scale)
        item = (index, origin, step, lift_spread, landmarks)
        decided = list(_frame_fits(self.chain.push(item, fit), self.scale))
        if not decided or decided[-1].index != index:
            self.latest = next(_frame_fits([(item, self.chain.current)], self.scale))
        return decided

    def flush(self) -> list[FrameFit]:
        """The fits still held, at the end of the video."""
        return list(_frame_fits(self.chain.flush(), self.scale))


class FitStream:
    """Pass two alongside pass one: ``push`` each silhouette to get the fits now decided, ``finish`` for the
    rest. A frame is fitted once its chained windows' silhouettes are in, so the fits equal whole-clip ones."""

    def __init__(self, scale: float, fps: float):
        self.scale, self.fitter = scale, Fitter(scale, fps)
        self.height_half = half_window(SCALE_WINDOW_S, fps)
        self.spread_half = half_window(SPREAD_WINDOW_S, fps)
        self.silhouettes: list[Silhouette | None] = []
        self._sizes: list[float] = []  # silhouette heights, NaN where nobody is
        self._standing: list[float] = []  # their heights from the head's top (head_to_feet)
        self._heights: list[float] = []  # body heights (body_heights) known so far
        self._spreads: list[float] = []  # per-frame torso spreads (torso.torso_spread)
        self._lift_reads: list[float] = []  # the same at the processing resolution (torso_reads)
        self._readable: list[bool] = []  # whether each is trusted (torso.torso_width_readable)
        self._normalised: dict[int, tuple] = {}  # frames read but not fitted yet: normalise's
        self._fitted = 0
        self._provisional: list[FrameFit] = []

    def push(self, sil: Silhouette | None) -> list[FrameFit]:
        self.silhouettes.append(sil)
        self._sizes.append(np.nan if sil is None else sil.height)
        return self._advance(False)

    @property
    def provisional(self) -> list[FrameFit]:
        """Fits of the last push whose legs are not chosen yet, with the best path's legs."""
        return self._provisional

    def finish(self) -> list[FrameFit]:
        return self._advance(True) + self.fitter.flush()

    def _advance(self, end: bool) -> list[FrameFit]:
        n, out, half = len(self.silhouettes), [], self.height_half
        while len(self._standing) < n and (end or len(self._standing) + half < n):
            j, sil = len(self._standing), self.silhouettes[len(self._standing)]
            self._standing.append(
                np.nan
                if sil is None
                else head_to_feet(sil, window_percentile(self._sizes, j, half, STANDING_PERCENTILE))
            )
        known = len(self._standing)
        while len(self._heights) < known and (end or len(self._heights) + half < known):
            i, sil = len(self._heights), self.silhouettes[len(self._heights)]
            height = np.nan if sil is None else window_percentile(self._standing, i, half, STANDING_PERCENTILE)
            self._heights.append(height)
            if sil is not None:
                self._normalised[i] = normalise(sil, height)
            reads = (np.nan, np.nan, False) if sil is None else torso_reads(sil, height, self._normalised[i][0])
            for values, value in zip((self._spreads, self._lift_reads, self._readable), reads):
                values.append(value)
        known, self._provisional = len(self._heights), []
        while self._fitted < known and (end or self._fitted + self.spread_half < known):
            i = self._fitted
            spreads = (
                (np.nan, np.nan)
                if self.silhouettes[i] is None
                else (
                    window_percentile(self._spreads, i, self.spread_half, SPREAD_PERCENTILE),
                    lift_spread(self._lift_reads, self._readable, i, self.spread_half),
                )
            )
            out += self.fitter.fit(
                i, self.silhouettes[i], self._heights[i], *spreads, normalised=self._normalised.pop(i, None)
            )
            if self.fitter.latest is not None and not end:
                self._provisional.append(self.fitter.latest)
            self._fitted += 1
        return out


def _frame_fits(decided: list, scale: float) -> Iterator[FrameFit]:
    """FrameFits of ``LegChain``'s (item, fit) pairs; item: (index, crop origin, crop step, lift spread,
    video-pixel landmarks), or the index alone where fit is None."""
    for item, fit in decided:
        if fit is None:
            yield FrameFit(item, None, None)
            continue
        index, origin, step, spread, landmarks = item
        joints = (origin + (reported_joints(fit.joints, FIT_SCALE) + 0.5) * step - 0.5) / scale
        yield FrameFit(index, joints, fit.score, fit, BODY_HEIGHT * FIT_SCALE * step / scale, spread, landmarks)


def fit_arrays(fits: list[FrameFit]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Image-side joints (F, 16, 2), body heights (F,), the lift's spreads (F,); NaN where nobody is."""
    nan = np.full((len(JOINTS), 2), np.nan)
    joints = np.array([nan if f.joints2d is None else f.joints2d for f in fits], float)
    body_px = np.array([np.nan if f.body_px is None else f.body_px for f in fits], float)
    spread = np.array([np.nan if f.spread is None else f.spread for f in fits], float)
    return joints.reshape(len(fits), len(JOINTS), 2), body_px, spread
