"""The one pipeline from a video to a 3D animation; the command line and the app
both run it, reporting each step to a ``progress`` callback.

The silhouette method: silhouettes (section 3.2), then the 2D fits (section 3.3),
streamed frame by frame (``mocap.silhouette.passes``); the lifting (section 3.4) and
the motion follow from its session. The tracking method: the joints marked on frame
0 followed through the video (mocap.track.tracking), the 3D from its session.
``open_session`` runs either and returns the session (mocap.session) that lifts
and exports; ``fit_video_to_file`` is `mocap fit`.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

from mocap.errors import MocapError, MocapWarning
from mocap.io.annotations import Annotations, load_annotations
from mocap.io.export.formats import check_ending, require, write_format
from mocap.io.fileio import check_writable, check_writable_folder
from mocap.io.video import VideoInfo, open_video, processing_scale
from mocap.person import DEFAULT_MODEL, NONE, available, check_name, install_hint, open_person_model
from mocap.session.review import Doubt
from mocap.session import Session, SilhouetteSession, TrackSession, tracked_video
from mocap.silhouette import Background, FrameFit, Silhouette, clip_background, fit_clip
from mocap.track.tracking import TrackResult

SILHOUETTES = "finding the performer's silhouette"
FITTING = "fitting the body model"
TRACKING = "following the marked joints"


@dataclass(frozen=True)
class Progress:
    """How far a run is: ``done`` of ``total`` steps (the silhouette method: two per
    frame, the tracking method: one), at ``stage``. A step that produced a frame's
    silhouette or 2D fit carries it (``frame``, ``product``: a Silhouette, None where
    nobody is, or a FrameFit) so that a viewer can show it at once; a fit whose legs are
    not chosen yet comes first as a report that is not ``final`` (done unchanged)."""

    done: int
    total: int
    stage: str
    error: str | None = None
    frame: int | None = None
    product: Silhouette | FrameFit | None = None
    final: bool = True      # False: a fit shown before its legs are chosen (not a step)

    @property
    def ready(self) -> bool:
        return self.done == self.total and self.error is None


Report = Callable[[Progress], None]


def _quiet(_: Progress) -> None:
    pass


def silhouette_passes(info: VideoInfo, progress: Report | None = None, background: Background | None = None,
                      person: str = NONE) -> tuple[list[Silhouette | None], list[FrameFit]]:
    """The silhouette method over a video (mocap.silhouette.fit_clip), seen also by the
    ``person`` model named (mocap.person; "none": background subtraction alone), each
    silhouette and fit reported as it comes (``done`` counts both)."""
    report, total, done = progress or _quiet, 2 * info.frame_count, [0]

    def shown(product: Silhouette | FrameFit | None, frame: int, final: bool) -> None:
        done[0] += final
        stage = FITTING if isinstance(product, FrameFit) else SILHOUETTES
        report(Progress(done[0], total, stage, frame=frame, product=product, final=final))
    model = open_person_model(person)
    try:
        return fit_clip(info, background, model, shown)
    finally:
        if model is not None:
            model.close()


def fit_video(video: str | os.PathLike | VideoInfo,
              progress: Report | None = None) -> tuple[VideoInfo, list[FrameFit]]:
    """Silhouettes and 2D fits for every frame of a video (a path or an opened one)."""
    info = video if isinstance(video, VideoInfo) else open_video(video)
    return info, silhouette_passes(info, progress)[1]


def person_model(name: str | None) -> str:
    """The person model a run uses: ``name``, else the environment's MOCAP_PERSON_MODEL,
    else the default one; where its package is not installed a MocapWarning says how
    to get it, and the run takes the paper's classical path ("none")."""
    name = check_name(name or os.environ.get("MOCAP_PERSON_MODEL") or DEFAULT_MODEL, " (MOCAP_PERSON_MODEL)")
    if name == NONE or available(name):
        return name
    warnings.warn(f"no person model, fitting by silhouettes alone: {install_hint(name)}", MocapWarning,
                  stacklevel=2)
    return NONE


def tracked(info: VideoInfo, notes: Annotations, progress: Report | None = None) -> TrackResult:
    """The tracking method's pass: the marks on frame 0 of ``notes`` (marks_of), and
    on every frame they mark the whole body again, followed through the video
    (mocap.session.tracking.tracked_video)."""
    report = progress or _quiet
    return tracked_video(info, notes, lambda done, total: report(Progress(done, total, TRACKING)))


def takes_tracking(method: str | None, notes: Annotations) -> bool:
    """Whether a run takes the tracking method: ``method`` if given, else the
    annotations' (the silhouette method when they name none)."""
    return (method or notes.method) == "track"


def open_session(video: str | os.PathLike | VideoInfo, notes: Annotations | None = None, *,
                 method: str | None = None, smooth: float = 0.0,
                 background: str | os.PathLike | tuple[int, int] | None = None,
                 progress: Report | None = None, person: str = NONE) -> Session:
    """Run a method over a video and return its session. ``method`` None: the
    annotations' method, else the silhouette method; ``background``: the empty
    scene for it (a photo or video file, or first and last frames of the clip;
    None: the annotations', resolved by the caller, else estimated); ``person``: the
    person model the silhouette method also looks through (``person_model``)."""
    info = video if isinstance(video, VideoInfo) else open_video(video)
    notes = notes or Annotations()
    if takes_tracking(method, notes):
        return TrackSession(info, tracked(info, notes, progress), notes, smooth)
    scene = clip_background(info, processing_scale(info), background)
    silhouettes, fits = silhouette_passes(info, progress, scene, person)
    return SilhouetteSession(info, fits, notes, smooth, silhouettes=silhouettes, background=scene, person=person)


@dataclass(frozen=True)
class Written:
    """What `mocap fit` wrote, and the frames the app's review would show (every
    doubtful one, most doubtful first: mocap.session.review) of the clip's ``n_frames``."""

    paths: list[Path]
    doubtful: list[Doubt]
    n_frames: int


def fit_video_to_file(video: str | os.PathLike, exports: dict[str, str | os.PathLike], *,
                      annotations: str | os.PathLike | None = None, method: str | None = None,
                      smooth: float = 0.0, background: str | os.PathLike | None = None,
                      masks: str | os.PathLike | None = None, foot_lock: bool = False,
                      progress: Report | None = None, person: str | None = None) -> Written:
    """`mocap fit`: fit (silhouette method) or track (tracking method), lift,
    interpolate and write the files asked for, {format key: path} of
    mocap.io.export.formats (the motion file "json" always: VIDEO.motion.json unless
    given). ``background``: the empty scene (else the
    annotations'); ``masks``: a folder for the silhouettes, named in the motion
    file; ``foot_lock``: planted feet kept in place; ``person``: the person model
    (``person_model``: None, the default where installed). A background that holds the
    performer is a MocapWarning; a format this installation cannot write is refused
    before the video is read."""
    for key, path in exports.items():
        require(key)
        check_ending(key, path)
    info = open_video(video)
    notes = load_annotations(annotations, info.frame_count) if annotations else Annotations()
    paths = {"json": Path(video).with_suffix(".motion.json")} | exports
    check_writable(*paths.values())
    if masks is not None:
        if takes_tracking(method, notes):
            raise MocapError("--masks needs the silhouette method (the tracking method finds no silhouettes)")
        check_writable_folder(masks)
    plate = background if background is not None else notes.background_source(annotations)
    person = NONE if takes_tracking(method, notes) else person_model(person)
    session = open_session(info, notes, method=method, smooth=smooth, background=plate, progress=progress,
                           person=person)
    if session.background_warning:
        warnings.warn(session.background_warning, MocapWarning, stacklevel=2)
    clip = session.clip(foot_lock)
    folders = []
    if masks is not None:
        folders = [session.write_masks(masks)]
        relative = os.path.relpath(folders[0].resolve(), Path(paths["json"]).resolve().parent)
        clip = replace(clip, extra={"masks": Path(relative).as_posix()})
    written = [write_format(key, path, clip) for key, path in paths.items()] + folders
    return Written(written, session.review_queue(), info.frame_count)
