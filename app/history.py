"""The app's undo history: each edit as (annotations before, annotations after, frame)."""

from __future__ import annotations

from dataclasses import dataclass, field

from mocap.io.annotations import Annotations

Step = tuple[Annotations, Annotations, int]


@dataclass
class History:
    """Undo and redo stacks of edits; a new edit clears the redo stack."""

    undo: list[Step] = field(default_factory=list)
    redo: list[Step] = field(default_factory=list)

    def record(self, before: Annotations, after: Annotations, frame: int) -> None:
        self.undo.append((before, after, frame))
        self.redo.clear()

    def peek(self, back: bool) -> tuple[Annotations, int] | None:
        """(annotations, frame) that undoing (``back``) or redoing would apply; None if nothing to."""
        source = self.undo if back else self.redo
        if not source:
            return None
        before, after, frame = source[-1]
        return (before if back else after), frame

    def move(self, back: bool) -> None:
        """Move the latest edit from one stack to the other (once applied)."""
        source, target = (self.undo, self.redo) if back else (self.redo, self.undo)
        target.append(source.pop())
