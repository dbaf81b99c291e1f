"""Canvas: modes and native values, colour conversion, Pillow export without shared memory, copy, blit."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from pixelpen.errors import ConfigError
from pixelpen.raster.canvas import MODES, Canvas


@pytest.mark.parametrize("mode,shape,dtype", [("1", (3, 4), np.uint8), ("L", (3, 4), np.uint8), ("P", (3, 4), np.uint8),
                                              ("RGB565", (3, 4), np.uint16), ("RGB", (3, 4, 3), np.uint8),
                                              ("RGBA", (3, 4, 4), np.uint8)])
def test_modes_arrays(mode, shape, dtype):
    c = Canvas(4, 3, mode)
    assert c.array.shape == shape and c.array.dtype == dtype and c.size == (4, 3)
    assert (c.palette is not None) == (mode == "P")


def test_colour_values_per_mode():
    rgb = (200, 100, 50)
    assert Canvas(1, 1, "L").colour_value(rgb) == (299 * 200 + 587 * 100 + 114 * 50 + 500) // 1000
    assert Canvas(1, 1, "1").colour_value(rgb) == 0 and Canvas(1, 1, "1").colour_value((200, 150, 50)) == 1
    assert Canvas(1, 1, "RGB565").colour_value((255, 255, 255)) == 0xFFFF
    assert Canvas(1, 1, "RGB565").colour_value((0x12, 0x34, 0x56)) == 0x11AA  # 00010 001101 01010
    assert Canvas(1, 1, "RGB").colour_value(rgb) == rgb and Canvas(1, 1, "RGBA").colour_value(rgb) == (*rgb, 255)
    pal = Canvas(1, 1, "P", palette=[(0, 0, 0), (255, 0, 0), (190, 110, 40), (200, 100, 50)])
    assert pal.colour_value(rgb) == 3 and pal.colour_value((250, 5, 0)) == 1
    assert pal.palette.shape == (256, 3)


def test_to_rgb_every_mode():
    for mode, value, want in (
        ("1", 1, (255, 255, 255)),
        ("L", 77, (77, 77, 77)),
        ("RGB565", 0xF800, (255, 0, 0)),
        ("RGB565", 0x07E0, (0, 255, 0)),
        ("RGB", (1, 2, 3), (1, 2, 3)),
        ("RGBA", (1, 2, 3, 4), (1, 2, 3)),
    ):
        c = Canvas(3, 2, mode)
        c.fill(value)
        out = c.to_rgb()
        assert out.shape == (2, 3, 3) and out.dtype == np.uint8 and (out == want).all(), mode
    p = Canvas(2, 2, "P", palette=[(9, 8, 7), (1, 2, 3)])
    p.fill(1)
    assert (p.to_rgb() == (1, 2, 3)).all()


def test_to_image_does_not_share_memory_and_round_trips(tmp_path):
    for mode in MODES:
        c = Canvas(9, 5, mode)
        c.lines([[0, 0, 8, 4]], c.colour_value((255, 255, 255)))
        image = c.to_image()
        before = np.asarray(image).copy()
        c.array[...] = 0
        assert (np.asarray(image) == before).all(), mode
        assert image.size == (9, 5)
    c = Canvas(9, 5, "RGBA")
    c.lines([[0, 0, 8, 4]], (10, 20, 30, 40))
    path = tmp_path / "out.png"
    c.save(path)
    with Image.open(path) as back:
        assert back.mode == "RGBA" and (np.asarray(back) == c.array).all()
    m = Canvas(11, 3, "1")
    m.array[1, ::2] = 1
    assert (np.asarray(m.to_image()) == m.array.astype(bool)).all()


def test_copy_is_independent():
    c = Canvas(5, 5, "P")
    c.fill(3)
    d = c.copy()
    d.array[0, 0] = 9
    d.palette[3] = (1, 1, 1)
    assert c.array[0, 0] == 3 and (c.palette[3] == 3).all()
    assert d.damage() == c.damage()


def test_blit_clips():
    c = Canvas(6, 4, "RGB")
    src = np.arange(3 * 3 * 3, dtype=np.uint8).reshape(3, 3, 3)
    c.blit(src, 4, -1)
    assert (c.array[0:2, 4:6] == src[1:3, 0:2]).all() and c.array[:, :4].sum() == 0
    assert c.damage(merge_cost=0) == [(4, 0, 6, 2)]
    c.blit(src, 10, 10)  # wholly outside: nothing
    with pytest.raises(ConfigError, match="HxWx3 uint8"):
        c.blit(np.zeros((2, 2), np.uint8), 0, 0)


def test_from_array_and_pixel():
    c = Canvas.from_array(np.array([[0, 1], [1, 0]], np.uint8), "1")
    assert c.pixel(1, 0) == 1 and c.pixel(0, 0) == 0
    with pytest.raises(ConfigError, match="only 0 and 1"):
        Canvas.from_array(np.array([[0, 2]], np.uint8), "1")
    with pytest.raises(ConfigError, match="outside"):
        c.pixel(2, 0)


@pytest.mark.parametrize(
    "args,kwargs,match",
    [
        ((0, 5), {}, "width"),
        ((5, 5.5), {}, "height"),
        ((5, 5, "CMYK"), {}, "CMYK"),
        ((5, 5, "L", [(1, 2, 3)]), {}, "palette"),
        ((5, 5, "P", [(1, 2)]), {}, "palette"),
        ((5, 5, "P", [(1, 2, 300)]), {}, "0..255"),
        ((70000, 5), {}, "width"),
        ((5, 5), {"merge_cost": -3}, "merge_cost"),
    ],
)
def test_bad_canvas_arguments(args, kwargs, match):
    with pytest.raises(ConfigError, match=match):
        Canvas(*args, **kwargs)


@pytest.mark.parametrize(
    "mode,value",
    [
        ("1", 2),
        ("L", 256),
        ("L", -1),
        ("L", (1, 2, 3)),
        ("L", 1.5),
        ("RGB", 5),
        ("RGB", (1, 2)),
        ("RGB", (1, 2, 256)),
        ("RGBA", (1, 2, 3, 4, 5)),
        ("RGB565", 70000),
    ],
)
def test_bad_values_name_the_mode(mode, value):
    with pytest.raises(ConfigError, match=mode):
        Canvas(3, 3, mode).fill(value)


def test_bad_colour():
    with pytest.raises(ConfigError, match="colour"):
        Canvas(3, 3).colour_value((1, 2))
    with pytest.raises(ConfigError, match=r"0..255"):
        Canvas(3, 3).colour_value((1, 2, 300))


def test_colour_values_match_colour_value_in_every_mode():
    rng = np.random.default_rng(5)
    colours = rng.integers(0, 256, (50, 3))
    for mode in ("1", "L", "P", "RGB565", "RGB", "RGBA"):
        c = Canvas(4, 4, mode, palette=rng.integers(0, 256, (256, 3)) if mode == "P" else None)
        batch = c.colour_values(colours)
        for rgb, v in zip(colours.tolist(), batch, strict=False):
            single = c.colour_value(rgb)
            assert (tuple(int(x) for x in v) if np.ndim(v) else int(v)) == single


def test_put_colours_composites_over_and_records_damage():
    c = Canvas(4, 3, "RGB")
    c.fill((0, 0, 200))
    c.clear_damage()
    c.put_colours([1, 2], [0, 2], [[255, 0, 0, 255], [255, 255, 255, 0]])
    assert c.pixel(1, 0) == (255, 0, 0)  # opaque replaces
    assert c.pixel(2, 2) == (0, 0, 200)  # transparent leaves as it was
    c.put_colours([0], [1], [[255, 0, 0, 128]])
    # over: (255*128 + 0*127 + 127)//255 = 128 red; (200*127 + 127)//255 = 100 blue
    assert c.pixel(0, 1) == (128, 0, 100)
    ((x0, y0, x1, y1),) = [tuple(r) for r in c.damage()][:1] or [(None,) * 4]
    assert x0 <= 0 and y0 <= 0 and x1 >= 3 and y1 >= 3
    grey = Canvas(2, 2, "L")
    grey.put_colours([0], [0], [[255, 255, 255, 255]])
    assert grey.pixel(0, 0) == 255
    with pytest.raises(ConfigError):
        grey.put_colours([5], [0], [[0, 0, 0, 255]])
