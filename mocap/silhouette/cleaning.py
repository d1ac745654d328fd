"""A raw foreground mask reduced to the performer (the 2013 paper, section 3.2): speckle
opened, gaps closed, the person's regions kept and their small holes filled."""

from __future__ import annotations

import cv2
import numpy as np


def clean_mask(
    mask: np.ndarray,
    max_hole: float = 0.02,
    min_area: float = 0.001,
    min_piece: float = 0.02,
    stood: np.ndarray | None = None,
) -> np.ndarray:
    """Open (speckle), close (gaps), keep the person, fill its holes under `max_hole` of its area. The person is
    the largest region (none under `min_area` of the frame) and nearby regions of `min_piece` of it (a leg cut
    off), less those lying mostly where `stood` (``_apart_where_stood``)."""
    out, disk = np.zeros_like(mask), cleaning_disk(mask.shape)
    box = mask_box(mask, 2 * disk.shape[0] + 2)  # beyond the closing's reach, and a ring of zeros
    if box is None:
        return out
    out[box] = _cleaned(
        mask[box], disk, max_hole, min_area * mask.size, min_piece, None if stood is None else stood[box]
    )
    return out


def _cleaned(
    mask: np.ndarray,
    disk: np.ndarray,
    max_hole: float,
    min_area: float,
    min_piece: float,
    stood: np.ndarray | None = None,
) -> np.ndarray:
    """``clean_mask`` on a box holding all of the mask (``min_area`` in pixels)."""
    mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, disk)
    contours, hierarchy = cv2.findContours(mask, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_SIMPLE)
    person = np.zeros_like(mask)
    if not contours:
        return person
    parents = hierarchy[0][:, 3]
    areas = np.array([cv2.contourArea(c) for c in contours])
    keep = _person_regions(contours, parents, areas, min_area, min_piece)
    if not keep:
        return person
    if stood is not None:
        keep = [keep[0]] + [i for i in keep[1:] if not _apart_where_stood(contours[i], stood)]
    cv2.drawContours(person, [contours[i] for i in keep], -1, 255, cv2.FILLED)
    limit = max_hole * areas[keep].sum()
    holes = [c for c, p, a in zip(contours, parents, areas) if p in keep and a >= limit]
    if holes:
        open_holes = np.zeros_like(mask)
        cv2.drawContours(open_holes, holes, -1, 255, cv2.FILLED)
        person = cv2.bitwise_or(cv2.bitwise_and(person, cv2.bitwise_not(open_holes)), cv2.bitwise_and(person, mask))
    return person


def _person_regions(contours, parents, areas, min_area: float, min_piece: float) -> list[int]:
    """Indices of the person's outer contours: the largest, and large ones within a tenth of its height."""
    outer = np.flatnonzero(parents < 0)
    main = outer[np.argmax(areas[outer])]
    if areas[main] < min_area:
        return []
    x, y, w, h = cv2.boundingRect(contours[main])
    gap = max(2, h // 10)
    keep = [int(main)]
    for i in outer:
        lx, ly, lw, lh = cv2.boundingRect(contours[i])
        near = lx <= x + w + gap and x <= lx + lw + gap and ly <= y + h + gap and y <= ly + lh + gap
        if i != main and near and areas[i] >= min_piece * areas[main]:
            keep.append(int(i))
    return keep


def _apart_where_stood(contour: np.ndarray, stood: np.ndarray) -> bool:
    """Whether a region apart from the person's largest lies mostly where `stood`: there it is scene uncovered
    when the performer left (a jump), since a performer standing there joins their body."""
    inside = np.zeros(stood.shape, np.uint8)
    cv2.drawContours(inside, [contour], -1, 1, cv2.FILLED)
    area = cv2.countNonZero(inside)
    return area > 0 and np.count_nonzero(stood[inside > 0]) > 0.5 * area


def mask_box(mask: np.ndarray, margin: int) -> tuple[slice, slice] | None:
    """The box (slices) of a mask's nonzero pixels and `margin` more within the image, None if empty."""
    x, y, w, h = cv2.boundingRect(mask)
    if not w:
        return None
    return slice(max(0, y - margin), y + h + margin), slice(max(0, x - margin), x + w + margin)


def cleaning_disk(shape: tuple[int, ...]) -> np.ndarray:
    """The structuring element of the cleaning: about 1% of the frame height, odd, >= 3."""
    size = max(3, round(shape[0] / 100) | 1)
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (size, size))
