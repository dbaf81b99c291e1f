"""Flood fill and boundary fill (Hearn & Baker §3.14) without recursion, and a scan-line span-fill reference.

The textbook fills recurse on 4 or 8 neighbours: a flood fill replaces the connected region of the seed's
old value, a boundary fill spreads until pixels of the boundary value (pixels already of the fill value
also stop it, as in ``boundaryFill4``).  Both regions are connected components of a boolean mask, so they
are found with ``scipy.ndimage.label`` (C speed, no recursion, any region size);
:func:`span_fill_reference` is the book's scan-line span fill in pure Python, kept for the tests.
"""

from __future__ import annotations

import numpy as np

from pixelpen.errors import ConfigError

_STRUCTURES = {4: np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], bool), 8: np.ones((3, 3), bool)}
"""4- and 8-neighbour structures (scipy.ndimage.generate_binary_structure(2, 1) and (2, 2))."""


def check_seed(seed: object, width: int, height: int) -> tuple[int, int]:
    """The seed as (x, y) ints on the canvas, or ConfigError."""
    try:
        x, y = seed  # type: ignore[misc]
        xi, yi = int(x), int(y)  # type: ignore[has-type]
    except (TypeError, ValueError):
        raise ConfigError(f"seed must be an (x, y) pair of integers, found {seed!r}") from None
    if xi != x or yi != y:  # type: ignore[has-type]
        raise ConfigError(f"seed must be an (x, y) pair of integers, found {seed!r}")
    if not (0 <= xi < width and 0 <= yi < height):
        raise ConfigError(f"seed {seed!r} is outside the {width}x{height} canvas")
    return xi, yi


def check_connectivity(connectivity: object) -> int:
    """4 or 8, or ConfigError."""
    if connectivity not in _STRUCTURES:
        raise ConfigError(f"connectivity must be 4 or 8, found {connectivity!r}")
    return int(connectivity)  # type: ignore[call-overload,unused-ignore]


def equal_mask(array: np.ndarray, value: np.ndarray) -> np.ndarray:
    """HxW bool: pixels equal to value (all channels for HxWxC arrays)."""
    eq = array == value
    return eq.all(axis=2) if array.ndim == 3 else eq


def connected_region(fillable: np.ndarray, seed: tuple[int, int], connectivity: int = 4
                     ) -> tuple[tuple[slice, slice], np.ndarray] | None:
    """The connected component of ``fillable`` containing seed (x, y): (bounding slices, mask within them).

    None when the seed pixel itself is not fillable.
    """
    x, y = seed
    if not fillable[y, x]:
        return None
    from scipy import ndimage  # imported here: a display that never fills need not load scipy (0.5 s)

    labels, _ = ndimage.label(fillable, structure=_STRUCTURES[check_connectivity(connectivity)])
    label = int(labels[y, x])
    box = ndimage.find_objects(labels, max_label=label)[label - 1]
    return box, labels[box] == label


def span_fill_reference(fillable: np.ndarray, seed: tuple[int, int], connectivity: int = 4) -> np.ndarray:
    """Scan-line span fill (Hearn & Baker): bool mask of the region of ``fillable`` connected to seed (x, y).

    Pure Python with an explicit stack of span seeds: fill the run through the seed, then push one seed
    per fillable run in the rows above and below (widened by one pixel each side for 8-connectivity).
    """
    check_connectivity(connectivity)
    grid = np.asarray(fillable, dtype=bool)
    height, width = grid.shape
    cells = grid.tolist()
    done = [[False] * width for _ in range(height)]
    x, y = seed
    if not cells[y][x]:
        return np.zeros_like(grid)
    reach = 1 if connectivity == 8 else 0
    stack = [(x, y)]
    while stack:
        x, y = stack.pop()
        row, filled = cells[y], done[y]
        if filled[x] or not row[x]:
            continue
        left = x
        while left > 0 and row[left - 1] and not filled[left - 1]:
            left -= 1
        right = x
        while right < width - 1 and row[right + 1] and not filled[right + 1]:
            right += 1
        for i in range(left, right + 1):
            filled[i] = True
        for ny in (y - 1, y + 1):
            if not 0 <= ny < height:
                continue
            nrow, nfilled = cells[ny], done[ny]
            i = max(left - reach, 0)
            end = min(right + reach, width - 1)
            while i <= end:
                if nrow[i] and not nfilled[i]:
                    stack.append((i, ny))
                    while i <= end and nrow[i] and not nfilled[i]:
                        i += 1
                i += 1
    return np.array(done, dtype=bool)
