"""The real hidapi ``hidraw`` module and python-evdev against devices umockdev emulates from recordings (no root).

Each test exports a recording (:func:`pixelpen.drivers.recordings.umockdev.export_umockdev`), runs a small
program under ``umockdev-run`` that prints what the real library saw as JSON, and compares it with the
recording.  Skipped, with the reason, only where umockdev (Debian's ``umockdev``, installed by ``.ci/run``)
or the library is missing.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from pixelpen.drivers.recordings.evemu import read_evemu
from pixelpen.drivers.recordings.hidrecorder import HidRecording
from pixelpen.drivers.recordings.umockdev import UmockdevFixture, export_umockdev

pytestmark = pytest.mark.skipif(shutil.which("umockdev-run") is None,
                                reason="umockdev-run is not installed (Debian: apt-get install umockdev)")
REPO = Path(__file__).resolve().parents[2]

# HID 1.11 Appendix B.2, the boot mouse: 3 buttons, 5 bits padding, X and Y as int8 (-127..127)
BOOT_MOUSE = bytes.fromhex("05010902a1010901a100050919012903150025019503750181029501750581010501093009311581"
                           "257f750895028106c0c0")
MOUSE = HidRecording("Test Mouse", "usb-0000:00:14.0-1/input0", 3, 0x046D, 0xC077, BOOT_MOUSE,
                     [(0.0, bytes([0x01, 0x05, 0xFB])), (0.2, bytes([0x00, 0x20, 0x0A])),
                      (0.4, bytes([0x04, 0x81, 0x7F]))])

PEN_EVEMU = """\
# EVEMU 1.3
N: Test Pen Tablet
I: 0003 056a 0374 0110
P: 01 00 00 00 00 00 00 00
B: 00 0b 00 00 00 00 00 00 00
B: 01 00 00 00 00 00 00 00 00
B: 01 00 00 00 00 00 00 00 00
B: 01 00 00 00 00 00 00 00 00
B: 01 00 00 00 00 00 00 00 00
B: 01 00 00 00 00 00 00 00 00
B: 01 01 0c 00 00 00 00 00 00
B: 03 03 00 00 01 00 00 00 00
A: 00 0 15200 4 0 100
A: 01 0 9500 4 0 100
A: 18 0 4095 0 0 0
E: 0.000001 0001 0140 1
E: 0.000001 0003 0000 7600
E: 0.000001 0003 0001 4750
E: 0.000001 0000 0000 0
E: 0.010000 0001 014a 1
E: 0.010000 0003 0018 2048
E: 0.010000 0000 0000 0
"""
# B: 01 line 6 covers codes 320..383: byte 0 = 0x01 -> 320 BTN_TOOL_PEN; byte 1 = 0x0c -> 330, 331 BTN_TOUCH,
# BTN_STYLUS.  B: 03 byte 0 = 0x03 -> ABS_X, ABS_Y; byte 3 = 0x01 -> 24 ABS_PRESSURE.


def run_under(fixture: UmockdevFixture, program: str, tmp_path: Path) -> object:
    """Run ``program`` under umockdev-run with the fixture; what it printed last, as JSON."""
    script = tmp_path / "program.py"
    script.write_text(textwrap.dedent(program))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run(fixture.command(sys.executable, str(script)), capture_output=True, text=True,
                          timeout=60, env=env, check=False)
    assert done.returncode == 0, f"umockdev-run failed:\n{done.stdout}\n{done.stderr}"
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_real_hidraw_module_enumerates_reads_and_times_out(tmp_path):
    pytest.importorskip("hidraw", reason="cython-hidapi's hidraw module (PyPI hidapi) is not installed")
    fixture = export_umockdev(MOUSE, tmp_path)
    seen = run_under(fixture, """
        import json, hidraw
        found = hidraw.enumerate(0x046d, 0xc077)
        d = hidraw.device()
        d.open_path(found[0]["path"])
        reads = [d.read(3, 1000) for _ in range(3)]
        tail = d.read(3, 200)
        info = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in found[0].items()}
        print(json.dumps({"info": info, "descriptor": d.get_report_descriptor(), "reads": reads, "tail": tail}))
    """, tmp_path)
    assert isinstance(seen, dict)
    info = seen["info"]
    assert (info["path"], info["vendor_id"], info["product_id"]) == ("/dev/hidraw0", 0x046D, 0xC077)
    assert (info["product_string"], info["interface_number"]) == ("Test Mouse", 0)
    assert (info["usage_page"], info["usage"]) == (0x01, 0x02)  # Generic Desktop Mouse, from the descriptor
    assert bytes(seen["descriptor"]) == BOOT_MOUSE
    assert [bytes(r) for r in seen["reads"]] == [r for _, r in MOUSE.reports]
    assert seen["tail"] == []  # the script is over: a read times out


def test_pixelpen_hidapi_link_and_mouse_semantics_on_the_real_module(tmp_path):
    pytest.importorskip("hidraw", reason="cython-hidapi's hidraw module (PyPI hidapi) is not installed")
    # HidapiLink reads a whole buffer, as hidraw gives one report a read; the emulated node is a stream, so
    # each report is sent only when the program asks for it (it writes "go" to the node)
    fixture = export_umockdev(MOUSE, tmp_path, handshake=b"go")
    seen = run_under(fixture, """
        import json, os
        from pixelpen.devices.hid import parse_descriptor
        from pixelpen.devices.hid.semantics import semantics_for
        from pixelpen.drivers.hidapi import open_hid
        link = open_hid("046d:c077")
        sem = semantics_for(parse_descriptor(link.report_descriptor), link.device_id)
        out = []
        node = open("/dev/hidraw0", "wb", buffering=0)
        for _ in range(3):
            node.write(b"go")
            report = link.read_report(5.0)
            out += [type(e).__name__ + ":" + ",".join(f"{k}={getattr(e, k)}" for k in ("dx", "dy", "button", "pressed")
                                                       if hasattr(e, k)) for e in sem.feed(report, 0.0)]
        out.append(repr(link.read_report(0.2)))
        node.close()
        link.close()
        print(json.dumps(out))
    """, tmp_path)
    # by hand from the boot mouse layout: byte 0 buttons 1..3, byte 1 X, byte 2 Y (int8)
    assert seen == ["Motion:dx=5,dy=-5", "Button:button=1,pressed=True",
                    "Motion:dx=32,dy=10", "Button:button=1,pressed=False",
                    "Motion:dx=-127,dy=127", "Button:button=3,pressed=True", "None"]


def test_real_python_evdev_reads_the_ids_axes_and_events(tmp_path):
    pytest.importorskip("evdev", reason="python-evdev (the input extra) is not installed")
    rec = read_evemu(PEN_EVEMU)
    fixture = export_umockdev(rec, tmp_path)
    seen = run_under(fixture, """
        import json, select, evdev
        d = evdev.InputDevice("/dev/input/event0")
        caps = d.capabilities(absinfo=True)
        events = []
        while select.select([d.fd], [], [], 0.5)[0]:
            events += [[e.type, e.code, e.value] for e in d.read()]
        print(json.dumps({"name": d.name, "info": list(d.info), "props": d.input_props(),
                          "keys": caps[evdev.ecodes.EV_KEY], "abs": {str(c): list(a) for c, a in caps[3]},
                          "events": events, "listed": evdev.list_devices()}))
    """, tmp_path)
    assert isinstance(seen, dict)
    assert (seen["name"], seen["info"]) == ("Test Pen Tablet", [3, 0x056A, 0x0374, 0x0110])
    assert seen["props"] == [0]  # INPUT_PROP_POINTER
    assert seen["keys"] == [0x140, 0x14A, 0x14B]
    assert seen["abs"] == {"0": [0, 0, 15200, 4, 0, 100], "1": [0, 0, 9500, 4, 0, 100], "24": [0, 0, 4095, 0, 0, 0]}
    assert seen["events"] == [list(e[1:]) for e in rec.events]
    assert seen["listed"] == ["/dev/input/event0"]


def test_evdev_link_and_semantics_on_real_python_evdev(tmp_path):
    pytest.importorskip("evdev", reason="python-evdev (the input extra) is not installed")
    fixture = export_umockdev(read_evemu(PEN_EVEMU), tmp_path)
    seen = run_under(fixture, """
        import json
        from pixelpen.devices.hid.evdev import EvdevSemantics
        from pixelpen.drivers.evdev import EvdevLink
        with EvdevLink("/dev/input/event0", grab=True) as link:
            sem = EvdevSemantics(link.device_id, link.absinfo, keys=link.codes.get(1, ()))
            pens = []
            while len(pens) < 2:
                batch = link.read_events(2.0)
                assert batch, "timed out"
                pens += sem.feed_events(batch)
            tail = link.read_events(0.2)
        print(json.dumps({"id": [link.device_id.bus, link.device_id.vendor_id, link.device_id.name],
                          "pens": [[p.x_mm, p.y_mm, p.pressure, p.touching, p.in_range] for p in pens],
                          "tail": tail}))
    """, tmp_path)
    assert seen == {"id": ["usb", 0x056A, "Test Pen Tablet"],
                    "pens": [[76.0, 47.5, 0.0, False, True], [76.0, 47.5, 2048 / 4095, True, True]], "tail": []}
