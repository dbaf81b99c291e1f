"""A Linux framebuffer simulator: a memory-mapped file behind real ``fb_var_screeninfo``/``fb_fix_screeninfo`` bytes.

The structs are laid out from ``linux/fb.h`` at the literal byte offsets below (written apart from the host
driver's ctypes decoder, so each checks the other).  ``open()`` gives a node with ``ioctl`` and ``map`` as
``/dev/fbN`` has: FBIOGET/FBIOPUT_VSCREENINFO, FBIOGET_FSCREENINFO, FBIOPAN_DISPLAY (checked as the kernel's
``fb_pan_display`` does: EINVAL for an offset off ``ypanstep`` or past the virtual screen), FBIOBLANK,
FBIO_WAITFORVSYNC (option ``vsync``; else ENOTTY, as drivers without it answer), FBIOPUTCMAP (8-bit
pseudocolour; the levels are read at the caller's pointers in this process), anything else ENOTTY.
Rows are padded (default stride: the row rounded up to 64 bytes) and the virtual screen is two pages high.
"""

from __future__ import annotations

import errno
import math
import mmap
import os
import struct
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass
from typing import IO, Any

import numpy as np
from PIL import Image

from pixelpen.clock import REAL_CLOCK, Clock
from pixelpen.errors import ConfigError, URLError
from pixelpen.options import OptionSpec, boolean, integer, number, pixels, read_options, text
from pixelpen.sim.base import register_simulator

FBIOGET_VSCREENINFO, FBIOPUT_VSCREENINFO, FBIOGET_FSCREENINFO = 0x4600, 0x4601, 0x4602
FBIOPUTCMAP, FBIOPAN_DISPLAY, FBIOBLANK, FBIO_WAITFORVSYNC = 0x4605, 0x4606, 0x4611, 0x40044620
FB_VMODE_YWRAP = 256

VAR_SIZE = 160
VAR_OFFSETS: dict[str, int] = {
    "xres": 0, "yres": 4, "xres_virtual": 8, "yres_virtual": 12, "xoffset": 16, "yoffset": 20,
    "bits_per_pixel": 24, "grayscale": 28,
    "red.offset": 32, "red.length": 36, "red.msb_right": 40, "green.offset": 44, "green.length": 48,
    "green.msb_right": 52, "blue.offset": 56, "blue.length": 60, "blue.msb_right": 64,
    "transp.offset": 68, "transp.length": 72, "transp.msb_right": 76,
    "nonstd": 80, "activate": 84, "height": 88, "width": 92, "accel_flags": 96, "pixclock": 100,
    "left_margin": 104, "right_margin": 108, "upper_margin": 112, "lower_margin": 116, "hsync_len": 120,
    "vsync_len": 124, "sync": 128, "vmode": 132, "rotate": 136, "colorspace": 140,
}
"""``fb_var_screeninfo``: every field a u32 at this byte offset (reserved[4] at 144..159)."""

FIX_LAYOUTS: dict[int, tuple[int, dict[str, tuple[int, str]]]] = {
    8: (80, {"smem_start": (16, "Q"), "smem_len": (24, "I"), "type": (28, "I"), "type_aux": (32, "I"),
             "visual": (36, "I"), "xpanstep": (40, "H"), "ypanstep": (42, "H"), "ywrapstep": (44, "H"),
             "line_length": (48, "I"), "mmio_start": (56, "Q"), "mmio_len": (64, "I"), "accel": (68, "I"),
             "capabilities": (72, "H")}),
    4: (68, {"smem_start": (16, "I"), "smem_len": (20, "I"), "type": (24, "I"), "type_aux": (28, "I"),
             "visual": (32, "I"), "xpanstep": (36, "H"), "ypanstep": (38, "H"), "ywrapstep": (40, "H"),
             "line_length": (44, "I"), "mmio_start": (48, "I"), "mmio_len": (52, "I"), "accel": (56, "I"),
             "capabilities": (60, "H")}),
}
"""``fb_fix_screeninfo`` by ``sizeof(unsigned long)``: (struct size, field -> (offset, struct code)); id[16] at 0."""

FIX_SIZE = FIX_LAYOUTS[struct.calcsize("@L")][0]
"""The struct's size on this machine (80 on 64-bit, 68 on 32-bit)."""

VISUAL_TRUECOLOR, VISUAL_PSEUDOCOLOR, VISUAL_STATIC_PSEUDOCOLOR = 2, 3, 5
CMAP_LAYOUTS = {8: (40, "<IIQQQQ"), 4: (24, "<IIIIII")}
"""``fb_cmap`` by ``sizeof(void *)``: (size, struct code for start, len, red, green, blue, transp pointers)."""
SMEM_START = 0xFD000000
"""The physical address the simulated memory pretends to start at."""

Field = tuple[int, int]
"""A bitfield: (offset, length)."""

DEFAULT_BITFIELDS: dict[int, dict[str, Field]] = {
    8: {"red": (0, 8), "green": (0, 8), "blue": (0, 8), "transp": (0, 0)},
    16: {"red": (11, 5), "green": (5, 6), "blue": (0, 5), "transp": (0, 0)},
    24: {"red": (16, 8), "green": (8, 8), "blue": (0, 8), "transp": (0, 0)},
    32: {"red": (16, 8), "green": (8, 8), "blue": (0, 8), "transp": (0, 0)},
}
"""Default layouts: 8 bpp grey, RGB565, RGB888 (memory B, G, R), XRGB8888; ``bgr`` swaps red and blue."""

MAX_MEMORY = 1 << 28
"""Largest simulated framebuffer memory in bytes (line_length x yres_virtual): 256 MiB."""

STRIDE_ALIGN = 64
"""Default row padding: rows start every multiple of this many bytes (as many display controllers need)."""


@dataclass
class FbdevStats:
    """What programs did to the simulated framebuffer (counters; the live view shows them)."""

    ioctls: int = 0
    pans: int = 0
    """Successful FBIOPAN_DISPLAY calls (and yoffset changes by FBIOPUT_VSCREENINFO)."""
    vsync_waits: int = 0
    palette_loads: int = 0


class FbdevSim:
    """A simulated ``/dev/fbN``: screeninfo structs, ioctls and a memory-mapped file as the framebuffer memory."""

    model = "fbdev"

    def __init__(
        self, width: int, height: int, bpp: int = 16, *, stride: int | None = None,
        virtual_height: int | None = None, bitfields: Mapping[str, Field] | None = None, bgr: bool = False,
        vsync: bool = True, panstep: int = 1, pseudocolor: bool = False, refresh_hz: float = 60.0,
        path: str | None = None, clock: Clock | None = None, name: str = "pixelpen-fbsim",
    ) -> None:
        if bpp not in DEFAULT_BITFIELDS:
            raise ConfigError(f"fbdev simulator: bpp must be 8, 16, 24 or 32, got {bpp!r}")
        for label, value in (("width", width), ("height", height)):
            if not isinstance(value, int) or not 1 <= value <= 16384:
                raise ConfigError(f"fbdev simulator: {label} must be 1..16384 pixels, got {value!r}")
        row = width * bpp // 8
        stride = -(-row // STRIDE_ALIGN) * STRIDE_ALIGN if stride is None else stride
        if stride < row:
            raise ConfigError(f"fbdev simulator: stride {stride} is shorter than a row of {width} pixels at "
                              f"{bpp} bpp ({row} bytes)")
        virtual_height = 2 * height if virtual_height is None else virtual_height
        if virtual_height < height:
            raise ConfigError(f"fbdev simulator: virtual height {virtual_height} is less than the height {height}")
        if pseudocolor and bpp != 8:
            raise ConfigError(f"fbdev simulator: pseudocolour needs bpp 8, got {bpp}")
        if not 0 <= panstep <= 0xFFFF:
            raise ConfigError(f"fbdev simulator: panstep must be 0..65535, got {panstep}")
        fields = dict(DEFAULT_BITFIELDS[bpp])
        if bgr:
            fields["red"], fields["blue"] = fields["blue"], fields["red"]
        fields.update(bitfields or {})
        for channel, (offset, length) in fields.items():
            if channel not in DEFAULT_BITFIELDS[16] or not (offset >= 0 and length >= 0 and offset + length <= 32):
                raise ConfigError(f"fbdev simulator: bitfield {channel} = ({offset}, {length}) is not a channel's "
                                  f"(offset, length) inside a 32-bit word")
        if stride * virtual_height > MAX_MEMORY:
            raise ConfigError(f"fbdev simulator: {stride} x {virtual_height} bytes is more than MAX_MEMORY = "
                              f"{MAX_MEMORY}")
        self.clock = clock if clock is not None else REAL_CLOCK
        self.refresh_hz = refresh_hz
        self.vsync = vsync
        self.id = name
        self.var: dict[str, int] = dict.fromkeys(VAR_OFFSETS, 0)
        """The current ``fb_var_screeninfo`` fields (``red.offset`` style names for the bitfields)."""
        self.var.update(xres=width, yres=height, xres_virtual=width, yres_virtual=virtual_height,
                        bits_per_pixel=bpp, grayscale=int(bpp == 8 and bitfields is None and not pseudocolor))
        for channel, (offset, length) in fields.items():
            self.var[f"{channel}.offset"], self.var[f"{channel}.length"] = offset, length
        size = stride * virtual_height
        self.fix: dict[str, int] = dict.fromkeys(FIX_LAYOUTS[8][1], 0)
        """The ``fb_fix_screeninfo`` fields (``id`` apart)."""
        visual = VISUAL_STATIC_PSEUDOCOLOR if self.var["grayscale"] else VISUAL_TRUECOLOR
        self.fix.update(smem_start=SMEM_START, smem_len=-(-size // mmap.PAGESIZE) * mmap.PAGESIZE,
                        visual=VISUAL_PSEUDOCOLOR if pseudocolor else visual, ypanstep=panstep, line_length=stride)
        self.fix_id = name.encode("ascii", "replace")[:15]
        self.palette = np.repeat(np.arange(256, dtype=np.uint16)[:, None] * 257, 3, axis=1)
        """Pseudocolour: (256, 3) uint16 red, green, blue levels per index (FBIOPUTCMAP; a grey ramp at first)."""
        self.blank_level = 0
        """The last FBIOBLANK level (0: showing; 1..4 blanked: the glass is black)."""
        self.stats = FbdevStats()
        self.path = path
        self._file: IO[bytes] = open(path, "w+b") if path else tempfile.TemporaryFile()  # noqa: SIM115
        self._file.truncate(self.fix["smem_len"])
        self._memory = mmap.mmap(self._file.fileno(), self.fix["smem_len"])
        self.closed = False

    # -- the structs -------------------------------------------------------------------------------------
    def var_bytes(self) -> bytes:
        """``fb_var_screeninfo`` as the kernel hands it out (160 bytes)."""
        out = bytearray(VAR_SIZE)
        for name, offset in VAR_OFFSETS.items():
            struct.pack_into("<I", out, offset, self.var[name] & 0xFFFFFFFF)
        return bytes(out)

    def fix_bytes(self) -> bytes:
        """``fb_fix_screeninfo`` as the kernel hands it out (80 bytes on 64-bit)."""
        size, layout = FIX_LAYOUTS[struct.calcsize("@L")]
        out = bytearray(size)
        out[: len(self.fix_id)] = self.fix_id
        for name, (offset, code) in layout.items():
            struct.pack_into("<" + code, out, offset, self.fix[name])
        return bytes(out)

    @staticmethod
    def parse_var(data: bytes) -> dict[str, int]:
        """The fields of a 160-byte ``fb_var_screeninfo``."""
        return {name: struct.unpack_from("<I", data, offset)[0] for name, offset in VAR_OFFSETS.items()}

    # -- the device node ---------------------------------------------------------------------------------
    def open(self) -> FbdevNode:
        """Open the simulated node (as ``os.open("/dev/fb0", O_RDWR)``); several may be open at once."""
        if self.closed:
            raise OSError(errno.ENODEV, "the simulated framebuffer is gone", self.id)
        return FbdevNode(self)

    def ioctl(self, request: int, arg: bytes | int) -> bytes:
        """Answer one ioctl as a framebuffer driver does; failures are OSError with the kernel's errno."""
        if self.closed:
            raise OSError(errno.ENODEV, "no such device")
        self.stats.ioctls += 1
        if request == FBIOBLANK:
            if not isinstance(arg, int) or not 0 <= arg <= 4:
                raise OSError(errno.EINVAL, f"FBIOBLANK level {arg!r}")
            self.blank_level = arg
            return b""
        if isinstance(arg, int):
            raise OSError(errno.EFAULT, "bad address")
        if request == FBIOGET_VSCREENINFO:
            return self._copy_out(self.var_bytes(), arg)
        if request == FBIOGET_FSCREENINFO:
            return self._copy_out(self.fix_bytes(), arg)
        if request == FBIOPUT_VSCREENINFO:
            self._put_var(self._copy_in(arg, VAR_SIZE))
            return self._copy_out(self.var_bytes(), arg)
        if request == FBIOPAN_DISPLAY:
            self._pan(self._copy_in(arg, VAR_SIZE))
            return bytes(arg)
        if request == FBIOPUTCMAP and self.fix["visual"] == VISUAL_PSEUDOCOLOR:
            self._put_cmap(arg)
            return bytes(arg)
        if request == FBIO_WAITFORVSYNC and self.vsync:
            if struct.unpack_from("<I", self._copy_in(arg, 4))[0] != 0:
                raise OSError(errno.ENODEV, "no such CRTC")
            self._wait_vblank()
            return bytes(arg)
        raise OSError(errno.ENOTTY, "inappropriate ioctl for device")

    @staticmethod
    def _copy_in(arg: bytes, size: int) -> bytes:
        if len(arg) < size:
            raise OSError(errno.EFAULT, f"bad address: {len(arg)} bytes for a {size}-byte struct")
        return bytes(arg[:size])

    @staticmethod
    def _copy_out(data: bytes, arg: bytes) -> bytes:
        if len(arg) < len(data):
            raise OSError(errno.EFAULT, f"bad address: {len(arg)} bytes for a {len(data)}-byte struct")
        return data + bytes(arg[len(data):])

    def _pan(self, data: bytes) -> None:
        """``fb_pan_display``: offsets on the pan steps and inside the virtual screen, else EINVAL."""
        want = self.parse_var(data)
        x, y, var, fix = want["xoffset"], want["yoffset"], self.var, self.fix
        yres = var["yres"]
        bad = False
        if y > 0:
            if want["vmode"] & FB_VMODE_YWRAP:
                bad = not fix["ywrapstep"] or y % fix["ywrapstep"] != 0
                yres = 0
            else:
                bad = not fix["ypanstep"] or y % fix["ypanstep"] != 0
        if x > 0 and (not fix["xpanstep"] or x % fix["xpanstep"]):
            bad = True
        if bad or y > var["yres_virtual"] - yres or x > var["xres_virtual"] - var["xres"]:
            raise OSError(errno.EINVAL, f"cannot pan to xoffset {x}, yoffset {y}")
        if want["vmode"] & FB_VMODE_YWRAP:  # the simulator does not wrap: refuse as a driver without it does
            raise OSError(errno.EINVAL, "y-wrap is not supported")
        var["xoffset"], var["yoffset"] = x, y
        self.stats.pans += 1

    def _put_var(self, data: bytes) -> None:
        """FBIOPUT_VSCREENINFO: the mode is fixed (other geometry is EINVAL); new offsets pan."""
        want = self.parse_var(data)
        fixed = [name for name in VAR_OFFSETS if name.split(".")[0] in {
            "xres", "yres", "xres_virtual", "yres_virtual", "bits_per_pixel", "grayscale",
            "red", "green", "blue", "transp"} and want[name] != self.var[name]]
        if fixed:
            raise OSError(errno.EINVAL, f"mode change refused ({', '.join(fixed)})")
        if (want["xoffset"], want["yoffset"]) != (self.var["xoffset"], self.var["yoffset"]):
            self._pan(data)
        self.var["activate"] = want["activate"]

    def _put_cmap(self, arg: bytes) -> None:
        """FBIOPUTCMAP: levels read at the caller's pointers (this process's memory, via /proc/self/mem)."""
        size, code = CMAP_LAYOUTS[struct.calcsize("P")]
        start, length, *pointers = struct.unpack(code, self._copy_in(arg, size))
        if length == 0 or start + length > 256:
            raise OSError(errno.EINVAL, f"palette entries {start}..{start + length - 1} of 256")
        levels = [_user_words(pointer, length) for pointer in pointers[:3]]
        self.palette[start:start + length] = np.stack(levels, axis=1)
        self.stats.palette_loads += 1

    def _wait_vblank(self) -> None:
        """Sleep on the clock to the next refresh boundary (multiples of 1/refresh_hz)."""
        now = self.clock.now()
        self.clock.sleep((math.floor(now * self.refresh_hz) + 1) / self.refresh_hz - now)
        self.stats.vsync_waits += 1

    def map(self, length: int) -> mmap.mmap:
        """A shared mapping of the memory (EINVAL past ``smem_len``, as the fbdev mmap refuses)."""
        if self.closed:
            raise OSError(errno.ENODEV, "no such device")
        if not 0 < length <= self.fix["smem_len"]:
            raise OSError(errno.EINVAL, f"cannot map {length} bytes of {self.fix['smem_len']}")
        return mmap.mmap(self._file.fileno(), length)

    # -- what the screen shows ------------------------------------------------------------------------
    @property
    def width(self) -> int:
        """Visible columns (xres)."""
        return self.var["xres"]

    @property
    def height(self) -> int:
        """Visible rows (yres)."""
        return self.var["yres"]

    @property
    def gram(self) -> np.ndarray:
        """A copy of the framebuffer memory, (yres_virtual, line_length) uint8, padding included."""
        rows, stride = self.var["yres_virtual"], self.fix["line_length"]
        return np.frombuffer(self._memory, dtype=np.uint8, count=rows * stride).reshape(rows, stride).copy()

    def glass(self) -> Image.Image:
        """The visible page at (xoffset, yoffset) decoded with the bitfields: RGB (mode "L" when grey)."""
        var = self.var
        bpp = var["bits_per_pixel"] // 8
        w, h = var["xres"], var["yres"]
        if self.blank_level:
            return Image.new("L" if var["grayscale"] else "RGB", (w, h))
        rows = self.gram[var["yoffset"]:var["yoffset"] + h, var["xoffset"] * bpp:(var["xoffset"] + w) * bpp]
        cells = rows.reshape(h, w, bpp).astype(np.uint32)
        word = np.zeros((h, w), dtype=np.uint32)
        for k in range(bpp):  # little-endian: byte k holds bits 8k..8k+7
            word |= cells[..., k] << np.uint32(8 * k)
        if var["grayscale"]:
            return Image.fromarray(self._field(word, "red"), "L")
        if self.fix["visual"] == VISUAL_PSEUDOCOLOR:
            return Image.fromarray((self.palette[word & 0xFF] >> 8).astype(np.uint8), "RGB")
        return Image.fromarray(np.dstack([self._field(word, c) for c in ("red", "green", "blue")]), "RGB")

    def _field(self, word: np.ndarray, channel: str) -> np.ndarray:
        """One channel as 8-bit values: the field's bits, widened by repeating them (or its top 8 bits)."""
        offset, length = self.var[f"{channel}.offset"], self.var[f"{channel}.length"]
        if length == 0:
            return np.zeros(word.shape, dtype=np.uint8)
        value = (word >> np.uint32(offset)) & np.uint32((1 << length) - 1)
        if length >= 8:
            return (value >> np.uint32(length - 8)).astype(np.uint8)
        acc = value << np.uint32(8 - length)
        filled = length
        while filled < 8:
            acc |= acc >> np.uint32(filled)
            filled *= 2
        return (acc & np.uint32(0xFF)).astype(np.uint8)

    def close(self) -> None:
        """Remove the device: nodes and new mappings fail from now on; ``gram`` and ``glass`` stay readable."""
        if self.closed:
            return
        self.closed = True
        self._file.close()


def _user_words(address: int, count: int) -> np.ndarray:
    """``count`` u16 at ``address`` of this process (EFAULT for a bad pointer, as copy_from_user fails)."""
    if not 0 < address < 1 << 63:
        raise OSError(errno.EFAULT, f"bad address {address:#x}")
    fd = os.open("/proc/self/mem", os.O_RDONLY)
    try:
        data = os.pread(fd, 2 * count, address)
    except OSError:
        raise OSError(errno.EFAULT, f"bad address {address:#x}") from None
    finally:
        os.close(fd)
    if len(data) != 2 * count:
        raise OSError(errno.EFAULT, f"bad address {address:#x}")
    return np.frombuffer(data, dtype="<u2")


class FbdevNode:
    """One open file description of a :class:`FbdevSim` (what ``os.open("/dev/fb0")`` gives a program)."""

    def __init__(self, sim: FbdevSim) -> None:
        self.sim = sim
        self.name = f"sim:fbdev ({sim.id})"
        self.closed = False

    def ioctl(self, request: int, arg: bytes | int) -> bytes:
        """The simulator's ioctl (EBADF once closed)."""
        self._check()
        return self.sim.ioctl(request, arg)

    def map(self, length: int) -> mmap.mmap:
        """A shared mapping of the simulated memory."""
        self._check()
        return self.sim.map(length)

    def close(self) -> None:
        """Close this node (the simulator and its memory stay)."""
        self.closed = True

    def _check(self) -> None:
        if self.closed:
            raise OSError(errno.EBADF, "bad file descriptor")


OPTIONS: tuple[OptionSpec[Any], ...] = (
    OptionSpec("size", pixels, (320, 240), "visible size in pixels, WxH"),
    OptionSpec("bpp", integer(8, 32), 16, "bits per pixel: 8 (grey), 16 (RGB565), 24 (RGB888) or 32 (XRGB8888)"),
    OptionSpec("stride", integer(1), None, "line_length in bytes (default: the row rounded up to 64 bytes)"),
    OptionSpec("virtual", integer(1), None, "yres_virtual in lines (default: twice the height, for panning)"),
    OptionSpec("bgr", boolean, False, "swap red and blue (BGR565, BGR888, XBGR8888)"),
    OptionSpec("vsync", boolean, True, "the driver answers FBIO_WAITFORVSYNC (false: ENOTTY)"),
    OptionSpec("panstep", integer(0, 0xFFFF), 1, "fix.ypanstep (0: the driver cannot pan)"),
    OptionSpec("pseudocolor", boolean, False, "8 bpp with a palette (FBIOPUTCMAP) instead of grey levels"),
    OptionSpec("hz", number(1.0, 1000.0), 60.0, "refresh rate: vertical blanks per second"),
    OptionSpec("path", text, "", "file holding the framebuffer memory (default: a temporary file)"),
)


def create(clock: Clock | None = None, **options: str) -> FbdevSim:
    """Simulator factory for ``sim:fbdev?...`` URLs (options: ``OPTIONS``)."""
    values = read_options(OPTIONS, options, "sim:fbdev")
    width, height = values["size"]
    try:
        return FbdevSim(width, height, values["bpp"], stride=values["stride"], virtual_height=values["virtual"],
                        bgr=values["bgr"], vsync=values["vsync"], panstep=values["panstep"],
                        pseudocolor=values["pseudocolor"],
                        refresh_hz=values["hz"], path=values["path"] or None, clock=clock)
    except ConfigError as exc:
        raise URLError(f"sim:fbdev: {exc}") from None
    except OSError as exc:
        raise URLError(f"sim:fbdev: cannot create the memory file: {exc}") from None


register_simulator("fbdev", create, OPTIONS)
