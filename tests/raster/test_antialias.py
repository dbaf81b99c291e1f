"""Wu anti-aliased lines: the scalar reference's coverage properties, the batch against it, blending."""

from __future__ import annotations

import numpy as np
import pytest

from pixelpen.errors import ConfigError
from pixelpen.raster.antialias import wu_coverage, wu_line
from pixelpen.raster.canvas import Canvas


def coverage_map(segments, width: int, height: int) -> np.ndarray:
    """Sum of the scalar reference's coverages per on-canvas pixel, clipped to 1."""
    total = np.zeros((height, width))
    for s in segments:
        pts, cov = wu_line(*s)
        ok = (pts[:, 0] >= 0) & (pts[:, 0] < width) & (pts[:, 1] >= 0) & (pts[:, 1] < height)
        np.add.at(total, (pts[ok, 1], pts[ok, 0]), cov[ok])
    return np.minimum(total, 1.0)


def test_horizontal_and_diagonal_lines():
    pts, cov = wu_line(2, 3, 8, 3)
    lit = {tuple(p): c for p, c in zip(pts.tolist(), cov.tolist(), strict=False) if c > 0}
    assert lit == {(2, 3): 0.5, **{(x, 3): 1.0 for x in range(3, 8)}, (8, 3): 0.5}
    pts, cov = wu_line(0, 0, 5, 5)
    lit = {tuple(p) for p, c in zip(pts.tolist(), cov.tolist(), strict=False) if c > 0}
    assert lit == {(i, i) for i in range(6)}


def test_interior_columns_carry_unit_coverage():
    rng = np.random.default_rng(2)
    for x0, y0, x1, y1 in rng.uniform(0, 50, size=(100, 4)).tolist():
        pts, cov = wu_line(x0, y0, x1, y1)
        steep = abs(y1 - y0) > abs(x1 - x0)
        major = pts[:, 1] if steep else pts[:, 0]
        columns = np.unique(major)
        sums = np.array([cov[major == m].sum() for m in columns])
        assert np.allclose(sums[1:-1], 1.0)
        assert (cov >= -1e-12).all() and (cov <= 1 + 1e-12).all()
        # each pixel pair straddles the ideal line: its weighted centre is the line's minor position
        minor = pts[:, 0] if steep else pts[:, 1]
        for m in columns[1:-1]:
            sel = major == m
            t = (m - (y0 if steep else x0)) / ((y1 - y0) if steep else (x1 - x0))
            ideal = (x0 + t * (x1 - x0)) if steep else (y0 + t * (y1 - y0))
            assert abs((minor[sel] * cov[sel]).sum() - ideal) < 1e-9


def test_batch_equals_scalar_reference():
    rng = np.random.default_rng(5)
    segs = rng.uniform(-20, 70, size=(80, 4))
    segs[:10] = np.round(segs[:10])
    pixels, cover = wu_coverage(segs, 50, 40)
    got = np.zeros(50 * 40)
    got[pixels] = cover
    assert np.allclose(got.reshape(40, 50), coverage_map(segs.tolist(), 50, 40), atol=1e-9)


def test_blend_into_grey_and_rgba():
    c = Canvas(12, 5, "L")
    c.fill(100)
    c.lines([[1, 2, 10, 2]], 200, antialias=True)
    assert c.array[2, 5] == 200 and c.array[2, 1] == 150 and c.array[1, 5] == 100  # 100 + (200-100)·0.5
    c = Canvas(12, 5, "RGBA")
    c.lines([[1.0, 2.25, 10.0, 2.25]], (255, 0, 0), antialias=True)
    assert c.pixel(5, 2) == (191, 0, 0, 191) and c.pixel(5, 3) == (64, 0, 0, 64)  # 255·0.75 rounded half up


def test_antialias_restrictions():
    with pytest.raises(ConfigError, match="mode"):
        Canvas(5, 5, "1").lines([[0, 0, 4, 4]], 1, antialias=True)
    with pytest.raises(ConfigError, match="1 px"):
        Canvas(5, 5).lines([[0, 0, 4, 4]], 1, antialias=True, width=2)
    with pytest.raises(ConfigError, match="finite"):
        Canvas(5, 5).lines([[0, 0, float("inf"), 4]], 1, antialias=True)
    with pytest.raises(ConfigError, match="x1"):
        wu_line(0, 0, float("nan"), 1)
