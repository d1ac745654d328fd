"""One instance of a person model in this process (the registry's, mocap.person, or a worker's,
mocap.person.worker)."""

from __future__ import annotations

import importlib

from mocap.person.views import PersonModel


def instance(module: str, filtered: bool, mirror: bool) -> PersonModel:
    """The ``Model`` of ``module`` opened ``filtered`` here; ``mirror``: unmasked (the frame's own view gives the
    mask) and fed mirror images (person.mirrored.MirrorImage)."""
    model = importlib.import_module(module).Model(filtered, masked=not mirror)
    if not mirror:
        return model
    from mocap.person.mirrored import MirrorImage

    return MirrorImage(model)
