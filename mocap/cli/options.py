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


def add_focal(parser) -> None:
    """``--focal PX``: the camera's focal length, for the 3D under perspective (mocap.lift.problem)."""
    parser.add_argument(
        "--focal",
        type=float,
        default=None,
        metavar="PX",
        help="the camera's focal length in pixels of the video (its width times the lens's 35 mm "
        "equivalent over 36 mm): the silhouette method's 3D is solved through that pinhole where "
        "the person model gives depths, and the root's depth follows it (default: scaled "
        "orthography, as for a camera far away)",
    )


def focal_of(args) -> float | None:
    """The ``--focal`` given, refused unless above 0."""
    if args.focal is not None and not args.focal > 0:
        raise MocapError(f"--focal must be a focal length in pixels above 0, got {args.focal}")
    return args.focal


def smooth_of(args) -> float:
    """The ``--smooth`` given, refused below 0."""
    if args.smooth < 0:
        raise MocapError(f"--smooth must be 0 or more, got {args.smooth}")
    return args.smooth
