"""`mocap batch`: many videos on a Dask cluster into a motion library, one task and folder each.

Without ``--scheduler``, a local cluster of one single-threaded process per core (the fit is
Python and numpy on small arrays); with it, workers must see the videos and DIR at the same
paths. Finished, up-to-date folders are skipped, so rerunning resumes; failures do not stop others.
"""

from __future__ import annotations

import glob
import hashlib
import logging
import os
import re
import sys
import time
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from tqdm import tqdm

from mocap.batch.library import ANNOTATIONS, is_finished, write_index
from mocap.batch.task import DEFAULT_EXPORTS, EXPORTS, FRAMES_TOPIC, Job, Outcome, run_job
from mocap.cli.options import add_smooth, smooth_of
from mocap.errors import MocapError
from mocap.io.export.formats import require

VIDEO_SUFFIXES = {".mp4", ".m4v", ".mov", ".avi", ".mkv", ".webm", ".mpg", ".mpeg", ".wmv", ".flv", ".ogv"}
# every BLAS/OpenMP pool in a worker to one thread, set before numpy loads
SINGLE_THREADED = {
    name: "1" for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OPENCV_FOR_THREADS_NUM")
}


def find_videos(inputs: list[str]) -> list[Path]:
    """The videos named by files, folders (searched below) and glob patterns, each once, in order."""
    found: dict[Path, None] = {}
    for item in inputs:
        path = Path(item)
        if path.is_dir():
            matches = sorted(p for p in path.rglob("*") if p.suffix.lower() in VIDEO_SUFFIXES)
            if not matches:
                raise MocapError(f"{item}: no videos in this folder")
        elif path.exists():
            matches = [path]
        elif glob.has_magic(item):
            matches = sorted(Path(p) for p in glob.glob(item, recursive=True) if Path(p).is_file())
            if not matches:
                raise MocapError(f"{item}: no file matches")
        else:
            raise MocapError(f"{item}: no such file or folder")
        found.update((p.resolve(), None) for p in matches)
    return list(found)


def library_names(videos: list[Path]) -> list[str]:
    """A folder name per video: its name without suffix, with as many of its parent
    folders' names as make it unique (``clips/punch/video.mp4`` -> ``punch-video``)."""
    for last in ("stem", "name"):  # x.mp4 beside x.avi: the suffix tells them apart
        parts = [[*v.parent.parts[1:], getattr(v, last)] for v in videos]
        for depth in range(1, max(len(p) for p in parts) + 1):
            names = [re.sub(r"[^\w.-]+", "_", "-".join(p[-depth:])) for p in parts]
            if len(set(names)) == len(names):
                return names
    raise MocapError("two inputs are the same video")


def settings_of(exports: list[str], smooth: float, annotations: Path | None) -> dict:
    """What a video's outputs depend on besides the video: recorded with them."""
    try:
        program = version("mocap")
    except PackageNotFoundError:
        program = "unknown"
    digest = hashlib.sha256(annotations.read_bytes()).hexdigest() if annotations else None
    return {"mocap": program, "exports": sorted(exports), "smooth": smooth, "annotations": digest}


def annotations_for(source: Path | None, name: str) -> Path | None:
    """A video's annotations in ``--annotations-from DIR``: ``DIR/<name>/annotations.json``
    (a reviewed library folder) or ``DIR/<name>.annotations.json``; None if neither."""
    if source is None:
        return None
    for path in (source / name / ANNOTATIONS, source / f"{name}.annotations.json"):
        if path.is_file():
            return path.resolve()
    return None


def plan(videos: list[Path], out: Path, exports: list[str], smooth: float, annotations_from: Path | None) -> list[Job]:
    """A job per video, into ``out/<name>``."""
    jobs = []
    for video, name in zip(videos, library_names(videos)):
        notes = annotations_for(annotations_from, name)
        jobs.append(
            Job(
                str(video),
                str((out / name).resolve()),
                settings_of(exports, smooth, notes),
                None if notes is None else str(notes),
            )
        )
    return jobs


def parse_exports(text: str) -> list[str]:
    """``--exports bvh,glb``: the names, checked."""
    names = [n.strip().lower() for n in text.split(",") if n.strip()]
    unknown = [n for n in names if n not in EXPORTS]
    if unknown:
        raise MocapError(f"--exports: unknown format {unknown[0]!r} (choose from {', '.join(EXPORTS)})")
    missing = [n for n in names if n not in DEFAULT_EXPORTS]
    if missing:
        require(missing[0])  # says what that format needs
    return names


@contextmanager
def dask_client(scheduler: str | None, workers: int | None) -> Iterator:
    """A Dask client: of the cluster at ``scheduler``, or of a local cluster of
    ``workers`` single-threaded processes (default: one per core)."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError as exc:
        raise MocapError(f"mocap batch needs Dask: pip install -e '.[batch]' ({exc})") from None
    logging.getLogger("distributed").setLevel(logging.ERROR)
    if scheduler:
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError) as exc:
            raise MocapError(f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None
        with client:
            yield client
        return
    with warnings.catch_warnings():  # 8787 taken: the dashboard moves, and we print where
        warnings.filterwarnings("ignore", "Port .* is already in use")
        cluster = LocalCluster(
            n_workers=workers or os.cpu_count() or 1,
            threads_per_worker=1,
            processes=True,
            env=SINGLE_THREADED,
            silence_logs=logging.ERROR,
        )
    with cluster, Client(cluster) as client:
        yield client


def dashboard(client) -> str:
    """The address of the cluster's Dask dashboard, or why there is none."""
    if "dashboard" not in client.scheduler_info().get("services", {}):
        return "none (the scheduler serves one when bokeh is installed: pip install -e '.[batch]')"
    return client.dashboard_link


@dataclass
class Tally:
    """How the batch is going: a stderr line per video ended, and on a terminal a tqdm bar
    below (videos done, failures, frames per second over the cluster)."""

    total: int
    skipped: int = 0
    done: int = 0
    frames: int = 0
    cpu: float = 0.0  # the workers' CPU seconds on the videos done
    failed: list[Outcome] = field(default_factory=list)
    start: float = field(default_factory=time.perf_counter)
    end: float | None = None  # when the last video came back
    bar: tqdm | None = None
    running: dict[str, int] = field(default_factory=dict)  # frames done of running videos
    ended: set[str] = field(default_factory=set)  # late reports of these are old

    def begin(self) -> None:
        """Start the clock (and the bar, on a terminal) as the tasks go out."""
        self.start = time.perf_counter()
        if sys.stderr.isatty():
            self.bar = tqdm(total=self.total, initial=self.skipped, unit="video", file=sys.stderr, dynamic_ncols=True)

    def running_frames(self, event: tuple) -> None:
        """A worker's report of a running video's frames (Dask's event thread)."""
        if event[1]["name"] not in self.ended:
            self.running[event[1]["name"]] = event[1]["frames"]
        if self.bar is not None:
            self.bar.set_postfix_str(self.counts())

    def counts(self) -> str:
        return f"{len(self.failed)} failed, {self.fps:.1f} frames/s"

    def add(self, outcome: Outcome) -> None:
        """Count an outcome and say it."""
        self.ended.add(outcome.name)
        self.running.pop(outcome.name, None)
        self.done += 1
        if outcome.error:
            self.failed.append(outcome)
            text = f"FAILED {outcome.name}: {outcome.error}"
        else:
            self.frames += outcome.frames
            self.cpu += outcome.cpu
            text = f"done {outcome.name}: {outcome.frames} frames in {outcome.seconds:.1f} s"
        counts = self.counts()
        if self.bar is None:
            print(f"{text} [{self.done + self.skipped}/{self.total} videos, {counts}]", file=sys.stderr, flush=True)
            return
        self.bar.write(text, file=sys.stderr)
        self.bar.set_postfix_str(counts, refresh=False)
        self.bar.update(1)

    def finish(self) -> None:
        self.end = time.perf_counter()
        if self.bar is not None:
            self.bar.close()

    @property
    def fps(self) -> float:
        """Frames per second over the cluster: the videos done and those running."""
        frames = self.frames + sum(self.running.values())
        return frames / max((self.end or time.perf_counter()) - self.start, 1e-9)


def run_batch(jobs: list[Job], client, tally: Tally) -> None:
    """Run the jobs on the cluster, counting each outcome as it comes."""
    from dask.distributed import as_completed

    client.subscribe_topic(FRAMES_TOPIC, tally.running_frames)
    futures = client.map(run_job, jobs, pure=False, key=[f"mocap-{j.name}-{i}" for i, j in enumerate(jobs)])
    names = {f.key: j.name for f, j in zip(futures, jobs)}
    for future in as_completed(futures):
        try:
            tally.add(future.result())
        except Exception as exc:  # noqa: BLE001 - a worker lost or a task not unpickled on it
            tally.add(Outcome(names[future.key], error=f"{type(exc).__name__}: {exc}"))
        future.release()


def batch(
    inputs: list[str],
    out: str,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    exports: str = ",".join(DEFAULT_EXPORTS),
    annotations_from: str | None = None,
    smooth: float = 0.0,
) -> Tally:
    """`mocap batch`: every video not already finished, then the library's index."""
    if workers is not None and (workers < 1 or scheduler):
        raise MocapError(
            "--workers must be 1 or more, and only sizes the local cluster "
            "(an existing one has the workers it was started with)"
        )
    source = Path(annotations_from) if annotations_from else None
    if source is not None and not source.is_dir():
        raise MocapError(f"--annotations-from {annotations_from}: no such folder")
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    jobs = plan(find_videos(inputs), folder, parse_exports(exports), smooth, source)
    todo = [j for j in jobs if not is_finished(Path(j.folder), j.video, j.settings)]
    tally = Tally(len(jobs), skipped=len(jobs) - len(todo))
    print(
        f"mocap batch: {len(jobs)} videos, {tally.skipped} already done, {len(todo)} to do", file=sys.stderr, flush=True
    )
    try:
        if todo:
            with dask_client(scheduler, workers) as client:
                print(f"dashboard: {dashboard(client)}", file=sys.stderr, flush=True)
                tally.begin()
                try:
                    run_batch(todo, client, tally)
                finally:
                    tally.finish()
    finally:
        page, _ = write_index(folder)
    print(
        f"{tally.done - len(tally.failed)} fitted, {tally.skipped} skipped, {len(tally.failed)} "
        f"failed; {tally.frames} frames at {tally.fps:.1f} frames/s; library: {page}"
    )
    return tally


def add_batch_arguments(parser) -> None:
    """Arguments of `mocap batch`; sets ``run``."""
    parser.add_argument(
        "inputs", nargs="+", metavar="INPUT", help="videos, folders of videos (searched below) or glob patterns"
    )
    parser.add_argument(
        "--out", required=True, metavar="DIR", help="the library: DIR/<name>/ per video, DIR/index.html and index.csv"
    )
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="an existing Dask cluster, e.g. tcp://host:8786 (default: a local cluster, one process per core)",
    )
    parser.add_argument(
        "--workers", type=int, metavar="N", help="processes of the local cluster (default: one per core)"
    )
    parser.add_argument(
        "--exports",
        default=",".join(DEFAULT_EXPORTS),
        metavar="LIST",
        help=f"comma-separated, of {', '.join(EXPORTS)} (default: all that this "
        "installation writes); the motion "
        "file, playback page and contact sheet are always written",
    )
    parser.add_argument(
        "--annotations-from",
        metavar="DIR",
        help="annotations per video: DIR/<name>/annotations.json (a library "
        "reviewed with `mocap serve DIR/<name>`) or DIR/<name>.annotations.json",
    )
    add_smooth(parser, "as `mocap fit`")
    parser.set_defaults(run=run_batch_command)


def run_batch_command(args) -> int:
    """Exit code 1 when some video failed (each was reported with its error)."""
    tally = batch(
        args.inputs,
        args.out,
        scheduler=args.scheduler,
        workers=args.workers,
        exports=args.exports,
        annotations_from=args.annotations_from,
        smooth=smooth_of(args),
    )
    return 1 if tally.failed else 0
