"""The silhouette method (the 2013 paper: Algorithms 1-6, Eq. 1-3): background, silhouettes and the 10-cylinder
model fitted to each; ``fit_clip`` is its front door."""

from __future__ import annotations

from collections.abc import Callable

from mocap.errors import MocapError
from mocap.io.video import VideoInfo, processing_scale
from mocap.person import PersonModel
from mocap.silhouette.background import Background
from mocap.silhouette.passes import FitStream, FrameFit, Silhouette, iter_silhouettes
from mocap.silhouette.plate import clip_background

Shown = Callable[["Silhouette | FrameFit | None", int, bool], None]

__all__ = ["Background", "FrameFit", "Silhouette", "clip_background", "fit_clip"]


def fit_clip(
    info: VideoInfo, background: Background | None = None, model: PersonModel | None = None, shown: Shown | None = None
) -> tuple[list[Silhouette | None], list[FrameFit]]:
    """Each frame's silhouette (section 3.2; against ``background``, else the clip's own, with the person
    ``model`` if given) and 2D fit (section 3.3), streamed to ``shown(product, frame, final)`` (fits whose legs
    are not chosen yet first with ``final`` False). MocapError if no frame holds a person."""
    n, scale = info.frame_count, processing_scale(info)
    stream, fits = FitStream(scale, info.fps), []
    say = shown or (lambda product, frame, final: None)
    for i, sil in enumerate(iter_silhouettes(info, scale, background, model)):
        batch = stream.push(sil)
        say(sil, i, True)
        for fit in batch:
            fits.append(fit)
            say(fit, fit.index, True)
        for fit in stream.provisional:
            say(fit, fit.index, False)
    if all(s is None for s in stream.silhouettes):
        frames = "its only frame" if n == 1 else f"any of its {n} frames"
        raise MocapError(
            f"{info.path}: no person found in {frames} (one who never moves shows only "
            "against a photo of the empty scene: --background, or the app's Stage tab)"
        )
    for fit in stream.finish():
        fits.append(fit)
        say(fit, fit.index, True)
    return stream.silhouettes, fits
