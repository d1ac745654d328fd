"""`mocap synth`: render a BVH file or the procedural walk as a video with exact truth."""

from __future__ import annotations

from pathlib import Path

from mocap.errors import MocapError
from mocap.synth import SHAPES, VIEWS, RenderOptions, render_motion


def add_synth_arguments(parser) -> None:
    """Arguments of `mocap synth`; sets ``run`` to the function that renders."""
    parser.add_argument("source", help="BVH file, or 'walk-cycle' for the procedural walk")
    parser.add_argument("out", help="video to write (.mp4 or .avi)")
    parser.add_argument(
        "--view", choices=list(VIEWS), default="side", help="camera direction relative to the performer (default side)"
    )
    parser.add_argument("--yaw", type=float, help="camera yaw in degrees (overrides --view)")
    parser.add_argument("--pitch", type=float, default=0.0, help="degrees looking down")
    parser.add_argument("--size", default="640x480", help="WIDTHxHEIGHT (default 640x480)")
    parser.add_argument("--fps", type=float, default=30.0, help="output frame rate")
    parser.add_argument("--frames", help="source frame range A:B (BVH frames)")
    parser.add_argument("--seconds", type=float, help="maximum duration (walk-cycle: 4)")
    parser.add_argument(
        "--perspective",
        type=float,
        metavar="FOCAL_PX",
        help="pinhole camera with this focal length (default orthographic)",
    )
    parser.add_argument(
        "--body-fraction", type=float, default=0.6, help="body height / frame height when the path fits (default 0.6)"
    )
    parser.add_argument(
        "--moving-background", action="store_true", help="pan a cluttered background (for the tracking method)"
    )
    parser.add_argument("--no-antialias", action="store_true", help="hard polygon edges")
    parser.add_argument("--hair", action="store_true", help="dark hair over the back of the head")
    parser.add_argument("--noise", type=float, default=2.0, help="sensor noise sigma")
    parser.add_argument("--in-place", action="store_true", help="walk-cycle on the spot")
    parser.add_argument("--truth", help="ground truth JSON (default OUT.truth.json)")
    parser.add_argument("--seed", type=int, default=0, help="background and noise seed")
    parser.add_argument(
        "--shape",
        choices=list(SHAPES),
        default="model",
        help="the body's widths: the model's own (default), slim or broad",
    )
    parser.set_defaults(run=run_synth)


def run_synth(args) -> None:
    """Render as the parsed `mocap synth` arguments say and report what was written."""
    opts = RenderOptions(
        view=args.view,
        yaw=args.yaw,
        pitch=args.pitch,
        size=_parse_pair(args.size, "x", "--size", int),
        fps=args.fps,
        perspective=args.perspective,
        body_fraction=args.body_fraction,
        moving_background=args.moving_background,
        antialias=not args.no_antialias,
        noise=args.noise,
        seed=args.seed,
        shape=args.shape,
        hair=args.hair,
    )
    if (
        min(opts.size) < 16
        or opts.fps <= 0
        or not 0 < opts.body_fraction <= 1
        or (opts.perspective is not None and opts.perspective <= 0)
    ):
        raise MocapError("--size must be at least 16x16, --fps and --perspective positive, --body-fraction in (0, 1]")
    frames = _parse_pair(args.frames, ":", "--frames", lambda v: int(v) if v else None) if args.frames else None
    truth = render_motion(
        args.source, args.out, opts, frames=frames, seconds=args.seconds, in_place=args.in_place, truth_path=args.truth
    )
    print(
        f"wrote {args.out}: {len(truth.joints2d)} frames {truth.width}x{truth.height}, "
        f"body {truth.body_height_px:.0f} px tall "
        f"({100 * truth.body_height_px / truth.height:.0f}% of the frame), "
        f"truth {args.truth or Path(args.out).with_suffix('.truth.json')}"
    )


def _parse_pair(text: str, sep: str, flag: str, convert) -> tuple:
    """'640x480' -> (640, 480); '10:' -> (10, None); bad text -> MocapError."""
    parts = text.split(sep)
    try:
        if len(parts) != 2:
            raise ValueError
        return tuple(convert(p.strip()) for p in parts)
    except ValueError:
        raise MocapError(f"{flag} expects A{sep}B, got {text!r}") from None
