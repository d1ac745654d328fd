"""`mocap fit | synth`: the command line face of the pipeline."""

from __future__ import annotations

import argparse
import sys

from mocap.errors import MocapError


def _add_fit(sub) -> None:
    p = sub.add_parser("fit", help="fit the body model to every frame of a video")
    p.add_argument("video", help="input video (any container/codec OpenCV reads)")
    p.add_argument("--annotations", help="annotations JSON (mocap-annotations)")
    p.add_argument("--out", default=None, help="motion JSON to write (default: VIDEO.motion.json)")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.set_defaults(run=_run_fit)


def _run_fit(args) -> None:
    from mocap.session import fit_video_to_file
    out = fit_video_to_file(args.video, args.out, annotations=args.annotations,
                            progress=None if args.quiet else _progress)
    print(f"wrote {out}")


def _add_synth(sub) -> None:
    from mocap.synth import add_synth_arguments
    p = sub.add_parser("synth", help="render the cylinder body into a video with ground truth")
    add_synth_arguments(p)


def _progress(done: int, total: int) -> None:
    width = 30
    filled = int(width * done / max(total, 1))
    end = "\n" if done >= total else ""
    print(f"\r[{'#' * filled}{'.' * (width - filled)}] {done}/{total} frames", end=end,
          file=sys.stderr, flush=True)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="mocap", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    _add_fit(sub)
    _add_synth(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        args.run(args)
    except MocapError as exc:
        print(f"mocap: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("mocap: interrupted", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
