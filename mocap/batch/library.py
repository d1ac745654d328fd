"""The motion library of `mocap batch`: a folder per video, and ``index.html`` / ``index.csv``.

``DIR/<name>/`` holds a video's outputs and, written last and atomically, ``batch.json``
(format ``mocap-batch``: video, settings, fit summary, files), the mark of a finished video;
a failed one has ``failed.json`` (its one-line error) instead.
"""

from __future__ import annotations

import csv
import html
import io
import json
import os
from pathlib import Path
from urllib.parse import quote

from mocap.errors import MocapError
from mocap.io.fileio import atomic_write_bytes, atomic_write_json

RECORD, FAILED, ANNOTATIONS = "batch.json", "failed.json", "annotations.json"
FORMAT, VERSION = "mocap-batch", 1
# the columns of index.csv; the files' columns hold paths relative to DIR
COLUMNS = (
    "name",
    "video",
    "status",
    "method",
    "frames",
    "fitted",
    "fps",
    "mean_score",
    "doubtful",
    "seconds",
    "error",
    "playback",
    "motion",
    "sheet",
    "bvh",
    "glb",
    "csv",
    "masks",
)
FILE_COLUMNS = COLUMNS[COLUMNS.index("playback") :]


def write_record(folder: Path, video: str, settings: dict, annotations: str | None, summary: dict, files: dict) -> Path:
    """Mark a video's folder finished: video, settings, annotations, summary, files (relative)."""
    (folder / FAILED).unlink(missing_ok=True)
    return atomic_write_json(
        folder / RECORD,
        {
            "format": FORMAT,
            "version": VERSION,
            "video": video,
            "settings": settings,
            "annotations": annotations,
            "summary": summary,
            "files": files,
        },
    )


def read_record(folder: Path) -> dict | None:
    """A folder's finished record, None when it has none (or one that does not read)."""
    try:
        record = json.loads((folder / RECORD).read_text())
    except (OSError, ValueError):
        return None
    ok = isinstance(record, dict) and record.get("format") == FORMAT and record.get("version") == VERSION
    return record if ok else None


def write_failure(folder: Path, video: str, error: str) -> Path:
    """Record that a video failed, and why (one line)."""
    (folder / RECORD).unlink(missing_ok=True)
    return atomic_write_json(folder / FAILED, {"video": video, "error": error})


def is_finished(folder: Path, video: str, settings: dict) -> bool:
    """Whether a folder's record is of ``video`` and ``settings``, complete, and newer than the video."""
    record = read_record(folder)
    if record is None or record["video"] != video or record["settings"] != settings:
        return False
    if not all((folder / f).exists() for f in record["files"].values()):
        return False
    return (folder / RECORD).stat().st_mtime >= Path(video).stat().st_mtime


def rows(out: Path) -> list[dict]:
    """One row per video folder of the library (finished or failed), by name."""
    found = []
    for folder in sorted(p for p in out.iterdir() if p.is_dir()):
        record = read_record(folder)
        if record is not None:
            found.append(_finished_row(folder.name, record))
        elif (folder / FAILED).is_file():
            failure = json.loads((folder / FAILED).read_text())
            found.append(
                {"name": folder.name, "video": failure["video"], "status": "failed", "error": failure["error"]}
            )
    return found


def _finished_row(name: str, record: dict) -> dict:
    row = {"name": name, "video": record["video"], "status": "done", **record["summary"]}
    row.update({k: f"{name}/{f}" for k, f in record["files"].items()})
    return row


def write_index(out: Path) -> tuple[Path, Path]:
    """``index.html`` and ``index.csv`` of the library in ``out``."""
    found = rows(out)
    text = io.StringIO()
    writer = csv.DictWriter(text, COLUMNS, extrasaction="ignore", lineterminator="\n")
    writer.writeheader()
    writer.writerows(found)
    table = atomic_write_bytes(out / "index.csv", text.getvalue().encode())
    return atomic_write_bytes(out / "index.html", index_html(out, found).encode()), table


_STYLE = """body{font:14px system-ui,sans-serif;margin:1.5em;color:#222}
table{border-collapse:collapse}td,th{padding:6px 10px;border-bottom:1px solid #ddd;
text-align:left;vertical-align:top}td.n{text-align:right}img{width:320px;display:block}
.failed{color:#b00}code{font-size:12px}"""


def index_html(out: Path, found: list[dict]) -> str:
    """The library's page: a table row per video (``rows``)."""
    failed = sum(r["status"] == "failed" for r in found)
    head = (
        "<tr><th>contact sheet</th><th>video</th><th>frames</th><th>mean score</th>"
        "<th>doubtful frames</th><th>files</th></tr>"
    )
    body = "\n".join(_row_html(r) for r in found)
    title = html.escape(f"Motion library: {out.resolve().name}")
    return (
        f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{title}'
        f"</title><style>{_STYLE}</style></head><body><h1>{title}</h1>\n<p>{len(found)} videos"
        f", {failed} failed. Review one with <code>mocap serve {html.escape(str(out))}/NAME"
        f"</code>; its corrections feed <code>mocap batch ... --annotations-from "
        f"{html.escape(str(out))}</code>.</p>\n<table>\n{head}\n{body}\n</table></body></html>\n"
    )


def _row_html(row: dict) -> str:
    name = html.escape(row["name"])
    if row["status"] == "failed":
        return (
            f'<tr class="failed"><td></td><td>{name}<br><code>{html.escape(row["video"])}'
            f'</code></td><td colspan="4">failed: {html.escape(row["error"])}</td></tr>'
        )
    thumb = f'<a href="{_href(row["sheet"])}"><img src="{_href(row["thumb"])}" alt="contact sheet of {name}"></a>'
    links = " ".join(f'<a href="{_href(row[k])}">{k}</a>' for k in FILE_COLUMNS if row.get(k) and k != "playback")
    score = "" if row["mean_score"] is None else f"{row['mean_score']:.3f}"
    return (
        f'<tr><td>{thumb}</td><td><a href="{_href(row["playback"])}">{name}</a><br>'
        f"<code>{html.escape(row['video'])}</code><br>{html.escape(row['method'])}</td>"
        f'<td class="n">{row["frames"]} ({row["fitted"]} with a person)</td>'
        f'<td class="n">{score}</td><td class="n">{row["doubtful"]}</td><td>{links}</td></tr>'
    )


def _href(path: str) -> str:
    return html.escape(quote(path))


def review_target(path: str | os.PathLike) -> tuple[str, Path] | None:
    """For `mocap serve`: a library folder (or a file in it) -> its video and the annotations
    file its review saves to (seeded from the batch's); None for anything else."""
    path = Path(path)
    folder = path if path.is_dir() else path.parent
    record = read_record(folder)
    if record is None:
        if path.is_dir():
            raise MocapError(
                f"{path}: is a folder, not a video nor a video's folder of a `mocap batch` library (no {RECORD} in it)"
            )
        return None
    notes = folder / ANNOTATIONS
    used = record.get("annotations")
    if not notes.exists() and used and Path(used).is_file():
        atomic_write_bytes(notes, Path(used).read_bytes())
    return record["video"], notes
