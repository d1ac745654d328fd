"""The pipeline from a video to a 3D animation, run by the command line and the app.

Silhouette method: silhouettes (section 3.2) and 2D fits (section 3.3) streamed frame by frame,
lifted (section 3.4) by its session; tracking method: the joints marked on frame 0 followed
through the video. ``open_session`` runs either; ``fit_video_to_file`` is `mocap fit`.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from mocap.camera import Focal
from mocap.errors import MocapError, MocapWarning
from mocap.io.annotations import Annotations, load_annotations
from mocap.io.export.formats import check_ending, require, write_format
from mocap.io.fileio import check_writable, check_writable_folder
from mocap.io.video import VideoInfo, open_video, processing_scale
from mocap.person import DEFAULT_MODEL, NONE, PersonModel, available, check_name, install_hint, opened_model
from mocap.session import Session, SilhouetteSession, TrackSession, tracked_video
from mocap.session.review import Doubt
from mocap.silhouette import Background, FrameFit, Silhouette, clip_background, fit_clip
from mocap.track import TrackResult

SILHOUETTES = "finding the performer's silhouette"
FITTING = "fitting the body model"
TRACKING = "following the marked joints"


@dataclass(frozen=True)
class Progress:
    """``done`` of ``total`` steps (two per frame for silhouettes, one for tracking) at ``stage``;
    ``product`` is the step's Silhouette (None: nobody), FrameFit or None, for viewers to show."""

    done: int
    total: int
    stage: str
    error: str | None = None
    frame: int | None = None
    product: Silhouette | FrameFit | None = None
    final: bool = True  # False: a fit shown before its legs are chosen (not a step)

    @property
    def ready(self) -> bool:
        return self.done == self.total and self.error is None


Report = Callable[[Progress], None]


def _quiet(_: Progress) -> None:
    pass


def silhouette_passes(
    info: VideoInfo,
    progress: Report | None = None,
    background: Background | None = None,
    model: PersonModel | None = None,
) -> tuple[list[Silhouette | None], list[FrameFit]]:
    """The silhouette method over a video, also seen by the person ``model`` (None: background
    subtraction alone); each silhouette and fit reported as it comes."""
    report, total, done = progress or _quiet, 2 * info.frame_count, [0]

    def shown(product: Silhouette | FrameFit | None, frame: int, final: bool) -> None:
        done[0] += final
        stage = FITTING if isinstance(product, FrameFit) else SILHOUETTES
        report(Progress(done[0], total, stage, frame=frame, product=product, final=final))

    return fit_clip(info, background, model, shown)


def fit_video(video: str | os.PathLike | VideoInfo, progress: Report | None = None) -> tuple[VideoInfo, list[FrameFit]]:
    """Silhouettes and 2D fits for every frame of a video (a path or an opened one)."""
    info = video if isinstance(video, VideoInfo) else open_video(video)
    return info, silhouette_passes(info, progress)[1]


def person_model(name: str | None, tracking: bool = False) -> str:
    """``name``, else $MOCAP_PERSON_MODEL, else the default; "none" (with a MocapWarning
    saying how to install it) where its package is missing."""
    name = check_name(name or os.environ.get("MOCAP_PERSON_MODEL") or DEFAULT_MODEL, " (MOCAP_PERSON_MODEL)")
    if name == NONE or available(name):
        return name
    alone = "tracking by colours alone" if tracking else "fitting by silhouettes alone"
    warnings.warn(f"no person model, {alone}: {install_hint(name)}", MocapWarning, stacklevel=2)
    return NONE


def tracked(info: VideoInfo, notes: Annotations, progress: Report | None = None, person: str = NONE) -> TrackResult:
    """The tracking method's pass: the body marked in ``notes`` (else the ``person`` model's) followed through the
    video, the person model named looking on."""
    report = progress or _quiet
    return tracked_video(info, notes, lambda done, total: report(Progress(done, total, TRACKING)), person=person)


def takes_tracking(method: str | None, notes: Annotations) -> bool:
    """Whether ``method``, else the annotations', is the tracking method."""
    return (method or notes.method) == "track"


def open_session(
    video: str | os.PathLike | VideoInfo,
    notes: Annotations | None = None,
    *,
    method: str | None = None,
    smooth: float = 0.0,
    background: str | os.PathLike | tuple[int, int] | None = None,
    progress: Report | None = None,
    person: str = NONE,
    focal: Focal | None = None,
) -> Session:
    """Run a method (None: the annotations', else silhouette) over a video; its session.
    ``background``: the empty scene (a photo or video, or first and last frames; None:
    estimated); ``person``: the person model either method looks through; ``focal``: the
    camera's focal length (silhouette method; None: scaled orthography)."""
    info = video if isinstance(video, VideoInfo) else open_video(video)
    notes = notes or Annotations()
    if takes_tracking(method, notes):
        return TrackSession(info, tracked(info, notes, progress, person), notes, smooth)
    # the model (two instances: the frame's and its mirror image's) in processes of their own, loading while the
    # background is read; unfiltered: the lift smooths both ways
    with opened_model(person, filtered=False, apart=True, with_mirror=True) as model:
        scene = clip_background(info, processing_scale(info), background)
        silhouettes, fits = silhouette_passes(info, progress, scene, model)
    return SilhouetteSession(
        info, fits, notes, smooth, silhouettes=silhouettes, background=scene, person=person, focal=focal
    )


@dataclass(frozen=True)
class Written:
    """What `mocap fit` wrote, and the review's doubtful frames (most first) of ``n_frames``."""

    paths: list[Path]
    doubtful: list[Doubt]
    n_frames: int


def fit_video_to_file(
    video: str | os.PathLike,
    exports: dict[str, str | os.PathLike],
    *,
    annotations: str | os.PathLike | None = None,
    method: str | None = None,
    smooth: float = 0.0,
    background: str | os.PathLike | None = None,
    masks: str | os.PathLike | None = None,
    foot_lock: bool = False,
    progress: Report | None = None,
    person: str | None = None,
    focal: Focal | None = None,
) -> Written:
    """`mocap fit`: fit or track, lift, and write ``exports`` ({format key: path}; "json" always,
    VIDEO.motion.json unless given). ``background``: the empty scene (else the annotations');
    ``masks``: a folder for the silhouettes; ``foot_lock``: planted feet kept in place; ``person``:
    None for ``person_model``'s; ``focal``: the camera's focal length (None: scaled orthography).
    Unwritable formats are refused before reading; a background holding the performer is a
    MocapWarning."""
    for key, path in exports.items():
        require(key)
        check_ending(key, path)
    info = open_video(video)
    notes = load_annotations(annotations, info.frame_count) if annotations else Annotations()
    paths = {"json": Path(video).with_suffix(".motion.json")} | exports
    check_writable(*paths.values())
    tracking = takes_tracking(method, notes)
    if masks is not None:
        if tracking:
            raise MocapError("--masks needs the silhouette method (the tracking method finds no silhouettes)")
        check_writable_folder(masks)
    plate = background if background is not None else notes.background_source(annotations)
    person = person_model(person, tracking)
    session = open_session(
        info, notes, method=method, smooth=smooth, background=plate, progress=progress, person=person, focal=focal
    )
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
