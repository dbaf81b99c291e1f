"""The fbdev simulator: structs at linux/fb.h's offsets, the kernel's pan checks, glass decoding, luma as a client."""

from __future__ import annotations

import contextlib
import errno
import random
import struct

import numpy as np
import pytest
from PIL import Image

from pixelpen.clock import SimulatedClock
from pixelpen.errors import ConfigError, URLError
from pixelpen.sim.base import create_simulator
from pixelpen.sim.panels.fbdev import FbdevSim

GET_V, PUT_V, GET_F, PAN, BLANK, VSYNC = 0x4600, 0x4601, 0x4602, 0x4606, 0x4611, 0x40044620
LP64 = struct.calcsize("@L") == 8


def u32(data: bytes, offset: int) -> int:
    return struct.unpack_from("<I", data, offset)[0]


def var_with(sim: FbdevSim, **fields: int) -> bytes:
    """The sim's var struct with fields (at fb.h offsets) changed, as a program passes it to an ioctl."""
    offsets = {"xoffset": 16, "yoffset": 20, "bits_per_pixel": 24, "activate": 84, "vmode": 132}
    data = bytearray(sim.ioctl(GET_V, bytes(160)))
    for name, value in fields.items():
        struct.pack_into("<I", data, offsets[name], value)
    return bytes(data)


def test_var_screeninfo_bytes_are_at_fb_h_offsets():
    sim = FbdevSim(1366, 768, 16, stride=2752)
    var = sim.ioctl(GET_V, bytes(160))
    assert len(var) == 160
    assert [u32(var, o) for o in (0, 4, 8, 12, 16, 20, 24, 28)] == [1366, 768, 1366, 1536, 0, 0, 16, 0]
    assert [u32(var, o) for o in (32, 36, 40, 44, 48, 52, 56, 60, 64, 68, 72, 76)] == [11, 5, 0, 5, 6, 0, 0, 5, 0,
                                                                                        0, 0, 0]
    assert var[144:160] == bytes(16)  # reserved[4]


@pytest.mark.skipif(not LP64, reason="offsets written for a 64-bit unsigned long")
def test_fix_screeninfo_bytes_are_at_fb_h_offsets():
    sim = FbdevSim(1366, 768, 16, stride=2752, panstep=2)
    fix = sim.ioctl(GET_F, bytes(80))
    assert len(fix) == 80 and fix[:16].rstrip(b"\0") == b"pixelpen-fbsim"
    assert u32(fix, 24) >= 2752 * 1536 and u32(fix, 24) % 4096 == 0  # smem_len, whole pages
    assert (u32(fix, 28), u32(fix, 36)) == (0, 2)  # FB_TYPE_PACKED_PIXELS, FB_VISUAL_TRUECOLOR
    assert struct.unpack_from("<HHH", fix, 40) == (0, 2, 0)  # xpanstep, ypanstep, ywrapstep
    assert u32(fix, 48) == 2752  # line_length
    assert struct.unpack_from("<Q", fix, 16)[0] != 0  # smem_start


@pytest.mark.parametrize("width, bpp, stride", [
    (500, 16, 1024), (480, 16, 960), (320, 16, 640), (100, 24, 320), (10, 32, 64)])
def test_default_stride_pads_rows_to_64_bytes(width, bpp, stride):
    assert FbdevSim(width, 4, bpp).fix["line_length"] == stride


def test_bitfields_are_checked():
    assert FbdevSim(4, 2, 16, bitfields={"transp": (15, 1), "red": (10, 5)}).var["transp.offset"] == 15
    with pytest.raises(ConfigError, match=r"bitfield green = \(30, 6\)"):
        FbdevSim(4, 2, 32, bitfields={"green": (30, 6)})


def test_pan_follows_the_kernel_checks():
    sim = FbdevSim(8, 4, 16, panstep=2)
    sim.ioctl(PAN, var_with(sim, yoffset=4))
    assert sim.var["yoffset"] == 4 and sim.stats.pans == 1
    for fields in ({"yoffset": 5}, {"yoffset": 3}, {"xoffset": 1}, {"yoffset": 6}):
        with pytest.raises(OSError) as info:
            sim.ioctl(PAN, var_with(sim, **fields))
        assert info.value.errno == errno.EINVAL
    assert sim.var["yoffset"] == 4 and sim.stats.pans == 1
    no_pan = FbdevSim(8, 4, 16, panstep=0)
    no_pan.ioctl(PAN, var_with(no_pan, yoffset=0))  # offset 0 needs no pan step
    with pytest.raises(OSError, match="cannot pan"):
        no_pan.ioctl(PAN, var_with(no_pan, yoffset=4))


def test_put_vscreeninfo_pans_but_refuses_a_mode_change():
    sim = FbdevSim(8, 4, 16)
    answer = sim.ioctl(PUT_V, var_with(sim, yoffset=4))
    assert u32(answer, 20) == 4 and sim.stats.pans == 1
    with pytest.raises(OSError) as info:
        sim.ioctl(PUT_V, var_with(sim, bits_per_pixel=32))
    assert info.value.errno == errno.EINVAL and "bits_per_pixel" in str(info.value)


@pytest.mark.parametrize("request_, arg, code", [
    (0x4605, bytes(40), errno.ENOTTY),  # FBIOPUTCMAP on a truecolour framebuffer
    (GET_V, bytes(100), errno.EFAULT),
    (PAN, 3, errno.EFAULT),
    (BLANK, 9, errno.EINVAL),
    (VSYNC, struct.pack("<I", 1), errno.ENODEV),
])
def test_bad_ioctls_fail_with_the_kernels_errno(request_, arg, code):
    with pytest.raises(OSError) as info:
        FbdevSim(8, 4, 16).ioctl(request_, arg)
    assert info.value.errno == code


def test_vsync_waits_for_the_next_refresh_or_is_absent():
    clock = SimulatedClock(0.005)
    sim = FbdevSim(8, 4, 16, clock=clock, refresh_hz=100.0)
    sim.ioctl(VSYNC, bytes(4))
    assert clock.now() == pytest.approx(0.01) and sim.stats.vsync_waits == 1
    with pytest.raises(OSError) as info:
        FbdevSim(8, 4, 16, vsync=False).ioctl(VSYNC, bytes(4))
    assert info.value.errno == errno.ENOTTY


def decode(word: int, offset: int, length: int) -> int:
    """fb.h channel -> 8 bits: the field's value scaled to 0..255 by repeating its bits (exact for 255 and 0)."""
    value = (word >> offset) & ((1 << length) - 1)
    bits = [(value >> (length - 1 - i)) & 1 for i in range(length)]
    out = 0
    for i in range(8):
        out = out << 1 | bits[i % length]
    return out


@pytest.mark.parametrize("bpp, bgr", [(16, False), (16, True), (24, False), (32, False), (32, True)])
def test_glass_decodes_the_visible_page_with_bitfields_and_stride(bpp, bgr):
    sim = FbdevSim(6, 3, bpp, stride=64, bgr=bgr)
    memory = sim.map(sim.fix["smem_len"])
    raw = bytes(random.Random(bpp + bgr).randrange(256) for _ in range(64 * 6))
    memory[: len(raw)] = raw
    sim.ioctl(PAN, var_with(sim, yoffset=3))
    glass = np.asarray(sim.glass())
    b = bpp // 8
    for y in range(3):
        for x in range(6):
            at = (y + 3) * 64 + x * b
            word = int.from_bytes(raw[at:at + b], "little")
            want = [decode(word, sim.var[f"{c}.offset"], sim.var[f"{c}.length"]) for c in ("red", "green", "blue")]
            assert glass[y, x].tolist() == want, (x, y)
    sim.ioctl(BLANK, 4)
    assert not np.asarray(sim.glass()).any()  # a blanked screen is dark


@pytest.mark.skipif(not LP64, reason="fb_cmap written for 64-bit pointers")
def test_pseudocolour_glass_reads_the_palette_put_by_fbioputcmap():
    import ctypes

    sim = FbdevSim(4, 1, 8, pseudocolor=True)
    assert sim.fix["visual"] == 3 and sim.var["grayscale"] == 0
    levels = [(ctypes.c_uint16 * 2)(0xFFFF, 0x1200), (ctypes.c_uint16 * 2)(0, 0x3400), (ctypes.c_uint16 * 2)(0, 0x5600)]
    cmap = struct.pack("<IIQQQQ", 7, 2, *(ctypes.addressof(level) for level in levels), 0)  # fb.h fb_cmap
    sim.ioctl(0x4605, cmap)
    sim.map(sim.fix["smem_len"])[:4] = bytes([7, 8, 0, 255])
    assert np.asarray(sim.glass())[0].tolist() == [[255, 0, 0], [0x12, 0x34, 0x56], [0, 0, 0], [255, 255, 255]]
    for bad, code in ((struct.pack("<IIQQQQ", 255, 2, 8, 8, 8, 0), errno.EINVAL),
                      (struct.pack("<IIQQQQ", 0, 1, 16, 16, 16, 0), errno.EFAULT)):
        with pytest.raises(OSError) as info:
            sim.ioctl(0x4605, bad)
        assert info.value.errno == code
    with pytest.raises(OSError) as info:
        FbdevSim(4, 1, 16).ioctl(0x4605, cmap)  # a truecolour driver has no palette to set
    assert info.value.errno == errno.ENOTTY


def test_gram_is_the_raw_memory_and_survives_close():
    sim = FbdevSim(6, 3, 16)
    node = sim.open()
    node.map(sim.fix["smem_len"])[64:66] = b"\x12\x34"
    assert sim.gram.shape == (6, 64) and sim.gram[1, :2].tolist() == [0x12, 0x34]
    node.close()
    with pytest.raises(OSError) as info:
        node.ioctl(GET_V, bytes(160))
    assert info.value.errno == errno.EBADF
    sim.close()
    assert sim.gram[1, :2].tolist() == [0x12, 0x34] and sim.glass().size == (6, 3)
    with pytest.raises(OSError):
        sim.open()
    with pytest.raises(OSError, match="cannot map"):
        FbdevSim(6, 3, 16).map(1 << 20)


def test_url_options_build_the_simulator():
    sim = create_simulator("fbdev", size="1366x768", bpp="16", stride="2752", virtual="768", bgr="true",
                           vsync="false", panstep="0")
    assert (sim.width, sim.height, sim.fix["line_length"], sim.var["yres_virtual"]) == (1366, 768, 2752, 768)
    assert (sim.var["red.offset"], sim.var["blue.offset"], sim.vsync, sim.fix["ypanstep"]) == (0, 11, False, 0)
    for options, words in (({"stride": "100"}, "stride 100 is shorter than a row of 64 pixels"),
                           ({"bpp": "12"}, "bpp must be 8, 16, 24 or 32"),
                           ({"size": "10x2.5"}, "whole pixels"), ({"colour": "x"}, "unknown option"),
                           ({"stride": "99999999"}, "MAX_MEMORY")):
        with pytest.raises(URLError, match=words):
            create_simulator("fbdev", **{"size": "64x8", **options})


def test_seeded_fuzz_of_ioctls_raises_only_oserror():
    rng = random.Random(10)
    sim = FbdevSim(16, 8, 8, clock=SimulatedClock(), pseudocolor=True)
    requests = [GET_V, PUT_V, GET_F, PAN, BLANK, VSYNC, 0x4605, rng.randrange(1 << 32)]
    for _ in range(400):
        arg: bytes | int = (rng.randrange(-5, 10) if rng.random() < 0.2
                            else bytes(rng.randrange(256) for _ in range(rng.choice((0, 3, 4, 40, 80, 160, 200)))))
        with contextlib.suppress(OSError):
            sim.ioctl(rng.choice(requests), arg)
        assert 0 <= sim.var["yoffset"] <= 8 and sim.var["xoffset"] == 0
    assert sim.glass().size == (16, 8)


# ---- luma.core's linux_framebuffer as a client ------------------------------------------------------------------

def luma_on(sim: FbdevSim, monkeypatch, tmp_path, bgr: bool = False):
    """luma's linux_framebuffer writing into the simulator's memory file (sysfs answers from the sim's var)."""
    device_module = pytest.importorskip("luma.core.device")
    sysfs = {"virtual_size": f"{sim.var['xres_virtual']},{sim.var['yres_virtual']}",
             "bits_per_pixel": str(sim.var["bits_per_pixel"])}

    def fake_open(path, mode="r", *args, **kwargs):
        if path.startswith("/sys/class/graphics/fb7/"):
            file = tmp_path / path.rsplit("/", 1)[1]
            file.write_text(sysfs[file.name])
            return open(file, mode)
        assert path == "/dev/fb7"
        return open(sim.path, "r+b")  # luma opens "wb", which would truncate the mapped file

    monkeypatch.setattr(device_module, "open", fake_open, raising=False)
    device = device_module.linux_framebuffer("/dev/fb7", bgr=bgr)
    device.persist = True  # else luma's cleanup (also registered with atexit) clears the screen
    return device


@pytest.mark.filterwarnings("ignore:Image.Image.getdata is deprecated")
def test_luma_draws_correctly_on_an_unpadded_framebuffer(monkeypatch, tmp_path):
    sim = FbdevSim(40, 20, 24, stride=120, virtual_height=20, bgr=False, path=str(tmp_path / "mem"))
    image = Image.fromarray(np.random.default_rng(0).integers(0, 256, (20, 40, 3), dtype=np.uint8))
    device = luma_on(sim, monkeypatch, tmp_path, bgr=True)  # luma's bgr=True is fb.h's usual red offset 16
    device.display(image)
    device.cleanup()
    assert np.array_equal(np.asarray(sim.glass()), np.asarray(image))


@pytest.mark.filterwarnings("ignore:Image.Image.getdata is deprecated")
def test_luma_shears_the_picture_when_rows_are_padded(monkeypatch, tmp_path):
    sim = FbdevSim(40, 20, 16, stride=128, virtual_height=20, path=str(tmp_path / "mem"))
    image = Image.fromarray(np.full((20, 40, 3), 255, dtype=np.uint8))
    device = luma_on(sim, monkeypatch, tmp_path)
    device.display(image)
    device.cleanup()
    glass = np.asarray(sim.glass())
    # luma writes row y at y * 80 bytes (stride assumed = width * 2): rows after the first land in the padding
    assert glass[0].all() and not glass[19].any()
    assert (sim.gram[:, 80:] == 0xFF).any()
