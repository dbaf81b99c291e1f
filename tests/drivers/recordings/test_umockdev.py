"""umockdev fixtures: the files follow umockdev's formats (script escapes, ioctl sizes, device blocks), offline."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from pixelpen.drivers.recordings.evemu import AbsInfo, EvdevRecording, read_evemu
from pixelpen.drivers.recordings.hidrecorder import HidRecording
from pixelpen.drivers.recordings.umockdev import encode_script_data, export_umockdev
from pixelpen.errors import InvalidArgument, InvalidArgumentType

BOOT_MOUSE = bytes.fromhex("05010902a1010901a100050919012903150025019503750181029501750581010501093009311581"
                           "257f750895028106c0c0")
MOUSE = HidRecording("Test Mouse", "usb-0000:00:14.0-1/input0", 3, 0x046D, 0xC077, BOOT_MOUSE,
                     [(0.0, bytes([1, 5, 0xFB])), (0.25, bytes([0, 0x5E, 10]))])
PEN = EvdevRecording("Test Pen", 3, 0x056A, 0x0374, 0x0110, frozenset({1}),
                     {0: frozenset({0}), 1: frozenset({0x140, 0x14A}), 3: frozenset({0, 1}), 0x11: frozenset({1})},
                     {0: AbsInfo(0, 0, 15200, 4, 0, 100), 1: AbsInfo(0, 0, 9500, 4, 0, 100)}, leds={1: 1},
                     events=[(0.5, 3, 0, 7600), (0.5, 0, 0, 0), (1.5, 3, 0, 7601), (1.5, 0, 0, 0)])


def _ioctls(path: Path) -> dict[str, list[tuple[int, bytes]]]:
    out: dict[str, list[tuple[int, bytes]]] = {}
    for line in path.read_text().splitlines():
        if line.startswith("@"):
            continue
        name, ret, data = line.split(" ")
        out.setdefault(name, []).append((int(ret), bytes.fromhex(data)))
    return out


def test_script_escapes_as_umockdevs_script_format_says():
    # docs/script-format.txt: 0 -> ^@, 1 -> ^A, 10 -> ^J, 30 -> ^^, 94 ('^') -> ^`; >= 32 verbatim
    assert encode_script_data(bytes([0, 1, 10, 30, 94, 32, 65, 0xFF])) == b"^@^A^J^^^` A\xff"


def test_hidraw_script_lines_and_gaps(tmp_path):
    fixture = export_umockdev(MOUSE, tmp_path, realtime=True)
    assert fixture.node == "/dev/hidraw0" and fixture.data.name == "hidraw0.script"
    assert fixture.data.read_bytes() == b"r 0 ^A^E\xfb\nr 250 ^@^`^J\n"
    assert export_umockdev(MOUSE, tmp_path / "fast").data.read_bytes() == b"r 0 ^A^E\xfb\nr 0 ^@^`^J\n"


def test_handshake_puts_a_write_before_each_report(tmp_path):
    assert export_umockdev(MOUSE, tmp_path, handshake=b"\x01k").data.read_bytes() == (
        b"w 0 ^Ak\nr 0 ^A^E\xfb\nw 0 ^Ak\nr 0 ^@^`^J\n")
    with pytest.raises(InvalidArgument, match="handshake is for hidraw"):
        export_umockdev(PEN, tmp_path, handshake=b"go")
    with pytest.raises(InvalidArgument, match="0x20"):
        export_umockdev(MOUSE, tmp_path, handshake=b" go")


def test_a_report_starting_with_a_space_joins_the_one_before(tmp_path):
    rec = HidRecording("m", "", 3, 1, 2, BOOT_MOUSE, [(0.0, b"\x01\x02\x03"), (0.1, b" \x02\x03")])
    assert export_umockdev(rec, tmp_path).data.read_bytes() == b"r 0 ^A^B^C ^B^C\n"
    with pytest.raises(InvalidArgument, match="0x20"):
        export_umockdev(HidRecording("m", "", 3, 1, 2, BOOT_MOUSE, [(0.0, b" \x01")]), tmp_path)


def test_hidraw_ioctls_have_the_kernels_struct_sizes(tmp_path):
    ioctls = _ioctls(export_umockdev(MOUSE, tmp_path).ioctl)
    (ret, size), = ioctls["HIDIOCGRDESCSIZE"]
    assert struct.unpack("<i", size) == (len(BOOT_MOUSE),)
    (ret, desc), = ioctls["HIDIOCGRDESC"]
    assert len(desc) == 4 + 4096  # struct hidraw_report_descriptor: __u32 size, __u8 value[HID_MAX_DESCRIPTOR_SIZE]
    assert desc[:4] == struct.pack("<I", 50) and desc[4:54] == BOOT_MOUSE and desc[54:] == bytes(4096 - 50)
    (ret, info), = ioctls["HIDIOCGRAWINFO"]
    assert struct.unpack("<IhH", info) == (3, 0x046D, 0xC077)  # struct hidraw_devinfo: __u32 bustype, __s16 x2
    (ret, name), = ioctls["HIDIOCGRAWNAME"]
    assert ret == len("Test Mouse") + 1 and len(name) == 256 and name.rstrip(b"\0") == b"Test Mouse"


def test_hidraw_device_tree_has_what_hidapi_enumerate_reads(tmp_path):
    text = export_umockdev(MOUSE, tmp_path).device.read_text()
    blocks = [b.splitlines() for b in text.strip().split("\n\n")]
    paths = [b[0] for b in blocks]
    assert paths[0].endswith("/0003:046D:C077.0001/hidraw/hidraw0") and paths[1].endswith("/0003:046D:C077.0001")
    hidraw, hid, interface, usb = blocks
    assert "N: hidraw0" in hidraw and "E: DEVNAME=/dev/hidraw0" in hidraw and "E: SUBSYSTEM=hidraw" in hidraw
    assert "L: device=../../../0003:046D:C077.0001" in hidraw
    assert "E: HID_ID=0003:0000046D:0000C077" in hid and "E: HID_NAME=Test Mouse" in hid
    assert f"H: report_descriptor={BOOT_MOUSE.hex().upper()}" in hid
    assert "A: bInterfaceNumber=00\\n" in interface and "E: DEVTYPE=usb_interface" in interface
    assert "A: idVendor=046d\\n" in usb and "E: DEVTYPE=usb_device" in usb


def test_bluetooth_device_has_no_usb_parents(tmp_path):
    rec = HidRecording("BT", "aa:bb", 5, 1, 2, BOOT_MOUSE, [])
    text = export_umockdev(rec, tmp_path, number=3).device.read_text()
    assert text.count("P: ") == 2 and "/devices/virtual/misc/uhid/0005:0001:0002.0004" in text
    assert "hidraw3" in text


def test_evdev_ioctls_match_python_evdevs_buffers(tmp_path):
    fixture = export_umockdev(PEN, tmp_path, number=2)
    assert fixture.node == "/dev/input/event2"
    ioctls = _ioctls(fixture.ioctl)
    assert ioctls["EVIOCGID"] == [(0, struct.pack("<4H", 3, 0x056A, 0x0374, 0x0110))]
    bits = {len(data): (ret, data) for ret, data in ioctls["EVIOCGBIT(0)"]}
    # the types: EV_SYN, EV_KEY, EV_ABS -> byte 0 bits 0, 1, 3 = 0x0b; EV_LED (0x11) -> byte 2 bit 1
    assert bits[4] == (4, bytes([0x0B, 0, 0x02, 0]))
    assert bits[96] == (96, bytes([0x0B, 0, 0x02]) + bytes(93))  # EVIOCGBIT(EV_SYN, 96) answers the types too
    keys = bytearray(96)
    keys[0x140 // 8] |= 1  # BTN_TOOL_PEN 320: byte 40 bit 0
    keys[0x14A // 8] |= 1 << 2  # BTN_TOUCH 330: byte 41 bit 2
    assert ioctls["EVIOCGBIT(1)"] == [(96, bytes(keys))]
    assert ioctls["EVIOCGBIT(3)"] == [(96, bytes([0x03]) + bytes(95))]
    assert ioctls["EVIOCGABS(0)"] == [(0, struct.pack("<6i", 0, 0, 15200, 4, 0, 100))]  # struct input_absinfo
    assert ioctls["EVIOCGLED(0)"] == [(2, bytes([0x02, 0]))]  # LED_CAPSL on; (LED_MAX + 7) / 8 bytes
    assert ioctls["EVIOCGSW(0)"] == [(2, bytes(2))]  # (SW_MAX 0x10 + 7) / 8
    assert ioctls["EVIOCGPROP(0)"] == [(4, bytes([0x02, 0, 0, 0]))]  # INPUT_PROP_DIRECT
    assert len(ioctls["EVIOCGNAME(0)"][0][1]) == len(ioctls["EVIOCGPHYS(0)"][0][1]) == 256


def test_evdev_events_file_moves_times_past_second_32(tmp_path):
    fixture = export_umockdev(PEN, tmp_path, realtime=True)
    back = read_evemu("N: x\nI: 0003 0001 0002 0003\n" + fixture.data.read_text())
    assert [t for t, *_ in back.events] == [33.0, 33.0, 34.0, 34.0]
    assert [e[1:] for e in back.events] == [e[1:] for e in PEN.events]
    long = EvdevRecording("x", 3, 1, 2, 3, events=[(0.0, 0, 0, 0), (255.0, 0, 0, 0), (300.0, 0, 0, 0)])
    times = [t for t, *_ in read_evemu("N: x\nI: 0003 0001 0002 0003\n"
                                       + export_umockdev(long, tmp_path / "l", realtime=True).data.read_text()).events]
    assert times == [33.0, 289.0, 334.0]  # 33 + 255 = 288 = 0x120: one second later, and the rest with it
    assert all(int(t) % 256 != 0x20 for t in times)


def test_export_refuses_other_objects_and_bad_numbers(tmp_path):
    with pytest.raises(InvalidArgumentType):
        export_umockdev("not a recording", tmp_path)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument, match="node number"):
        export_umockdev(MOUSE, tmp_path, number=-1)
    with pytest.raises(InvalidArgument, match="line break"):
        export_umockdev(HidRecording("a\nb", "", 3, 1, 2, BOOT_MOUSE, []), tmp_path)


def test_command_line(tmp_path):
    fixture = export_umockdev(MOUSE, tmp_path)
    assert fixture.command("prog") == ["umockdev-run", "--device", str(fixture.device), "--ioctl",
                                       f"/dev/hidraw0={fixture.ioctl}", "--script", f"/dev/hidraw0={fixture.data}",
                                       "--", "prog"]
    assert "--evemu-events" in export_umockdev(PEN, tmp_path).command("prog")
