"""The framebuffer driver against linux/fb.h: struct offsets as literal numbers, a hand-built node, scalar packing.

The node here builds its screeninfo bytes with struct at fb.h's byte offsets (x86_64, panels.md §6) and
maps anonymous memory, so neither the driver's ctypes structs nor the simulator stand behind the answers.
"""

from __future__ import annotations

import ctypes
import errno
import mmap
import os
import struct

import numpy as np
import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.drivers import fbdev
from pixelpen.drivers.fbdev import DeviceNode, FbFixScreeninfo, FbVarScreeninfo, Framebuffer
from pixelpen.errors import ConfigError, LinkError
from pixelpen.sim.panels.fbdev import FbdevSim
from tests.fuzzing import QUICK_CASES, campaign

LP64 = ctypes.sizeof(ctypes.c_ulong) == 8
VAR = {"xres": 0, "yres": 4, "xres_virtual": 8, "yres_virtual": 12, "xoffset": 16, "yoffset": 20,
       "bits_per_pixel": 24, "grayscale": 28, "red": 32, "green": 44, "blue": 56, "transp": 68, "nonstd": 80,
       "activate": 84, "height": 88, "width": 92, "accel_flags": 96, "pixclock": 100, "sync": 128, "vmode": 132,
       "rotate": 136, "colorspace": 140, "reserved": 144}
FIX = {"id": 0, "smem_start": 16, "smem_len": 24, "type": 28, "type_aux": 32, "visual": 36, "xpanstep": 40,
       "ypanstep": 42, "ywrapstep": 44, "line_length": 48, "mmio_start": 56, "mmio_len": 64, "accel": 68,
       "capabilities": 72}


class Node:
    """A framebuffer node from fb.h's numbers: var/fix fields in dicts, the memory a file (shared mappings)."""

    def __init__(self, xres, yres, bpp, *, line_length, tmp_path, yres_virtual=None, fields=None, smem_len=None,
                 ypanstep=1, visual=2, fb_type=0, grayscale=0, pan_errno=None):
        yv = yres_virtual or yres
        self.name = "testfb"
        self.var = {"xres": xres, "yres": yres, "xres_virtual": xres, "yres_virtual": yv, "xoffset": 0,
                    "yoffset": 0, "bits_per_pixel": bpp, "grayscale": grayscale, "width": 0, "height": 0}
        self.fields = fields or {"red": (11, 5, 0), "green": (5, 6, 0), "blue": (0, 5, 0), "transp": (0, 0, 0)}
        self.fix = {"smem_len": line_length * yv if smem_len is None else smem_len, "type": fb_type,
                    "visual": visual, "ypanstep": ypanstep, "line_length": line_length}
        self.file = open(tmp_path / "fbmem", "w+b")  # noqa: SIM115 - closed with the test's tmp_path
        self.file.truncate(max(self.fix["smem_len"], 1))
        self.pan_errno = pan_errno
        self.pans: list[int] = []
        self.blanks: list[int] = []
        self.closed = False

    def var_bytes(self):
        out = bytearray(160)
        for name, value in self.var.items():
            struct.pack_into("<I", out, VAR[name], value)
        for name, (offset, length, msb) in self.fields.items():
            struct.pack_into("<3I", out, VAR[name], offset, length, msb)
        return bytes(out)

    def fix_bytes(self):
        out = bytearray(80)
        out[:6] = b"testfb"
        for name, value in self.fix.items():
            struct.pack_into("<H" if name.endswith("panstep") else "<I", out, FIX[name], value)
        return bytes(out)

    def ioctl(self, request, arg):
        if request == 0x4600:
            return self.var_bytes()
        if request == 0x4602:
            return self.fix_bytes()
        if request == 0x4606:
            if self.pan_errno:
                raise OSError(self.pan_errno, os.strerror(self.pan_errno))
            self.pans.append(struct.unpack_from("<I", arg, 20)[0])
            self.var["yoffset"] = self.pans[-1]
            return bytes(arg)
        if request == 0x4611:
            self.blanks.append(arg)
            return b""
        raise OSError(errno.ENOTTY, "Inappropriate ioctl for device")

    def map(self, length):
        return mmap.mmap(self.file.fileno(), length)

    def raw(self):
        self.file.seek(0)
        return self.file.read()

    def close(self):
        self.closed = True


@pytest.mark.skipif(not LP64, reason="offsets written for a 64-bit unsigned long")
def test_struct_layouts_are_linux_fb_h():
    assert ctypes.sizeof(FbVarScreeninfo) == 160 and ctypes.sizeof(FbFixScreeninfo) == 80
    for name, offset in VAR.items():
        assert getattr(FbVarScreeninfo, name).offset == offset, name
    for name, offset in FIX.items():
        assert getattr(FbFixScreeninfo, name).offset == offset, name
    assert ctypes.sizeof(fbdev.FbBitfield) == 12


def test_ioctl_numbers():
    iow = (1 << 30) | (4 << 16) | (ord("F") << 8) | 0x20  # _IOW('F', 0x20, __u32)
    assert (fbdev.FBIOGET_VSCREENINFO, fbdev.FBIOPUT_VSCREENINFO, fbdev.FBIOGET_FSCREENINFO) == (0x4600, 0x4601, 0x4602)
    expected = {"FBIOPAN_DISPLAY": 0x4606, "FBIOBLANK": 0x4611, "FBIO_WAITFORVSYNC": iow}
    assert {name: getattr(fbdev, name) for name in expected} == expected


def test_screeninfo_decoded_from_bytes(tmp_path):
    node = Node(1366, 768, 16, line_length=2752, tmp_path=tmp_path)
    node.var.update(width=344, height=193)
    fb = Framebuffer(node)
    assert (fb.width, fb.height, fb.line_length, fb.layout.bits_per_pixel) == (1366, 768, 2752, 16)
    assert fb.fix.id == b"testfb" and fb.size_mm == (344.0, 193.0)
    assert (fb.layout.red.offset, fb.layout.green.length, fb.layout.blue.offset) == (11, 6, 0)
    assert not fb.double_buffered and "yres_virtual = 768" in fb.buffering
    fb.close()
    assert node.closed and fb.closed


def word_bytes(pixel, fields, bpp):
    """The scalar reference from fb.h: each channel's top `length` bits at `offset`, the word little-endian."""
    word = 0
    for channel, value in zip(("red", "green", "blue"), pixel, strict=True):
        offset, length, _ = fields[channel]
        v = int(value)
        if length <= 8:
            bits = v >> (8 - length)
        else:  # widen by repeating the bits from the top
            bits = 0
            for i in range(length):
                bits |= ((v >> (7 - i % 8)) & 1) << (length - 1 - i)
        word |= bits << offset
    t_off, t_len, _ = fields["transp"]
    word |= ((1 << t_len) - 1) << t_off
    return word.to_bytes(4, "little")[: bpp // 8]


LAYOUTS = {
    "rgb565": (16, {"red": (11, 5, 0), "green": (5, 6, 0), "blue": (0, 5, 0), "transp": (0, 0, 0)}),
    "bgr565": (16, {"red": (0, 5, 0), "green": (5, 6, 0), "blue": (11, 5, 0), "transp": (0, 0, 0)}),
    "rgb555": (16, {"red": (10, 5, 0), "green": (5, 5, 0), "blue": (0, 5, 0), "transp": (0, 0, 0)}),
    "argb1555": (16, {"red": (10, 5, 0), "green": (5, 5, 0), "blue": (0, 5, 0), "transp": (15, 1, 0)}),
    "rgb888": (24, {"red": (16, 8, 0), "green": (8, 8, 0), "blue": (0, 8, 0), "transp": (0, 0, 0)}),
    "bgr888": (24, {"red": (0, 8, 0), "green": (8, 8, 0), "blue": (16, 8, 0), "transp": (0, 0, 0)}),
    "rgb666-24": (24, {"red": (12, 6, 0), "green": (6, 6, 0), "blue": (0, 6, 0), "transp": (0, 0, 0)}),
    "xrgb8888": (32, {"red": (16, 8, 0), "green": (8, 8, 0), "blue": (0, 8, 0), "transp": (0, 0, 0)}),
    "xbgr8888": (32, {"red": (0, 8, 0), "green": (8, 8, 0), "blue": (16, 8, 0), "transp": (0, 0, 0)}),
    "rgbx8888": (32, {"red": (24, 8, 0), "green": (16, 8, 0), "blue": (8, 8, 0), "transp": (0, 0, 0)}),
    "argb8888": (32, {"red": (16, 8, 0), "green": (8, 8, 0), "blue": (0, 8, 0), "transp": (24, 8, 0)}),
    "xrgb2101010": (32, {"red": (20, 10, 0), "green": (10, 10, 0), "blue": (0, 10, 0), "transp": (0, 0, 0)}),
}


@pytest.mark.parametrize("name", sorted(LAYOUTS))
def test_packing_matches_the_scalar_reference_at_the_stride(tmp_path, name):
    bpp, fields = LAYOUTS[name]
    w, h, stride = 13, 7, 64  # rows padded well past 13 * 4 bytes
    node = Node(w, h, bpp, line_length=stride, fields=fields, tmp_path=tmp_path)
    fb = Framebuffer(node)
    fb.memory[...] = 0xA5
    rgb = np.random.default_rng(len(name)).integers(0, 256, (4, 9, 3), dtype=np.uint8)
    fb.write(rgb, 3, 2)
    raw = node.raw()
    bpb = bpp // 8
    expected = bytearray(b"\xa5" * (stride * h))
    for y in range(4):
        for x in range(9):
            at = (y + 2) * stride + (x + 3) * bpb
            expected[at:at + bpb] = word_bytes(rgb[y, x], fields, bpp)
    assert raw[:stride * h] == bytes(expected)
    fb.close()


def test_grey_8_bpp_is_the_luma_of_each_pixel(tmp_path):
    node = Node(5, 2, 8, line_length=8, grayscale=1, visual=5, tmp_path=tmp_path,
                      fields={"red": (0, 8, 0), "green": (0, 8, 0), "blue": (0, 8, 0), "transp": (0, 0, 0)})
    fb = Framebuffer(node)
    rgb = np.random.default_rng(3).integers(0, 256, (2, 5, 3), dtype=np.uint8)
    fb.write(rgb)
    raw = node.raw()
    for y in range(2):
        for x in range(5):
            r, g, b = (int(c) for c in rgb[y, x])
            assert raw[y * 8 + x] == (299 * r + 587 * g + 114 * b + 500) // 1000


class PaletteNode(Node):
    """A pseudocolour node that keeps the FBIOPUTCMAP levels (read at the struct's pointers) or refuses it."""

    def __init__(self, *args, refuse=False, **kwargs):
        super().__init__(*args, **kwargs)
        self.refuse = refuse
        self.cmap: tuple[int, int, int, list[np.ndarray]] | None = None

    def ioctl(self, request, arg):
        if request != 0x4605:
            return super().ioctl(request, arg)
        if self.refuse:
            raise OSError(errno.EINVAL, "Invalid argument")
        start, length, red, green, blue, transp = struct.unpack("<IIQQQQ", arg)  # fb.h: u32, u32, 4 pointers
        self.cmap = (start, length, transp, [np.frombuffer(ctypes.string_at(p, 2 * length), "<u2")
                                             for p in (red, green, blue)])
        return bytes(arg)


@pytest.mark.skipif(not LP64, reason="fb_cmap written for 64-bit pointers")
def test_pseudocolour_gets_an_rgb332_palette(tmp_path, caplog):
    fields = {"red": (0, 8, 0), "green": (0, 8, 0), "blue": (0, 8, 0), "transp": (0, 0, 0)}
    node = PaletteNode(4, 2, 8, line_length=8, visual=3, fields=fields, tmp_path=tmp_path)
    fb = Framebuffer(node)
    assert node.cmap is not None
    start, length, transp, (red, green, blue) = node.cmap
    assert (start, length, transp) == (0, 256, 0)
    index = 0b101_011_10  # RRRGGGBB
    assert (red[index], green[index], blue[index]) == (5 * 65535 // 7, 3 * 65535 // 7, 2 * 65535 // 3)
    fb.write(np.array([[[255, 0, 0], [0, 255, 0], [0, 0, 255], [160, 100, 170]]], dtype=np.uint8))
    assert list(node.raw()[:4]) == [0b111_000_00, 0b000_111_00, 0b000_000_11, index]
    refused = Framebuffer(PaletteNode(4, 2, 8, line_length=8, visual=3, fields=fields, refuse=True,
                                      tmp_path=tmp_path))
    assert refused.layout.grey and "FBIOPUTCMAP failed" in caplog.text


@pytest.mark.parametrize("width, stride", [(1366, 2752), (480, 1024)])
def test_padded_strides_of_real_hardware(tmp_path, width, stride):
    node = Node(width, 4, 16, line_length=stride, tmp_path=tmp_path)
    fb = Framebuffer(node)
    fb.memory[...] = 0x5A
    fb.write(np.full((4, width, 3), 255, dtype=np.uint8))
    raw = np.frombuffer(node.raw(), dtype=np.uint8)[: 4 * stride].reshape(4, stride)
    assert (raw[:, : width * 2] == 0xFF).all()  # white RGB565 = 0xFFFF at y*line_length + x*2
    assert (raw[:, width * 2:] == 0x5A).all()  # the padding is never written
    # luma's linux_framebuffer writes row y at y * width * 2: row 1 would start inside row 0's padding
    assert width * 2 < stride


@pytest.mark.parametrize("change, words", [
    ({"bits_per_pixel": 0}, "var.bits_per_pixel = 0"),
    ({"bits_per_pixel": 4}, "var.bits_per_pixel = 4"),
    ({"xres": 0}, "var.xres = 0"),
    ({"yres_virtual": 1 << 20}, r"var.yres_virtual = 1048576 is not 1..65536"),
    ({"yres_virtual": 2}, "yres_virtual"),
    ({"yoffset": 4}, "var.xoffset, yoffset"),
    ({"grayscale": 0x34325258}, "FOURCC"),
])
def test_malformed_var_screeninfo_names_the_field(tmp_path, change, words):
    node = Node(8, 4, 16, line_length=16, yres_virtual=4, tmp_path=tmp_path)
    node.var.update(change)
    with pytest.raises(ConfigError, match=words):
        Framebuffer(node)
    assert node.closed  # the node is closed again when it is not usable


@pytest.mark.parametrize("fix, fields, words", [
    ({"line_length": 15}, None, r"fix.line_length = 15 bytes is shorter than .* = 8 .* \(16 bytes\)"),
    ({"smem_len": 63}, None, r"fix.smem_len = 63 is smaller than line_length x yres_virtual = 16 x 4 = 64"),
    ({"type": 1}, None, "fix.type = 1"),
    ({"visual": 0}, None, r"fix.visual = 0 \(mono01\)"),
    ({}, {"red": (11, 5, 1)}, "var.red.msb_right = 1"),
    ({}, {"green": (5, 0, 0)}, "var.green.length = 0"),
    ({}, {"blue": (12, 5, 0)}, r"var.blue \(offset 12, length 5\) does not fit var.bits_per_pixel = 16"),
])
def test_malformed_fix_and_bitfields_name_the_field(tmp_path, fix, fields, words):
    node = Node(8, 4, 16, line_length=16, tmp_path=tmp_path)
    node.fix.update(fix)
    node.fields.update(fields or {})
    with pytest.raises(ConfigError, match=words):
        Framebuffer(node)


def test_double_buffering_draws_on_the_hidden_page_and_pans(tmp_path):
    node = Node(4, 3, 16, line_length=8, yres_virtual=6, tmp_path=tmp_path)
    fb = Framebuffer(node)
    assert fb.double_buffered and (fb.visible_page, fb.draw_page) == (0, 1) and node.pans == [0]
    fb.write(np.full((3, 4, 3), 255, dtype=np.uint8))
    raw = node.raw()
    assert raw[:24] == bytes(24) and raw[24:48] == b"\xff" * 24  # page 1 starts at 3 * line_length
    fb.flip(vsync=False)
    assert node.pans == [0, 3] and fb.visible_page == 1 and fb.draw_page == 0


@pytest.mark.parametrize("change, words", [
    ({"ypanstep": 0}, "fix.ypanstep = 0"),
    ({"ypanstep": 2}, "fix.ypanstep = 2 cannot pan to line 3"),
    ({"pan_errno": errno.EINVAL}, "FBIOPAN_DISPLAY failed"),
])
def test_single_buffering_when_the_driver_cannot_pan(tmp_path, change, words):
    node = Node(4, 3, 16, line_length=8, yres_virtual=6, tmp_path=tmp_path,
                      ypanstep=change.get("ypanstep", 1), pan_errno=change.get("pan_errno"))
    fb = Framebuffer(node)
    assert not fb.double_buffered and words in fb.buffering
    fb.write(np.full((3, 4, 3), 255, dtype=np.uint8))
    fb.flip()  # nothing to flip
    assert node.raw()[:24] == b"\xff" * 24
    assert not Framebuffer(Node(4, 3, 16, line_length=8, yres_virtual=6, tmp_path=tmp_path),
                           double_buffer=False).double_buffered


def test_vsync_blank_and_the_simulated_node():
    clock = SimulatedClock(0.001)
    sim = FbdevSim(16, 8, 32, clock=clock, refresh_hz=50.0)
    fb = Framebuffer(sim.open())
    assert fb.wait_for_vsync() and fb.vsync_supported and clock.now() == pytest.approx(0.02)
    fb.blank(4)
    assert sim.blank_level == 4
    fb.blank(0)
    no_vsync = Framebuffer(FbdevSim(16, 8, 32, vsync=False).open())
    assert not no_vsync.wait_for_vsync() and no_vsync.vsync_supported is False
    no_vsync.flip()  # falls back to an unsynchronised pan
    fb.close()
    with pytest.raises(LinkError, match="closed"):
        fb.write(np.zeros((1, 1, 3), dtype=np.uint8))


def test_a_block_off_the_screen_is_refused(tmp_path):
    fb = Framebuffer(Node(4, 3, 16, line_length=8, tmp_path=tmp_path))
    with pytest.raises(ConfigError, match=r"a 2x2 block at \(3, 0\) does not fit the 4x3 screen"):
        fb.write(np.zeros((2, 2, 3), dtype=np.uint8), 3, 0)


def test_opening_nodes_names_the_problem(tmp_path, monkeypatch):
    with pytest.raises(LinkError, match=r"no-fb does not exist: load a framebuffer driver .*ls /dev/fb\*"):
        Framebuffer.open(str(tmp_path / "no-fb"))
    plain = tmp_path / "plain"
    plain.write_bytes(bytes(64))
    with pytest.raises(LinkError, match=r"FBIOGET_VSCREENINFO failed.*not a framebuffer"):
        Framebuffer.open(str(plain))
    with pytest.raises(LinkError, match=r"cannot open: \[Errno 21\]"):  # EISDIR: the OS's own words
        DeviceNode(str(tmp_path))

    def denied(path, flags):
        raise PermissionError(errno.EACCES, "Permission denied", path)

    monkeypatch.setattr(fbdev.os, "open", denied)
    with pytest.raises(LinkError, match=r"permission denied on .*plain: add your user to the '.+' group "
                                        r"\(sudo usermod -aG .*KERNEL==\"fb\*\", GROUP="):
        DeviceNode(str(plain))
    gone = str(tmp_path / "fb7")  # no node to read a group from: the conventional one, video
    with pytest.raises(LinkError) as denied_info:
        DeviceNode(gone)
    assert str(denied_info.value) == (
        f"permission denied on {gone}: add your user to the 'video' group (sudo usermod -aG video $USER, then log "
        'in again) or add a udev rule SUBSYSTEM=="graphics", KERNEL=="fb*", GROUP="video", MODE="0660"')


def test_a_get_ioctl_failing_is_a_link_error(tmp_path):
    class NotFb(Node):
        def ioctl(self, request, arg):
            raise OSError(errno.ENOTTY, "Inappropriate ioctl for device")

    with pytest.raises(LinkError, match="testfb: FBIOGET_VSCREENINFO failed"):
        Framebuffer(NotFb(4, 3, 16, line_length=8, tmp_path=tmp_path))


class BytesNode:
    """A node answering the two GET ioctls with given bytes (maybe truncated or oversized), memory a sparse file."""

    def __init__(self, var: bytes, fix: bytes, path):
        self.name, self.var, self.fix, self.path = "fuzzfb", var, fix, path

    def ioctl(self, request, arg):
        if request in (0x4600, 0x4602):
            return self.var if request == 0x4600 else self.fix
        raise OSError(errno.ENOTTY, "Inappropriate ioctl for device")

    def map(self, length):
        with open(self.path, "w+b") as file:
            file.truncate(length)
            return mmap.mmap(file.fileno(), length)

    def close(self):
        pass


def test_seeded_fuzz_of_screeninfo_gives_a_framebuffer_or_a_clean_error(tmp_path):
    seed = Node(13, 7, 16, line_length=64, yres_virtual=14, tmp_path=tmp_path)
    seeds = [seed.var_bytes() + seed.fix_bytes(), seed.var_bytes()[:100] + seed.fix_bytes()]

    def target(data: bytes) -> None:
        fb = Framebuffer(BytesNode(data[:160], data[160:240], tmp_path / "fuzzmem"))
        try:
            pixel = np.full((1, 1, 3), 200, dtype=np.uint8)
            fb.write(pixel, 0, 0)
            fb.write(pixel, fb.width - 1, fb.height - 1)
        finally:
            fb.close()

    campaign("fbdev screeninfo", target, seeds, QUICK_CASES, seed=7).check()
