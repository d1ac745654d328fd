"""Checking decoded JSON documents (annotations, motion files): a problem is raised at its place in
the document, with what was found there; the loader turns it into one MocapError line."""

from __future__ import annotations

import json


class Bad(Exception):
    """A problem at a place in the document (turned into one MocapError)."""

    def __init__(self, place: str, problem: str):
        super().__init__(f"{place}: {problem}" if place else problem)


def describe(value) -> str:
    """What a JSON value is, for a message: its kind, and a scalar's own text."""
    if isinstance(value, dict):
        return "an object"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    if isinstance(value, str):
        return f"the string {json.dumps(value)[:40]}"
    if value is None or isinstance(value, bool):
        return json.dumps(value)
    return f"the number {json.dumps(value)[:40]}"


def is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def expect(value, kind: type, place: str, what: str):
    """value when it is of `kind` (a bool is no number), else Bad."""
    if not isinstance(value, kind) or isinstance(value, bool) and kind is not bool:
        raise Bad(place, f"expected {what}, got {describe(value)}")
    return value
