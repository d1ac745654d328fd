"""`mocap fit | synth | sheet | serve | export`: the command line face of the pipeline."""

from __future__ import annotations

import argparse
import os
import sys
import warnings

from mocap.cli.options import add_focal, add_smooth, focal_of, smooth_of
from mocap.cli.progress import Bar
from mocap.errors import MocapError, MocapWarning
from mocap.io.export.formats import FORMATS
from mocap.person import CHOICES as PERSON_MODELS


def _add_fit(p) -> None:
    p.add_argument("video", help="input video (any container/codec OpenCV reads)")
    p.add_argument(
        "--method",
        choices=("silhouette", "track"),
        default=None,
        help="silhouette: fit the cylinder body to each frame's silhouette (static "
        "background); track: follow the joints marked on frame 0 (any background; "
        "--annotations, else the person model's landmarks, mark them). Default: the "
        "annotations' method (the app saves it), else silhouette",
    )
    p.add_argument(
        "--annotations",
        metavar="FILE",
        help="mocap-annotations JSON: orientation, foreshortening, joint overrides, keyframes",
    )
    p.add_argument("--out", default=None, help="motion JSON to write (default: VIDEO.motion.json)")
    for fmt in FORMATS.values():
        if fmt.key != "json":
            p.add_argument(f"--{fmt.key}", metavar="FILE", help=f"also write {fmt.holds}")
    p.add_argument(
        "--background",
        metavar="IMAGE|VIDEO",
        help="a photo or short video of the empty scene, same camera (silhouette method; "
        "default: the annotations' background, else estimated from the clip)",
    )
    _add_person_model(p)
    p.add_argument(
        "--masks",
        metavar="DIR",
        help="also write each frame's silhouette as DIR/NNNNNN.png (255 = performer) and "
        "name the folder in the motion file",
    )
    p.add_argument(
        "--foot-lock",
        action="store_true",
        help="keep each planted foot in place through its contact (the motion file "
        "says which frames: contacts), in every file written",
    )
    add_smooth(p, "keyframes kept (default 0)")
    add_focal(p)
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.set_defaults(run=_run_fit)


def _add_person_model(p, switch: str = "") -> None:
    """--person-model, of `mocap fit` and `mocap serve` (``switch``: where else it is chosen)."""
    p.add_argument(
        "--person-model",
        choices=PERSON_MODELS,
        default=None,
        help="the learned person model the methods also look through (its mask and "
        "joints; the tracking method's marks where none are given, and the body where "
        "the colours lose it); none: the paper's classical paths. Default: mediapipe "
        "where installed, else none" + switch,
    )


def _run_fit(args) -> None:
    import cv2

    from mocap.pipeline import fit_video_to_file

    cv2.setNumThreads(1)  # on a frame's small images OpenCV's threads cost more CPU than they save
    paths = {key: getattr(args, "out" if key == "json" else key) for key in FORMATS}
    written = fit_video_to_file(
        args.video,
        {k: p for k, p in paths.items() if p is not None},
        annotations=args.annotations,
        method=args.method,
        smooth=smooth_of(args),
        background=args.background,
        masks=args.masks,
        foot_lock=args.foot_lock,
        person=args.person_model,
        focal=focal_of(args),
        progress=_progress.step,
    )
    print("wrote " + ", ".join(str(p) for p in written.paths))
    print(doubt_summary(written, args.video))


SUMMARY_FRAMES = 5  # doubtful frames named after a fit


def doubt_summary(written, video: str) -> str:
    """How many frames the review would show (pipeline.Written), the first few."""
    if not written.doubtful:
        return f"no doubtful frame of {written.n_frames}"
    first = ", ".join(str(d.frame) for d in written.doubtful[:SUMMARY_FRAMES])
    more = ", ..." if len(written.doubtful) > SUMMARY_FRAMES else ""
    return (
        f"{len(written.doubtful)} of {written.n_frames} frames doubtful, most first: {first}{more} "
        f"(`mocap serve {video}` shows why, on its Review tab)"
    )


def _add_synth(p) -> None:
    from mocap.cli.synth import add_synth_arguments

    add_synth_arguments(p)


def _add_sheet(p) -> None:
    from mocap.batch.sheet import add_sheet_arguments

    add_sheet_arguments(p)


def _add_serve(p) -> None:
    p.add_argument(
        "video",
        nargs="?",
        default=None,
        help="input video (default: the bundled sample_videos/walk.mp4), or a video's "
        "folder of a `mocap batch` library, DIR/<name>: its edits are saved there "
        "for `mocap batch --annotations-from DIR`",
    )
    p.add_argument(
        "--port", type=_port, default=8080, help="port to listen on (default 8080; an error if taken; 0: any free one)"
    )
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1: this machine only)")
    _add_person_model(p, "; the app's Stage tab switches it (Learned eyes)")
    add_focal(p)

    def run(args) -> None:
        try:  # the app package, imported only here: mocap itself never needs viser
            from app.serve import main as serve
        except ImportError as exc:
            raise MocapError(f"mocap serve needs the app extra: pip install -e '.[app]' ({exc})") from None
        from mocap.batch.library import review_target

        target = review_target(args.video) if args.video else None
        video, notes = target or (args.video, None)
        serve(
            video,
            args.port,
            args.host,
            progress=_progress,
            annotations=notes,
            person=args.person_model,
            focal=focal_of(args),
        )

    p.set_defaults(run=run)


def _port(text: str) -> int:
    """--port's value: a TCP port number, 0 for any free one."""
    if not text.isdigit() or int(text) > 65535:
        raise argparse.ArgumentTypeError(f"expected a port number from 0 to 65535, got {text!r}")
    return int(text)


def _add_batch(p) -> None:
    from mocap.batch import add_batch_arguments

    add_batch_arguments(p)


def _add_export(p) -> None:
    p.add_argument("motion", help="motion JSON written by `mocap fit` or the app")
    p.add_argument(
        "--html",
        metavar="FILE",
        required=True,
        help="the self-contained playback page to write (opens from disk, no network)",
    )

    def run(args) -> None:
        from mocap.io.export.html import motion_file_html, write_html

        print(f"wrote {write_html(args.html, motion_file_html(args.motion))}")

    p.set_defaults(run=run)


_progress = Bar()  # quiet with --quiet or off a terminal (main)
_OPENCV_LOG_ERROR = 2  # OpenCV's LOG_LEVEL_ERROR


def _quiet_video_libraries() -> None:
    """Keep FFmpeg's and OpenCV's own log lines off stderr: errors are ours to say."""
    os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")
    os.environ.setdefault("OPENCV_LOG_LEVEL", "ERROR")
    import cv2

    # OpenCV 5 has cv2.utils.logging; 4.x (the one beside bpy's numpy 1.x) cv2.setLogLevel
    logging = getattr(cv2.utils, "logging", None)
    if logging is not None:
        logging.setLogLevel(logging.LOG_LEVEL_ERROR)
    else:
        cv2.setLogLevel(_OPENCV_LOG_ERROR)


DESCRIPTION = (
    "Motion capture from one fixed camera: `mocap fit VIDEO` fits a body to every frame "
    "and writes the motion and its exports; `mocap serve VIDEO` reviews and corrects "
    "the fit in the browser. `mocap COMMAND --help` lists a command's options."
)


class _Version(argparse.Action):
    """--version: looked up only when asked (importlib.metadata would slow every start)."""

    def __init__(self, option_strings, dest, **kwargs):
        super().__init__(option_strings, dest, nargs=0, help="print mocap's version and exit")

    def __call__(self, parser, namespace, values, option_string=None):
        from importlib.metadata import version

        print(f"mocap {version('mocap')}")
        parser.exit()


_COMMANDS = {  # name: (help, the function that adds its arguments)
    "fit": ("fit the body model to every frame of a video and lift it to 3D", _add_fit),
    "synth": ("render the cylinder body into a video with ground truth", _add_synth),
    "sheet": ("contact sheet: frames beside their silhouettes and fitted skeletons", _add_sheet),
    "serve": ("review and correct a video's fit in the browser, export the animation", _add_serve),
    "export": ("turn a motion file into a playback page (one HTML file, no server needed)", _add_export),
    "batch": ("many videos at once on a Dask cluster, into a motion library (resumable)", _add_batch),
}


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """Every command's parser, with arguments only for ``command`` if given (adding them imports
    the command's modules)."""
    parser = argparse.ArgumentParser(prog="mocap", description=DESCRIPTION)
    parser.add_argument("--version", action=_Version)
    sub = parser.add_subparsers(dest="command", required=True)
    for name, (summary, add_arguments) in _COMMANDS.items():
        p = sub.add_parser(name, help=summary)
        if command in (None, name):
            add_arguments(p)
    return parser


def _command(argv: list[str]) -> str | None:
    """The command named on a command line: its first word that is not an option."""
    return next((word for word in argv if not word.startswith("-")), None)


def _warn_in_one_line(show):
    """warnings.showwarning printing a MocapWarning as `mocap: warning: ...`, others via ``show``."""

    def showwarning(message, category, *args, **kwargs) -> None:
        if not issubclass(category, MocapWarning):
            return show(message, category, *args, **kwargs)
        _progress.close()
        print(f"mocap: warning: {message}", file=sys.stderr, flush=True)

    return showwarning


def main(argv: list[str] | None = None) -> int:
    try:
        argv = sys.argv[1:] if argv is None else argv
        # imports what the command needs: a Ctrl+C lands here too
        args = build_parser(_command(argv)).parse_args(argv)
        _progress.quiet = getattr(args, "quiet", False) or not sys.stderr.isatty()  # before a model pipes it
        args.progress = _progress
        _quiet_video_libraries()
        with warnings.catch_warnings():
            warnings.simplefilter("default", MocapWarning)  # each one once
            warnings.showwarning = _warn_in_one_line(warnings.showwarning)
            code = args.run(args) or 0
    except MocapError as exc:
        _progress.close()
        print(f"mocap: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        _progress.close()
        print("mocap: interrupted", file=sys.stderr)
        return 130
    return code
