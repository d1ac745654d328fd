"""Command-line options shared by `mocap fit` and `mocap batch`, declared and checked once."""

from __future__ import annotations

from mocap.camera import Focal
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
    """``--focal PX|MMmm``: the camera's focal length, for the 3D under perspective (mocap.lift.problem)."""
    parser.add_argument(
        "--focal",
        default=None,
        metavar="PX|MMmm",
        help="the camera's focal length, in pixels of the video (1390) or as the lens's 35 mm "
        "equivalent (26mm: a phone's main camera): the silhouette method's 3D is solved through "
        "that pinhole where the person model gives depths, and the root's depth follows it "
        "(default: scaled orthography, as for a camera far away)",
    )


def focal_of(args) -> Focal | None:
    """The ``--focal`` given (camera.Focal), refused in one line if it is not a focal length."""
    if args.focal is None:
        return None
    try:
        return Focal.parse(args.focal)
    except ValueError as error:
        raise MocapError(f"--focal: {error}") from None


def smooth_of(args) -> float:
    """The ``--smooth`` given, refused below 0."""
    if args.smooth < 0:
        raise MocapError(f"--smooth must be 0 or more, got {args.smooth}")
    return args.smooth
