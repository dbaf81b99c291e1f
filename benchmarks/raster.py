"""Raster engine benchmark: pixelpen vs Pillow on the seeded workloads W1-W5 of graphics.md §1, in one process.

Run: ``python3 benchmarks/raster.py [--runs N] [--only W1,W3] [--pillow-flood-runs N]``.  Each workload's
inputs are generated outside the timing; a timing covers arrays -> finished canvas (or bytes), including
allocation and, for Pillow, converting the arrays to its per-primitive calls.  Reports the median of the
runs, the ratio pixelpen/Pillow, and a fidelity check (W1, W3, W4, W5: identical output; W2: Pillow's
polygon fill is a superset of the pixel-centre rule, so the check is "pixelpen ⊆ Pillow" plus the count of
extra Pillow pixels).
"""

from __future__ import annotations

import argparse
import random
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from PIL import Image, ImageChops, ImageDraw

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pixelpen.raster.canvas import Canvas

SEED = 20240601
SIZE = 1024


def median_time(fn: Callable[[], object], runs: int) -> tuple[float, object]:
    """Median wall time of fn over runs, and the result of the last run."""
    times = []
    result = None
    for _ in range(runs):
        t = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), result


def w1_inputs() -> np.ndarray:
    """100,000 segments with endpoints uniform in [0, 1024)²."""
    return np.random.default_rng(SEED).integers(0, SIZE, size=(100_000, 4))


def w1_pixelpen(seg: np.ndarray) -> np.ndarray:
    """W1 with Canvas.lines."""
    c = Canvas(SIZE, SIZE, "L")
    c.lines(seg, 255)
    return c.array


def w1_pillow(seg: np.ndarray) -> np.ndarray:
    """W1 with one ImageDraw.line call per segment."""
    im = Image.new("L", (SIZE, SIZE))
    line = ImageDraw.Draw(im).line
    for s in seg.tolist():
        line(s, fill=255)
    return np.asarray(im)


def w2_inputs() -> np.ndarray:
    """10,000 triangles: centre uniform in [64, 960)², vertices = centre + integer offset in [−64, 64]²."""
    rng = np.random.default_rng(SEED)
    centre = rng.integers(64, 960, size=(10_000, 1, 2))
    return centre + rng.integers(-64, 65, size=(10_000, 3, 2))


def w2_pixelpen(tris: np.ndarray) -> np.ndarray:
    """W2 with Canvas.triangles."""
    c = Canvas(SIZE, SIZE, "L")
    c.triangles(tris, 255)
    return c.array


def w2_pillow(tris: np.ndarray) -> np.ndarray:
    """W2 with one ImageDraw.polygon call per triangle."""
    im = Image.new("L", (SIZE, SIZE))
    polygon = ImageDraw.Draw(im).polygon
    for t in tris.tolist():
        polygon([tuple(p) for p in t], fill=255)
    return np.asarray(im)


def w3_inputs() -> tuple[np.ndarray, np.ndarray]:
    """2,000 outlined then 2,000 filled circles, r uniform in [4, 128], fully inside the canvas."""
    rng = np.random.default_rng(SEED)
    r = rng.integers(4, 129, size=4000)
    centres = np.stack([rng.integers(r, SIZE - r), rng.integers(r, SIZE - r)], axis=1)
    return centres, r


def w3_pixelpen(data: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """W3 with two Canvas.circles batches."""
    centres, r = data
    c = Canvas(SIZE, SIZE, "L")
    c.circles(centres[:2000], r[:2000], 255)
    c.circles(centres[2000:], r[2000:], 255, fill=True)
    return c.array


def w3_pillow(data: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """W3 with one ImageDraw.ellipse call per circle."""
    centres, r = data
    im = Image.new("L", (SIZE, SIZE))
    ellipse = ImageDraw.Draw(im).ellipse
    for i, ((x, y), rr) in enumerate(zip(centres.tolist(), r.tolist(), strict=True)):
        box = (x - rr, y - rr, x + rr, y + rr)
        if i < 2000:
            ellipse(box, outline=255)
        else:
            ellipse(box, fill=255)
    return np.asarray(im)


def w4_inputs() -> np.ndarray:
    """A perfect maze on 2048²: randomised depth-first search over 1023² cells, 1-px corridors (0 = open)."""
    n = 1023
    rng = random.Random(SEED)
    maze = np.ones((2048, 2048), dtype=np.uint8)
    seen = bytearray(n * n)
    opened = []
    stack = [0]
    seen[0] = 1
    while stack:
        cell = stack[-1]
        cy, cx = divmod(cell, n)
        options = []
        if cx > 0 and not seen[cell - 1]:
            options.append(cell - 1)
        if cx < n - 1 and not seen[cell + 1]:
            options.append(cell + 1)
        if cy > 0 and not seen[cell - n]:
            options.append(cell - n)
        if cy < n - 1 and not seen[cell + n]:
            options.append(cell + n)
        if not options:
            stack.pop()
            continue
        nxt = options[rng.randrange(len(options))]
        seen[nxt] = 1
        opened.append((cell, nxt))
        stack.append(nxt)
    maze[1:2 * n:2, 1:2 * n:2] = 0
    pairs = np.array(opened)
    ay, ax = np.divmod(pairs[:, 0], n)
    by, bx = np.divmod(pairs[:, 1], n)
    maze[ay + by + 1, ax + bx + 1] = 0
    return maze


def w4_pixelpen(maze: np.ndarray) -> np.ndarray:
    """W4 with Canvas.flood_fill (connected-component labelling)."""
    c = Canvas.from_array(maze, "L")
    c.flood_fill((1, 1), 128)
    return c.array


def w4_pillow(maze: np.ndarray) -> np.ndarray:
    """W4 with ImageDraw.floodfill."""
    im = Image.frombytes("L", (maze.shape[1], maze.shape[0]), maze.tobytes())  # fromarray would share memory
    ImageDraw.floodfill(im, (1, 1), 128)
    return np.asarray(im)


def w5_inputs() -> np.ndarray:
    """A seeded random 1920x1080 RGB frame."""
    return np.random.default_rng(SEED).integers(0, 256, size=(1080, 1920, 3), dtype=np.uint8)


def w5a_pillow(frame: np.ndarray) -> bytes:
    """Big-endian RGB565 by split + LUT ``point`` + ``ImageChops.add`` (disjoint bits) + merge "LA"."""
    r, g, b = Image.frombytes("RGB", (frame.shape[1], frame.shape[0]), frame.tobytes()).split()
    high = ImageChops.add(r.point([v & 0xF8 for v in range(256)]), g.point([v >> 5 for v in range(256)]))
    low = ImageChops.add(g.point([(v & 0x1C) << 3 for v in range(256)]), b.point([v >> 3 for v in range(256)]))
    return Image.merge("LA", (high, low)).tobytes()


def w5b_pillow(frame: np.ndarray) -> bytes:
    """SSD1306 pages: ``convert("1")`` without dither, transpose, ``tobytes("raw", "1;R")``, page-major order."""
    h, w = frame.shape[:2]
    mono = Image.frombytes("RGB", (w, h), frame.tobytes()).convert("1", dither=Image.Dither.NONE)
    columns = mono.transpose(Image.Transpose.TRANSPOSE).tobytes("raw", "1;R")
    return np.frombuffer(columns, dtype=np.uint8).reshape(w, -(-h // 8)).T.tobytes()


def main(argv: list[str] | None = None) -> int:
    """Run the selected workloads and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=7, help="timed runs per workload (median reported)")
    parser.add_argument("--pillow-flood-runs", type=int, default=3, help="runs of Pillow's slow flood fill (W4)")
    parser.add_argument("--only", default="W1,W2,W3,W4,W5", help="comma-separated workloads")
    args = parser.parse_args(argv)
    wanted = {w.strip().upper() for w in args.only.split(",")}
    rows = []

    def compare(name: str, ours: Callable, theirs: Callable, data: object, check: Callable, pillow_runs: int) -> None:
        """Time both implementations on the same input and record a table row."""
        ours(data)  # warm-up
        t_ours, a = median_time(lambda: ours(data), args.runs)
        t_pil, b = median_time(lambda: theirs(data), pillow_runs)
        rows.append((name, t_ours, t_pil, check(a, b)))
        print(f"{name}: pixelpen {t_ours:.4f} s, Pillow {t_pil:.4f} s", file=sys.stderr)

    def identical(a: np.ndarray, b: np.ndarray) -> str:
        """'identical' or how many pixels differ."""
        diff = int(np.count_nonzero(np.asarray(a) != np.asarray(b)))
        return "identical" if diff == 0 else f"{diff} px DIFFER"

    def subset(a: np.ndarray, b: np.ndarray) -> str:
        """Whether pixelpen's pixels are all in Pillow's, and how many Pillow adds."""
        outside = int(np.count_nonzero((a != 0) & (b == 0)))
        extra = int(np.count_nonzero((b != 0) & (a == 0)))
        return f"pixelpen ⊆ Pillow, Pillow +{extra} px" if outside == 0 else f"{outside} px NOT in Pillow"

    if "W1" in wanted:
        compare("W1 100k lines", w1_pixelpen, w1_pillow, w1_inputs(), identical, args.runs)
    if "W2" in wanted:
        compare("W2 10k triangles", w2_pixelpen, w2_pillow, w2_inputs(), subset, args.runs)
    if "W3" in wanted:
        compare("W3 4k circles", w3_pixelpen, w3_pillow, w3_inputs(), identical, args.runs)
    if "W4" in wanted:
        maze = w4_inputs()
        compare("W4 flood 2048² maze", w4_pixelpen, w4_pillow, maze,
                lambda a, b: identical(a, b) + f", {int((a == 128).sum())} px", args.pillow_flood_runs)
    if "W5" in wanted:
        try:
            from pixelpen.raster.formats import pack
        except ImportError as exc:
            print(f"W5 skipped: pixelpen.raster.formats.pack is not available ({exc})", file=sys.stderr)
        else:
            frame = w5_inputs()
            compare("W5a 1080p -> rgb565be", lambda f: pack(f, "rgb565be"), w5a_pillow, frame,
                    lambda a, b: "identical" if a == b else "bytes DIFFER", args.runs)
            compare("W5b 1080p -> mono-pages", lambda f: pack(f, "mono-pages"), w5b_pillow, frame,
                    lambda a, b: "identical" if a == b else "bytes DIFFER", args.runs)
    print(f"{'workload':<26} {'pixelpen s':>11} {'Pillow s':>10} {'ratio':>7}  check")
    for name, t_ours, t_pil, check in rows:
        print(f"{name:<26} {t_ours:>11.4f} {t_pil:>10.4f} {t_ours / t_pil:>7.3f}  {check}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
