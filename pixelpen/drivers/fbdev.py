"""The Linux framebuffer (``/dev/fbN``): screeninfo ioctls, the mmap, stride, bitfield packing and page flipping.

Layouts are ``linux/fb.h``'s (``fb_var_screeninfo`` 160 bytes of u32; ``fb_fix_screeninfo`` holds ``unsigned
long`` fields, 80 bytes on 64-bit, 68 on 32-bit), decoded with ctypes.  A pixel lives at
``(y + yoffset)·line_length + (x + xoffset)·bpp/8``: the stride ``line_length`` is honoured (real hardware pads
rows: 1366 px at 16 bpp -> 2752 bytes).  Pixels are packed from the var bitfields (offset and length per
channel, any bpp of 8/16/24/32) into the pixel word stored little-endian (x86 and ARM boards); 8-bit grey
framebuffers get luma levels, 8-bit pseudocolour ones an RGB 3-3-2 palette (FBIOPUTCMAP).  With
``yres_virtual >= 2·yres`` and a ``ypanstep`` the driver can pan to, frames are drawn on the hidden page and
shown by FBIOPAN_DISPLAY; otherwise single buffering (``buffering`` says why).  The OS is behind
:class:`FramebufferDevice` (ioctl + mmap), so a simulator stands where ``/dev/fb0`` would.
"""

from __future__ import annotations

import ctypes
import errno
import fcntl
import logging
import mmap
import os
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from pixelpen.drivers.devnode import node_open_error
from pixelpen.errors import ConfigError, LinkError
from pixelpen.raster.colour import CHUNK_PIXELS, luma

log = logging.getLogger(__name__)

FBIOGET_VSCREENINFO = 0x4600
FBIOPUT_VSCREENINFO = 0x4601
FBIOGET_FSCREENINFO = 0x4602
FBIOPUTCMAP = 0x4605
FBIOPAN_DISPLAY = 0x4606
FBIOBLANK = 0x4611
FBIO_WAITFORVSYNC = 0x40044620  # _IOW('F', 0x20, __u32)

FB_TYPE_PACKED_PIXELS = 0
FB_VISUAL_TRUECOLOR, FB_VISUAL_PSEUDOCOLOR, FB_VISUAL_DIRECTCOLOR, FB_VISUAL_STATIC_PSEUDOCOLOR = 2, 3, 4, 5
FB_BLANK_UNBLANK, FB_BLANK_POWERDOWN = 0, 4
FB_ACTIVATE_VBL = 16
"""``activate`` flag: apply the pan at the next vertical blank (drivers that can, do)."""

MAX_SIDE = 1 << 16
"""Largest xres/yres (virtual too) taken as sane: a canvas side's limit."""

_VISUALS = {0: "mono01", 1: "mono10", 2: "truecolor", 3: "pseudocolor", 4: "directcolor", 5: "static pseudocolor",
            6: "fourcc"}


class FbBitfield(ctypes.Structure):
    """``struct fb_bitfield``: where one colour channel sits in the pixel word."""

    _fields_ = [("offset", ctypes.c_uint32), ("length", ctypes.c_uint32), ("msb_right", ctypes.c_uint32)]


class FbVarScreeninfo(ctypes.Structure):
    """``struct fb_var_screeninfo`` (160 bytes): the mode, the visible page's offsets and the bitfields."""

    _fields_ = [
        ("xres", ctypes.c_uint32), ("yres", ctypes.c_uint32),
        ("xres_virtual", ctypes.c_uint32), ("yres_virtual", ctypes.c_uint32),
        ("xoffset", ctypes.c_uint32), ("yoffset", ctypes.c_uint32),
        ("bits_per_pixel", ctypes.c_uint32), ("grayscale", ctypes.c_uint32),
        ("red", FbBitfield), ("green", FbBitfield), ("blue", FbBitfield), ("transp", FbBitfield),
        ("nonstd", ctypes.c_uint32), ("activate", ctypes.c_uint32),
        ("height", ctypes.c_uint32), ("width", ctypes.c_uint32), ("accel_flags", ctypes.c_uint32),
        ("pixclock", ctypes.c_uint32), ("left_margin", ctypes.c_uint32), ("right_margin", ctypes.c_uint32),
        ("upper_margin", ctypes.c_uint32), ("lower_margin", ctypes.c_uint32),
        ("hsync_len", ctypes.c_uint32), ("vsync_len", ctypes.c_uint32),
        ("sync", ctypes.c_uint32), ("vmode", ctypes.c_uint32), ("rotate", ctypes.c_uint32),
        ("colorspace", ctypes.c_uint32), ("reserved", ctypes.c_uint32 * 4),
    ]


class FbFixScreeninfo(ctypes.Structure):
    """``struct fb_fix_screeninfo`` (80 bytes on 64-bit, 68 on 32-bit): memory, stride, visual, pan steps."""

    _fields_ = [
        ("id", ctypes.c_char * 16), ("smem_start", ctypes.c_ulong), ("smem_len", ctypes.c_uint32),
        ("type", ctypes.c_uint32), ("type_aux", ctypes.c_uint32), ("visual", ctypes.c_uint32),
        ("xpanstep", ctypes.c_uint16), ("ypanstep", ctypes.c_uint16), ("ywrapstep", ctypes.c_uint16),
        ("line_length", ctypes.c_uint32), ("mmio_start", ctypes.c_ulong), ("mmio_len", ctypes.c_uint32),
        ("accel", ctypes.c_uint32), ("capabilities", ctypes.c_uint16), ("reserved", ctypes.c_uint16 * 2),
    ]


class FbCmap(ctypes.Structure):
    """``struct fb_cmap``: ``len`` palette entries from ``start``, 16-bit levels behind four pointers."""

    _fields_ = [
        ("start", ctypes.c_uint32), ("len", ctypes.c_uint32), ("red", ctypes.POINTER(ctypes.c_uint16)),
        ("green", ctypes.POINTER(ctypes.c_uint16)), ("blue", ctypes.POINTER(ctypes.c_uint16)),
        ("transp", ctypes.POINTER(ctypes.c_uint16)),
    ]


class FramebufferDevice(Protocol):
    """An open framebuffer node: what :class:`Framebuffer` needs from the OS (or from a simulator)."""

    name: str

    def ioctl(self, request: int, arg: bytes | int) -> bytes:
        """``fcntl.ioctl``: a buffer argument comes back as the bytes the driver wrote; OSError on failure."""

    def map(self, length: int) -> mmap.mmap:
        """A shared read-write mapping of the first ``length`` bytes of the framebuffer memory."""

    def close(self) -> None:
        """Close the node (the picture stays on the screen)."""


class DeviceNode:
    """A real framebuffer node: ``os.open`` read-write, ``fcntl.ioctl``, ``mmap.mmap``."""

    def __init__(self, path: str) -> None:
        self.name = path
        try:
            self._fd = os.open(path, os.O_RDWR | os.O_CLOEXEC)
        except OSError as exc:
            raise node_open_error(path, exc, group="video", udev='SUBSYSTEM=="graphics", KERNEL=="fb*"',
                                  missing="load a framebuffer driver (fbdev, or DRM with fbdev emulation) and "
                                          "check the number (ls /dev/fb*)") from exc

    def ioctl(self, request: int, arg: bytes | int) -> bytes:
        """``fcntl.ioctl`` on the node."""
        if isinstance(arg, int):
            fcntl.ioctl(self._fd, request, arg)
            return b""
        buf = bytearray(arg)
        fcntl.ioctl(self._fd, request, buf, True)
        return bytes(buf)

    def map(self, length: int) -> mmap.mmap:
        """Map the framebuffer memory shared, read-write."""
        return mmap.mmap(self._fd, length, mmap.MAP_SHARED, mmap.PROT_READ | mmap.PROT_WRITE)

    def close(self) -> None:
        """Close the file descriptor."""
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1


@dataclass(frozen=True)
class Channel:
    """One colour channel of the pixel word: bit ``offset`` and ``length`` bits."""

    offset: int
    length: int


@dataclass(frozen=True)
class PixelLayout:
    """How an RGB pixel becomes the framebuffer's word: bits per pixel, channels (or grey) and the visual."""

    bits_per_pixel: int
    red: Channel
    green: Channel
    blue: Channel
    transp: Channel
    grey: bool
    """True when a pixel is one grey level (``grayscale`` set, or an 8-bit palette visual used as grey)."""

    @property
    def bytes_per_pixel(self) -> int:
        """Whole bytes per pixel."""
        return self.bits_per_pixel // 8

    def pack(self, rgb: np.ndarray) -> np.ndarray:
        """An HxWx3 uint8 RGB image as HxW·Bpp uint8 framebuffer bytes (vectorised)."""
        h, w = rgb.shape[:2]
        bpp = self.bytes_per_pixel
        if self.grey:
            return luma(rgb)
        channels = (self.red, self.green, self.blue)
        if all(c.length == 8 and c.offset % 8 == 0 for c in channels) and self.transp.length in (0, 8):
            out = np.zeros((h, w, bpp), dtype=np.uint8)
            for i, c in enumerate(channels):
                np.copyto(out[..., c.offset // 8], rgb[..., i])
            if self.transp.length:
                out[..., self.transp.offset // 8] = 0xFF
            return out.reshape(h, w * bpp)
        dtype = np.uint16 if self.bits_per_pixel <= 16 else np.uint32
        flat = rgb.reshape(h * w, 3)
        word = np.empty(h * w, dtype=dtype)
        field = np.empty(min(h * w, CHUNK_PIXELS), dtype=dtype)
        transp = ((1 << self.transp.length) - 1) << self.transp.offset
        for start in range(0, h * w, CHUNK_PIXELS):  # cache-sized chunks of contiguous byte planes
            part, value = flat[start:start + CHUNK_PIXELS], word[start:start + CHUNK_PIXELS]
            value[...] = transp
            for i, c in enumerate(channels):
                _place(np.ascontiguousarray(part[:, i]), c, field[: part.shape[0]])
                value |= field[: part.shape[0]]
        as_bytes = word.astype(word.dtype.newbyteorder("<"), copy=False).view(np.uint8).reshape(h, w, -1)
        return as_bytes[..., :bpp].reshape(h, w * bpp)


def _place(channel: np.ndarray, c: Channel, out: np.ndarray) -> None:
    """8-bit values into ``out`` as the field ``c``: the top ``length`` bits at ``offset`` (bit replication > 8)."""
    mask = out.dtype.type(((1 << c.length) - 1) << c.offset)
    if c.length > 8:  # widen: the 8 bits, then their top bits again below them
        np.left_shift(channel, c.offset + c.length - 8, out=out, dtype=out.dtype)
        out |= np.right_shift(channel, 16 - c.length).astype(out.dtype) << out.dtype.type(c.offset)
    elif c.offset + c.length >= 8:
        np.left_shift(channel, c.offset + c.length - 8, out=out, dtype=out.dtype)
    else:
        np.right_shift(channel, 8 - c.length - c.offset, out=out, dtype=out.dtype)
    out &= mask


RGB332 = PixelLayout(8, Channel(5, 3), Channel(2, 3), Channel(0, 2), Channel(0, 0), grey=False)
"""8-bit pseudocolour with the RGB 3-3-2 palette pixelpen loads."""


class Framebuffer:
    """A mapped framebuffer: pack and write rectangles of RGB pixels, flip pages, wait for vsync, blank."""

    def __init__(self, device: FramebufferDevice, *, double_buffer: bool = True) -> None:
        """Take over an open node (closed again if it is not a usable framebuffer)."""
        self.device = device
        self.name = device.name
        try:
            self._set_up(double_buffer)
        except BaseException:
            device.close()
            raise

    def _set_up(self, double_buffer: bool) -> None:
        self.var = self._get(FBIOGET_VSCREENINFO, FbVarScreeninfo, "FBIOGET_VSCREENINFO")
        self.fix = self._get(FBIOGET_FSCREENINFO, FbFixScreeninfo, "FBIOGET_FSCREENINFO")
        self.layout = self._check_layout()
        self.width, self.height = int(self.var.xres), int(self.var.yres)
        self.line_length = int(self.fix.line_length)
        self.vsync_supported: bool | None = None
        """Whether FBIO_WAITFORVSYNC works (None until tried)."""
        rows = int(self.var.yres_virtual)
        self._memory = self._map(self.line_length * rows)
        self.memory = np.ndarray((rows, self.line_length), dtype=np.uint8, buffer=self._memory)
        """The whole mapped framebuffer, one row of ``line_length`` bytes per virtual line."""
        self.double_buffered, self.buffering = self._choose_buffering(double_buffer)
        self._page = 0 if not self.double_buffered else int(self.var.yoffset) // self.height
        log.info("%s: %dx%d, %d bpp, line_length %d, %s", self.name, self.width, self.height,
                 self.layout.bits_per_pixel, self.line_length, self.buffering)

    @classmethod
    def open(cls, path: str = "/dev/fb0", *, double_buffer: bool = True) -> Framebuffer:
        """Open the framebuffer node at ``path`` (LinkError naming the node and the group on failure)."""
        return cls(DeviceNode(path), double_buffer=double_buffer)

    # -- set-up -------------------------------------------------------------------------------------
    def _get(self, request: int, struct: type[ctypes.Structure], name: str) -> ctypes.Structure:
        size = ctypes.sizeof(struct)
        try:
            data = self.device.ioctl(request, bytes(size))
        except OSError as exc:
            raise LinkError(f"{self.name}: {name} failed: {exc} (not a framebuffer device?)") from None
        if len(data) < size:
            raise LinkError(f"{self.name}: {name} returned {len(data)} bytes, expected {size}")
        return struct.from_buffer_copy(data[:size])

    def _check_layout(self) -> PixelLayout:
        var, fix = self.var, self.fix
        where = self.name
        if fix.type != FB_TYPE_PACKED_PIXELS:
            raise ConfigError(f"{where}: fix.type = {fix.type} is not packed pixels (0); planar framebuffers are "
                              f"not supported")
        bpp = int(var.bits_per_pixel)
        if bpp not in (8, 16, 24, 32):
            raise ConfigError(f"{where}: var.bits_per_pixel = {bpp} is not supported (8, 16, 24 or 32)")
        for field in ("xres", "yres", "xres_virtual", "yres_virtual"):
            if not 0 < getattr(var, field) <= MAX_SIDE:
                raise ConfigError(f"{where}: var.{field} = {getattr(var, field)} is not 1..{MAX_SIDE}")
        if var.xres_virtual < var.xres or var.yres_virtual < var.yres:
            raise ConfigError(f"{where}: var.xres_virtual x yres_virtual = {var.xres_virtual}x{var.yres_virtual} "
                              f"is smaller than the visible {var.xres}x{var.yres}")
        if var.xoffset + var.xres > var.xres_virtual or var.yoffset + var.yres > var.yres_virtual:
            raise ConfigError(f"{where}: var.xoffset, yoffset = {var.xoffset}, {var.yoffset} put the visible page "
                              f"outside the virtual {var.xres_virtual}x{var.yres_virtual}")
        row = var.xres_virtual * bpp // 8
        if fix.line_length < row:
            raise ConfigError(f"{where}: fix.line_length = {fix.line_length} bytes is shorter than a row of "
                              f"xres_virtual = {var.xres_virtual} pixels at {bpp} bpp ({row} bytes)")
        need = fix.line_length * var.yres_virtual
        if fix.smem_len < need:
            raise ConfigError(f"{where}: fix.smem_len = {fix.smem_len} is smaller than line_length x yres_virtual = "
                              f"{fix.line_length} x {var.yres_virtual} = {need} bytes")
        visual = int(fix.visual)
        grey = var.grayscale == 1 or (bpp == 8 and visual in (FB_VISUAL_PSEUDOCOLOR, FB_VISUAL_STATIC_PSEUDOCOLOR))
        if var.grayscale > 1:
            raise ConfigError(f"{where}: var.grayscale = {var.grayscale:#x} is a FOURCC format, not supported")
        if visual not in (FB_VISUAL_TRUECOLOR, FB_VISUAL_DIRECTCOLOR) and not grey:
            name = _VISUALS.get(visual, "unknown")
            raise ConfigError(f"{where}: fix.visual = {visual} ({name}) at {bpp} bpp is not supported (truecolor, "
                              f"directcolor, grey)")
        if grey and bpp != 8:
            raise ConfigError(f"{where}: a grey framebuffer at var.bits_per_pixel = {bpp} is not supported (8)")
        if visual == FB_VISUAL_PSEUDOCOLOR and var.grayscale != 1 and self._load_rgb332_palette():
            return RGB332
        if visual != FB_VISUAL_PSEUDOCOLOR and var.grayscale != 1 and grey:
            log.warning("%s: static pseudocolour: pixelpen writes grey levels as indices; the driver's fixed "
                        "palette decides the colours", where)
        channels = {name: self._channel(name, bpp, needed=not grey and name != "transp")
                    for name in ("red", "green", "blue", "transp")}
        return PixelLayout(bpp, channels["red"], channels["green"], channels["blue"], channels["transp"], grey)

    def _load_rgb332_palette(self) -> bool:
        """FBIOPUTCMAP an RGB 3-3-2 palette (index RRRGGGBB); False, with a warning, if the driver refuses."""
        levels = [[(i >> 5 & 7) * 0xFFFF // 7 for i in range(256)], [(i >> 2 & 7) * 0xFFFF // 7 for i in range(256)],
                  [(i & 3) * 0xFFFF // 3 for i in range(256)]]
        red, green, blue = ((ctypes.c_uint16 * 256)(*level) for level in levels)
        entry = ctypes.POINTER(ctypes.c_uint16)
        cmap = FbCmap(0, 256, ctypes.cast(red, entry), ctypes.cast(green, entry), ctypes.cast(blue, entry), None)
        try:
            self.device.ioctl(FBIOPUTCMAP, bytes(cmap))  # red, green, blue stay alive across the call
        except OSError as exc:
            log.warning("%s: 8-bit pseudocolour and FBIOPUTCMAP failed (%s): pixelpen writes grey levels as "
                        "indices; the driver's palette decides the colours", self.name, exc)
            return False
        return True

    def _channel(self, name: str, bpp: int, *, needed: bool) -> Channel:
        field = getattr(self.var, name)
        if field.msb_right:
            raise ConfigError(f"{self.name}: var.{name}.msb_right = {field.msb_right}: bit-reversed channels are not "
                              f"supported")
        offset, length = int(field.offset), int(field.length)
        if not needed:
            if name != "transp" or offset + length > bpp or length > 16:
                return Channel(0, 0)
            return Channel(offset, length)
        if not 1 <= length <= 16:
            raise ConfigError(f"{self.name}: var.{name}.length = {length} is not 1..16 bits")
        if offset + length > bpp:
            raise ConfigError(f"{self.name}: var.{name} (offset {offset}, length {length}) does not fit "
                              f"var.bits_per_pixel = {bpp}")
        return Channel(offset, length)

    def _map(self, length: int) -> mmap.mmap:
        try:
            return self.device.map(length)
        except (OSError, ValueError) as exc:
            raise LinkError(f"{self.name}: mmap of {length} bytes failed: {exc}") from None

    def _choose_buffering(self, wanted: bool) -> tuple[bool, str]:
        if not wanted:
            return False, "single buffering (double buffering off)"
        step = int(self.fix.ypanstep)
        if self.var.yres_virtual < 2 * self.var.yres:
            return False, (f"single buffering: yres_virtual = {self.var.yres_virtual} holds no second page of "
                           f"{self.var.yres} lines")
        if step == 0 or self.height % step:
            return False, f"single buffering: fix.ypanstep = {step} cannot pan to line {self.height}"
        try:
            self._pan(self.height if self.var.yoffset == self.height else 0)
        except OSError as exc:
            return False, f"single buffering: FBIOPAN_DISPLAY failed ({exc})"
        return True, "double buffering by FBIOPAN_DISPLAY"

    @property
    def size_mm(self) -> tuple[float, float] | None:
        """The visible area in millimetres as the driver reports it (var.width, var.height), None if unknown."""
        if self.var.width and self.var.height:
            return float(self.var.width), float(self.var.height)
        return None

    # -- drawing ------------------------------------------------------------------------------------
    @property
    def visible_page(self) -> int:
        """The page (0 or 1) on the screen."""
        return self._page

    @property
    def draw_page(self) -> int:
        """The page :meth:`write` draws on: the hidden one when double buffered, else the visible one."""
        return 1 - self._page if self.double_buffered else self._page

    def write(self, rgb: np.ndarray, x: int = 0, y: int = 0) -> None:
        """Pack an HxWx3 uint8 RGB block and store it with its top-left at (x, y) of :attr:`draw_page`."""
        self._check_open()
        h, w = rgb.shape[:2]
        if not (x >= 0 and y >= 0 and x + w <= self.width and y + h <= self.height):
            raise ConfigError(f"{self.name}: a {w}x{h} block at ({x}, {y}) does not fit the {self.width}x"
                              f"{self.height} screen")
        top = (self.draw_page * self.height if self.double_buffered else int(self.var.yoffset)) + y
        left = (int(self.var.xoffset) + x) * self.layout.bytes_per_pixel
        self.memory[top:top + h, left:left + w * self.layout.bytes_per_pixel] = self.layout.pack(rgb)

    def flip(self, *, vsync: bool = True) -> None:
        """Show the page just drawn (double buffering; a no-op otherwise), after a vertical blank if asked."""
        self._check_open()
        if not self.double_buffered:
            return
        if vsync:
            self.wait_for_vsync()
        try:
            self._pan(self.draw_page * self.height)
        except OSError as exc:
            raise LinkError(f"{self.name}: FBIOPAN_DISPLAY to yoffset {self.draw_page * self.height} failed: "
                            f"{exc}") from None
        self._page = 1 - self._page

    def _pan(self, yoffset: int) -> None:
        var = FbVarScreeninfo.from_buffer_copy(bytes(self.var))
        var.yoffset = yoffset
        var.activate = FB_ACTIVATE_VBL
        answer = self.device.ioctl(FBIOPAN_DISPLAY, bytes(var))
        self.var.yoffset = yoffset
        if len(answer) >= ctypes.sizeof(FbVarScreeninfo):
            self.var.xoffset = FbVarScreeninfo.from_buffer_copy(answer[:ctypes.sizeof(FbVarScreeninfo)]).xoffset

    def wait_for_vsync(self) -> bool:
        """Wait for the next vertical blank (FBIO_WAITFORVSYNC); False when the driver has no such ioctl."""
        self._check_open()
        if self.vsync_supported is False:
            return False
        try:
            self.device.ioctl(FBIO_WAITFORVSYNC, bytes(4))
        except OSError as exc:
            if exc.errno not in (errno.ENOTTY, errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
                raise LinkError(f"{self.name}: FBIO_WAITFORVSYNC failed: {exc}") from None
            log.info("%s: no FBIO_WAITFORVSYNC (%s): frames are not synchronised to the refresh", self.name, exc)
            self.vsync_supported = False
            return False
        self.vsync_supported = True
        return True

    def blank(self, level: int = FB_BLANK_POWERDOWN) -> None:
        """FBIOBLANK: 0 unblanks, 1..4 blank (4 powers the display down)."""
        self._check_open()
        try:
            self.device.ioctl(FBIOBLANK, level)
        except OSError as exc:
            raise LinkError(f"{self.name}: FBIOBLANK {level} failed: {exc}") from None

    # -- life cycle ---------------------------------------------------------------------------------
    @property
    def closed(self) -> bool:
        """True once :meth:`close` was called."""
        return self._memory.closed

    def _check_open(self) -> None:
        if self.closed:
            raise LinkError(f"{self.name}: the framebuffer is closed")

    def close(self) -> None:
        """Unmap and close the node; what was drawn stays on the screen (idempotent)."""
        if self.closed:
            return
        del self.memory
        self._memory.close()
        self.device.close()
