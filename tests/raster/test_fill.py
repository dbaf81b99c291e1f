"""Flood and boundary fill: connected components (hypothesis), span-fill reference, a 4096² maze, errors."""

from __future__ import annotations

from collections import deque

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from pixelpen.errors import ConfigError
from pixelpen.raster.canvas import Canvas
from pixelpen.raster.fill import span_fill_reference


def bfs_region(fillable: np.ndarray, seed: tuple[int, int], connectivity: int) -> np.ndarray:
    """Breadth-first search over neighbours: the textbook recursion made iterative."""
    h, w = fillable.shape
    out = np.zeros_like(fillable, dtype=bool)
    x, y = seed
    if not fillable[y, x]:
        return out
    steps = [(1, 0), (-1, 0), (0, 1), (0, -1)] + ([(1, 1), (1, -1), (-1, 1), (-1, -1)] if connectivity == 8 else [])
    queue = deque([(x, y)])
    out[y, x] = True
    while queue:
        cx, cy = queue.popleft()
        for dx, dy in steps:
            nx, ny = cx + dx, cy + dy
            if 0 <= nx < w and 0 <= ny < h and fillable[ny, nx] and not out[ny, nx]:
                out[ny, nx] = True
                queue.append((nx, ny))
    return out


@settings(max_examples=60, deadline=None)
@given(arrays(np.uint8, st.tuples(st.integers(1, 14), st.integers(1, 14)), elements=st.integers(0, 2)),
       st.integers(0, 100), st.integers(0, 100), st.sampled_from([4, 8]))
def test_flood_fill_is_the_connected_component(grid, sx, sy, connectivity):
    h, w = grid.shape
    seed = (sx % w, sy % h)
    region = bfs_region(grid == grid[seed[1], seed[0]], seed, connectivity)
    assert (span_fill_reference(grid == grid[seed[1], seed[0]], seed, connectivity) == region).all()
    c = Canvas.from_array(grid, "L")
    n = c.flood_fill(seed, 7, connectivity)
    assert n == region.sum()
    assert (c.array == np.where(region, 7, grid)).all()


@settings(max_examples=40, deadline=None)
@given(arrays(np.uint8, st.tuples(st.integers(1, 12), st.integers(1, 12)), elements=st.integers(0, 3)),
       st.integers(0, 100), st.integers(0, 100), st.sampled_from([4, 8]))
def test_boundary_fill_textbook_semantics(grid, sx, sy, connectivity):
    h, w = grid.shape
    seed = (sx % w, sy % h)
    fillable = (grid != 1) & (grid != 2)  # boundary 1, fill value 2 (already-filled pixels also stop it)
    region = bfs_region(fillable, seed, connectivity)
    c = Canvas.from_array(grid, "L")
    assert c.boundary_fill(seed, 2, 1, connectivity) == region.sum()
    assert (c.array == np.where(region, 2, grid)).all()


def test_flood_fill_rgb_compares_all_channels_and_records_damage():
    c = Canvas(10, 6, "RGB")
    c.array[:, 5] = (255, 0, 0)
    c.array[2, 5] = (255, 0, 1)
    c.clear_damage()
    assert c.flood_fill((0, 0), (0, 0, 9)) == 30
    assert (c.array[:, :5] == (0, 0, 9)).all() and (c.array[:, 6:] == 0).all()
    assert c.damage(merge_cost=0) == [(0, 0, 5, 6)]
    assert c.flood_fill((0, 0), (0, 0, 9)) == 0  # same value: nothing to do


def test_serpentine_4096_maze():
    n = 4096
    maze = np.ones((n, n), dtype=np.uint8)
    maze[1::2, 1:-1] = 0  # corridors on odd rows
    maze[2:-1:4, -2] = 0  # joined alternately at the right...
    maze[4:-1:4, 1] = 0  # ...and the left end: one long 1-px path
    c = Canvas.from_array(maze, "L")
    filled = c.flood_fill((1, 1), 5)
    assert filled == int((maze == 0).sum())
    assert not (c.array == 0).any()


@pytest.mark.parametrize("call,match", [
    (lambda c: c.flood_fill((10, 0), 1), "outside"), (lambda c: c.flood_fill((0.5, 0), 1), "integers"),
    (lambda c: c.flood_fill((0, 0), 1, connectivity=6), "connectivity"), (lambda c: c.flood_fill(3, 1), "pair"),
    (lambda c: c.boundary_fill((0, 0), 1, 300), "0..255"),
])
def test_bad_fill_arguments(call, match):
    with pytest.raises(ConfigError, match=match):
        call(Canvas(10, 10))
