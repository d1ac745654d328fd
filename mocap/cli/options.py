"""Command-line options shared by `mocap fit` and `mocap batch`, declared and checked once."""

from __future__ import annotations

from mocap.errors import MocapError


def add_smooth(parser, note: str) -> None:
    """``--smooth SIGMA``: the animation's Gaussian smoothing in frames (mocap.lift.motion)."""
    parser.add_argument(
        "--smooth",
        type=float,
        default=0.0,
        metavar="SIGMA",
        help=f"Gaussian smoothing of the animation in frames, {note}",
    )


def smooth_of(args) -> float:
    """The ``--smooth`` given, refused below 0."""
    if args.smooth < 0:
        raise MocapError(f"--smooth must be 0 or more, got {args.smooth}")
    return args.smooth
