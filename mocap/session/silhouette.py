"""The silhouette method's session: per-frame 2D fits (section 3.3, ``mocap.silhouette.passes``)
and the user's annotations, resolved into lifting inputs (the user's over the first guess of
``mocap.lift.orientation``); the clip's 3D solved at once (``mocap.lift.solve``, the user's signs
and placed joints as constraints), keyframes taken from it, the rest interpolated. An edit
re-solves windows around the frames whose inputs it changed (``SilhouetteSession.lifted``)."""

from __future__ import annotations

import os
from dataclasses import replace
from functools import cached_property
from pathlib import Path

import numpy as np

from mocap.body import JOINT_INDEX
from mocap.camera import Focal, Pinhole, default_camera
from mocap.errors import MocapError
from mocap.io.annotations import Annotations
from mocap.io.video import VideoInfo, processing_scale
from mocap.lift.clipdata import ClipArrays, Weights
from mocap.lift.cues import Cues
from mocap.lift.inputs import Inputs, Named, Said, name_limbs, resolve_inputs
from mocap.lift.motion import Motion
from mocap.lift.orientation import facing_evidence, guess_orientations
from mocap.lift.signpath import sign_margins
from mocap.lift.solve import Solution, lift_clip, resolve_edit, solve_windows
from mocap.person import NONE
from mocap.session.base import Session, said_of
from mocap.silhouette.background import Background
from mocap.silhouette.facing import facing_away, near_limbs
from mocap.silhouette.masks import held_warning, silhouette_confidence, write_masks, write_silhouettes
from mocap.silhouette.passes import FrameFit, Silhouette, fit_arrays

# earlier solutions an edit may start from: an undo or a sign set back finds its own again
SOLUTIONS_KEPT = 8


class SilhouetteSession(Session):
    """A video's per-frame 2D fits and the user's annotations; the clip's 3D solved on demand."""

    method = "silhouette"
    score_name = "similarity S"

    def __init__(
        self,
        info: VideoInfo,
        fits: list[FrameFit],
        annotations: Annotations | None = None,
        smooth: float = 0.0,
        *,
        silhouettes: list[Silhouette | None] | None = None,
        background: Background | None = None,
        person: str = NONE,
        focal: Focal | None = None,
    ):
        super().__init__(info, annotations, smooth)
        self.focal = focal  # the camera's focal length; None: scaled orthography
        self.fits = fits
        self.silhouettes, self.background = silhouettes, background
        self.person_model = person  # the person model the fit looked through (mocap.person)
        self._resolved: Inputs | None = None
        self._named: tuple[tuple, Named] | None = None  # name_limbs' answer and what the user said it for
        self._shown: tuple[Inputs, Inputs] | None = None  # the resolved inputs solved last, and as shown
        self._solved: list[tuple[ClipArrays, Solution]] = []  # the latest first, SOLUTIONS_KEPT of them
        self._later: list[slice] = []  # windows of the latest solution an edit left for settle()

    @property
    def camera(self) -> Pinhole | None:
        """The pinhole the 3D is solved through: the video's, centred, where its focal length is known."""
        size = (self.info.width, self.info.height)
        return None if self.focal is None else default_camera(*size, self.focal.pixels(*size))

    @cached_property
    def _arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return fit_arrays(self.fits)

    @cached_property
    def _away(self) -> np.ndarray | None:
        """(F,) how much the head's look says facing away (silhouette.facing.facing_away); None without silhouettes."""
        joints = self._arrays[0]
        return None if self.silhouettes is None else facing_away(self.silhouettes, joints, processing_scale(self.info))

    @cached_property
    def _near(self) -> "NearLimbs | None":
        """Limbs whose outline shows across the body (mocap.silhouette.facing.near_limbs); None without silhouettes."""
        joints, body_px, _ = self._arrays
        return (
            None
            if self.silhouettes is None
            else NearLimbs(self.silhouettes, joints, body_px, processing_scale(self.info))
        )

    @cached_property
    def cues(self) -> Cues | None:
        """The person model's landmarks over the clip (mocap.lift.cues); None if the fit used none."""
        return Cues.of([f.landmarks for f in self.fits], self.info.fps, self._away)

    @cached_property
    def _guessed(self) -> list[str | None]:
        """The orientations the fits and the heads' look suggest (once per session)."""
        joints, body_px, spread = self._arrays
        return guess_orientations(joints, body_px, spread, self.info.fps, self._away)

    @cached_property
    def _facing(self) -> np.ndarray:
        """(F,) turned toward or away by the body's growth and the head's look (facing_evidence, once)."""
        joints, body_px, _ = self._arrays
        return facing_evidence(joints, body_px, self.info.fps, self._away)

    @cached_property
    def silhouette_confidence(self) -> np.ndarray | None:
        """(F,) silhouette confidence (mocap.silhouette.masks); None without silhouettes and background."""
        if self.silhouettes is None or self.background is None:
            return None
        return silhouette_confidence(self.silhouettes, self.background)

    @property
    def background_warning(self) -> str | None:
        """The clip's warning when the performer never leaves much of their silhouette."""
        confidence = self.silhouette_confidence
        return None if confidence is None else held_warning(confidence)

    def write_masks(self, folder: str | os.PathLike) -> Path:
        """Write the silhouettes as mask files and return the folder: the fit's own where a person model
        looked (masks.write_silhouettes), else masks.write_masks against the fit's background."""
        if self.person_model != NONE and self.silhouettes is not None:
            return write_silhouettes(folder, self.info, self.silhouettes)
        if self.background is None:
            raise MocapError("this fit kept no background to write the silhouettes against")
        return write_masks(folder, self.info, self.background)

    def motion_frames(self, motion: Motion) -> list[dict]:
        """The base's entries, with each found frame's ``silhouette_confidence``."""
        frames = super().motion_frames(motion)
        confidence = self.silhouette_confidence
        if confidence is not None:
            for entry, value in zip(frames, confidence):
                if entry["person"] and np.isfinite(value):
                    entry["silhouette_confidence"] = float(value)
        return frames

    @cached_property
    def scores(self) -> np.ndarray:
        """(F,) each frame's fit score (Eq. 3's S), NaN where nobody was found."""
        return np.array([np.nan if f.score is None else f.score for f in self.fits], float)

    def annotate(self, annotations: Annotations, focus: int | None = None) -> None:
        super().annotate(annotations, focus)
        self._resolved = None

    def _resolve(self) -> Inputs:
        """The user's annotations over the first guess (``resolve_inputs``), once per annotations."""
        if self._resolved is None:
            joints, body_px, spread = self._arrays
            said = said_of(self._annotations, len(joints))
            self._resolved = resolve_inputs(joints, body_px, spread, self.info.fps, said, named=self._named_for(said))
        return self._resolved

    def _named_for(self, said: Said) -> Named:
        """``name_limbs`` for what the user said, kept while their orientations and joint overrides stay: a sign
        click, the commonest edit, does not name the limbs again."""
        key = (tuple(said.orientation), repr(sorted(said.overrides.items())))
        if self._named is None or self._named[0] != key:
            joints, body_px, spread = self._arrays
            named = name_limbs(
                joints,
                body_px,
                spread,
                self.info.fps,
                said,
                guessed=self._guessed,
                away=self._away,
                near=self._near,
                cues=self.cues,
                facing=self._facing,
            )
            self._named = (key, named)
        return self._named[1]

    @property
    def inputs(self) -> Inputs:
        """The resolved inputs with the signs of the solved 3D (what the page shows and flips)."""
        return self._solve()

    def held_signs(self) -> np.ndarray:
        return self._resolve().held

    def pose3d(self, frame: int) -> np.ndarray | None:
        """(16, 3) the solved joints of a frame (metres, contract frame); None without a person."""
        return self.lifted()[frame] if self.fits[frame].joints2d is not None else None

    def lifted(self) -> np.ndarray:
        """(F, 16, 3) every frame with a person, solved as one clip (``lift_clip``), NaN elsewhere.
        After an edit only windows around the frames whose inputs it changed are solved again
        (``resolve_edit``), the rest kept."""
        return self.solution().joints3d

    def placed(self) -> np.ndarray:
        """(F, 16) bool: the joints the user placed (overrides) on frames with a person."""
        out = np.zeros((self.n_frames, len(JOINT_INDEX)), bool)
        for i, points in self._annotations.overrides().items():
            if i < self.n_frames and self.fits[i].joints2d is not None:
                out[i, [JOINT_INDEX[j] for j in points]] = True
        return out

    def clip_arrays(self) -> ClipArrays:
        """What the clip solve read for the current annotations (``mocap.lift.clipdata``)."""
        self._solve()
        return self._solved[0][0]

    def solution(self) -> Solution:
        """The clip's solved 3D for the current annotations (``mocap.lift.solve``)."""
        self._solve()
        return self._solved[0][1]

    def sign_margins(self) -> np.ndarray:
        """(F, 10) the cost gaps of the solved signs (mocap.lift.signpath.sign_margins): small where
        toward and away explain the clip alike."""
        solution = self.solution()
        return sign_margins(self.clip_arrays(), solution.model, solution.lengths, Weights())

    def settle(self, most: int | None = None) -> bool:
        """Solve the windows an edit left for later (``annotate``'s focus), at most ``most`` of them (None:
        all); whether there were any."""
        self._solve()
        if not self._later:
            return False
        now, self._later = self._later[:most], self._later[len(self._later[:most]) :]
        clip, solution = self._solved[0]
        self._solved[0] = (clip, solve_windows(clip, solution, now))
        self._queue = None
        self._show(self._shown[0], clip, self._solved[0][1])
        return True

    def _solve(self) -> Inputs:
        """The inputs shown, the clip solved again first where the annotations changed: from scratch
        the first time, after that from the nearest earlier solution (``resolve_edit``; with the edit's
        focus, its window now and the rest at ``settle``)."""
        resolved = self._resolve()
        if self._shown is None or self._shown[0] is not resolved:
            clip = ClipArrays.of(resolved, self.info.fps, self.confidence(), self.placed(), self.camera)
            if self._solved:
                solution, self._later = resolve_edit(clip, self._solved, focus=self._focus)
            else:
                solution, self._later = lift_clip(clip), []
            self._solved = [(clip, solution)] + self._solved[: SOLUTIONS_KEPT - 1]
            self._show(resolved, clip, solution)
        return self._shown[1]

    def _show(self, resolved: Inputs, clip: ClipArrays, solution: Solution) -> None:
        """The inputs shown: ``resolved`` with the signs of ``solution``'s 3D."""
        signs = np.where(clip.person[:, None], solution.signs, resolved.signs)
        self._shown = (resolved, replace(resolved, signs=signs))


class NearLimbs:
    """mocap.silhouette.facing.near_limbs of a clip, computed per run when read (``near[frames]``, a slice:
    (len, 2)) and kept: only runs seen in profile need it (mocap.lift.sides.track_sides)."""

    def __init__(self, silhouettes: list[Silhouette | None], joints2d: np.ndarray, body_px: np.ndarray, scale: float):
        self.silhouettes, self.joints2d, self.body_px, self.scale = silhouettes, joints2d, body_px, scale
        self._runs: dict[tuple[int, int], np.ndarray] = {}

    def __getitem__(self, frames: slice) -> np.ndarray:
        start, stop, _ = frames.indices(len(self.joints2d))
        if (start, stop) not in self._runs:
            self._runs[start, stop] = near_limbs(
                self.silhouettes[start:stop], self.joints2d[start:stop], self.body_px[start:stop], self.scale
            )
        return self._runs[start, stop]
