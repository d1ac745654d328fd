"""One video of `mocap batch`, the task a Dask worker runs (``run_job``): `mocap fit`'s pipeline,
then each file of its library folder atomically, the record last. Errors are returned, not raised."""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from mocap.batch.library import RECORD, write_failure, write_record
from mocap.batch.sheet import contact_sheet, write_image
from mocap.errors import MocapError
from mocap.io.annotations import Annotations, load_annotations
from mocap.io.export.formats import FORMATS, Clip, write_format
from mocap.io.export.masks import mask_name
from mocap.io.export.motion_json import read_motion
from mocap.io.video import VideoInfo, open_video, processing_scale
from mocap.pipeline import Progress, open_session
from mocap.session import Session, SilhouetteSession
from mocap.silhouette.background import Background
from mocap.silhouette.masks import write_masks
from mocap.silhouette.plate import clip_background

ALWAYS = {"json": "motion", "html": "playback"}  # registry format -> the library's name
EXPORTS = (*(k for k in FORMATS if k not in ALWAYS), "masks")  # what --exports may name
# the default: every one this installation writes (FBX needs the fbx extra)
DEFAULT_EXPORTS = tuple(k for k in EXPORTS if k not in FORMATS or FORMATS[k].available())
MOTION, SHEET, THUMB, MASKS = "motion.json", "sheet.png", "thumb.jpg", "masks"
THUMB_WIDTH = 480  # px: the library page shows hundreds of these


@dataclass(frozen=True)
class Job:
    """A video to do: where its files go, the settings and annotations to use."""

    video: str  # absolute path, as the workers see it
    folder: str  # DIR/<name>
    settings: dict  # recorded; a finished folder with other settings is done again
    annotations: str | None = None

    @property
    def name(self) -> str:
        return Path(self.folder).name


@dataclass(frozen=True)
class Outcome:
    """What became of a job: frames, wall and CPU seconds, or its one-line error."""

    name: str
    frames: int = 0
    seconds: float = 0.0
    error: str | None = None
    cpu: float = 0.0


def run_job(job: Job) -> Outcome:
    """Do one video; its error, if any, is returned (and recorded), never raised."""
    cv2.setNumThreads(1)  # one worker process per core: OpenCV's own threads would contend
    start, cpu = time.perf_counter(), time.process_time()
    folder = Path(job.folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        frames = _make(job, folder)
        return Outcome(job.name, frames, time.perf_counter() - start, cpu=time.process_time() - cpu)
    except MocapError as exc:
        error = str(exc)
    except Exception as exc:  # noqa: BLE001 - whatever breaks on one video must not stop the rest
        error = f"{type(exc).__name__}: {exc}"
    error = (error.strip().splitlines() or ["failed"])[0]
    try:
        write_failure(folder, job.video, error)
    except OSError:
        pass  # an unwritable folder: the error still reaches the client
    return Outcome(job.name, 0, time.perf_counter() - start, error)


def _make(job: Job, folder: Path) -> int:
    """Fit the video and write its folder, record last; returns its frame count."""
    (folder / RECORD).unlink(missing_ok=True)  # done again: unfinished until the end
    start = time.perf_counter()
    info = open_video(job.video)
    notes = load_annotations(job.annotations, info.frame_count) if job.annotations else Annotations()
    session = open_session(info, notes, smooth=job.settings["smooth"], progress=Report(job.name, info.frame_count))
    clip = dataclasses.replace(session.clip(), name=folder.name)
    masks = write_masks(folder / MASKS, info, scene(session)) if "masks" in job.settings["exports"] else None
    files = write_exports(folder, clip, job.settings["exports"], masks)
    files.update(write_sheets(folder, info))
    summary = {**summarise(session, notes), "seconds": round(time.perf_counter() - start, 2)}
    write_record(folder, job.video, job.settings, job.annotations, summary, files)
    return info.frame_count


FRAMES_TOPIC = "mocap-batch-frames"  # Dask events: how far each running video is
REPORT_EVERY_S = 1.0


class Report:
    """A pipeline progress callback sending frames done as a ``FRAMES_TOPIC`` Dask event about
    once a second; silent outside a Dask worker."""

    def __init__(self, name: str, frames: int):
        self.name, self.frames, self.last = name, frames, time.monotonic()
        try:
            from distributed import get_worker

            self.worker = get_worker()
        except (ImportError, ValueError):
            self.worker = None

    def __call__(self, progress: Progress) -> None:
        now = time.monotonic()
        if self.worker is None or now - self.last < REPORT_EVERY_S:
            return
        self.last = now
        done = self.frames * progress.done // max(progress.total, 1)
        self.worker.log_event(FRAMES_TOPIC, {"name": self.name, "frames": done})


def scene(session: Session) -> Background:
    """The empty scene for the masks: the silhouette method's, else the clip's (section 3.2)."""
    if isinstance(session, SilhouetteSession) and session.background is not None:
        return session.background
    return clip_background(session.info, processing_scale(session.info))


def write_exports(folder: Path, clip: Clip, exports: list[str], masks: Path | None) -> dict[str, str]:
    """Write the motion file (naming the ``masks``), playback page and ``exports``; their names."""
    files = {}
    if masks is not None:
        files["masks"] = masks.name
        frames = [{**f, "mask": f"{MASKS}/{mask_name(f['index'])}"} for f in clip.frames]
        clip = dataclasses.replace(clip, frames=frames)
    for key, fmt in FORMATS.items():
        if key in ALWAYS or key in exports:
            path = write_format(key, folder / f"motion.{fmt.suffix.rsplit('.', 1)[-1]}", clip)
            files[ALWAYS.get(key, key)] = path.name
    return files


def write_sheets(folder: Path, info: VideoInfo) -> dict[str, str]:
    """The contact sheet (`mocap sheet`) of the motion file, and its thumbnail."""
    sheet = contact_sheet(info.path, read_motion(folder / MOTION))
    height = max(1, round(sheet.shape[0] * THUMB_WIDTH / sheet.shape[1]))
    thumb = cv2.resize(sheet, (THUMB_WIDTH, height), interpolation=cv2.INTER_AREA)
    return {
        "sheet": write_image(folder / SHEET, sheet, "contact sheet").name,
        "thumb": write_image(folder / THUMB, thumb, "thumbnail").name,
    }


def summarise(session: Session, notes: Annotations) -> dict:
    """What the library shows of a fit: frames, frames fitted, mean score, doubtful frames."""
    scores = session.scores
    fitted = np.isfinite(scores)
    return {
        "method": notes.method or "silhouette",
        "frames": len(scores),
        "fitted": int(fitted.sum()),
        "fps": session.info.fps,
        "mean_score": round(float(scores[fitted].mean()), 4) if fitted.any() else None,
        "doubtful": len(session.review_queue()),
    }
