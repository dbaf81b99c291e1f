"""``pixelpen hid dump``: every kind of SOURCE, both formats, and clear errors with exit status 2."""

from __future__ import annotations

import io
import json

import pytest

from pixelpen.cli import main
from tests.devices.hid.test_descriptor import BOOT_MOUSE

MOUSE_HEX = BOOT_MOUSE.hex(" ")


@pytest.fixture(autouse=True)
def no_user_config(monkeypatch):
    monkeypatch.setenv("PIXELPEN_CONFIG", "")


def run(capsys, *argv):
    code = main(["hid", "dump", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_binary_file_like_a_hidraw_sysfs_node(tmp_path, capsys):
    node = tmp_path / "sys/class/hidraw/hidraw0/device/report_descriptor"
    node.parent.mkdir(parents=True)
    node.write_bytes(BOOT_MOUSE)
    code, out, err = run(capsys, str(node))
    assert code == 0 and err == ""
    assert out.startswith("Report descriptor: 50 bytes, 26 items\n")
    assert "    46  81 06               Input (Data,Var,Rel)" in out
    assert "Input report (unnumbered): 3 bytes" in out


@pytest.mark.parametrize("text", [MOUSE_HEX, MOUSE_HEX.upper(), ", ".join(f"0x{b:02x}" for b in BOOT_MOUSE),
                                  BOOT_MOUSE.hex()])
def test_hex_argument(text, capsys):
    code, out, _ = run(capsys, text)
    assert code == 0 and "50 bytes" in out


def test_stdin_binary_and_hex(monkeypatch, capsys):
    monkeypatch.setattr("sys.stdin", io.TextIOWrapper(io.BytesIO(BOOT_MOUSE)))
    code, out, _ = run(capsys, "-")
    assert code == 0 and "50 bytes" in out
    monkeypatch.setattr("sys.stdin", io.TextIOWrapper(io.BytesIO(MOUSE_HEX.encode() + b"\n")))
    code, out, _ = run(capsys, "-")
    assert code == 0 and "50 bytes" in out


def test_hid_recorder_r_line(tmp_path, capsys):
    code, out, _ = run(capsys, f"R: 50 {MOUSE_HEX}")
    assert code == 0 and "50 bytes" in out
    path = tmp_path / "mouse.hid"
    path.write_text(f"# a comment\nR: 50 {MOUSE_HEX}\n")
    code, out, _ = run(capsys, str(path))
    assert code == 0 and "50 bytes" in out


def test_whole_hid_recorder_file_applies_the_devices_quirks(tmp_path, capsys):
    path = tmp_path / "keytouch.hid"
    path.write_text("D: 0\nR: 2 05 01\nN: Keytouch IEC\nP: usb-0000:00:14.0-1/input0\nI: 3 0926 3333\n")
    code, out, err = run(capsys, str(path))
    assert code == 0, err
    assert "Report descriptor: 65 bytes" in out and "quirk keytouch iec" in out


def test_json_format(capsys):
    code, out, _ = run(capsys, MOUSE_HEX, "--format", "json")
    data = json.loads(out)
    assert code == 0 and data["size"] == 50 and data["reports"][0]["length"] == 3


def test_long_items_warned_or_rejected(capsys):
    text = "05 01 09 02 a1 01 fe 01 10 aa c0"
    code, out, _ = run(capsys, text)
    assert code == 0 and "long item (tag 0x10, 1 data bytes) at offset 6 skipped" in out
    code, out, err = run(capsys, text, "--reject-long-items")
    assert code == 2 and out == "" and "byte offset 6" in err and "long item" in err


@pytest.mark.parametrize("argv, words", [
    (["05 01 09 zz"], "character 10: not hex bytes (pairs of hex digits, optionally 0x-prefixed) (found 'zz')"),
    (["05 01 a1 01"], "byte offset 2: unbalanced collection"),
    (["05"], "byte offset 0: Usage Page cut short"),
    (["no-such-file.bin"], "no such file"),
    (["R: 9 05 01"], "announces 9 bytes but holds 2"),
    (["R: x 05 01"], "size in bytes"),
])
def test_bad_input_exits_2_with_a_clear_message(argv, words, capsys):
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == "" and err.startswith("pixelpen hid: error: ") and words in err


def test_bad_files(tmp_path, capsys):
    empty = tmp_path / "empty.bin"
    empty.write_bytes(b"")
    code, _, err = run(capsys, str(empty))
    assert code == 2 and "empty report descriptor" in err and str(empty) in err
    big = tmp_path / "big.bin"
    big.write_bytes(bytes(5000))
    code, _, err = run(capsys, str(big))
    assert code == 2 and "4096" in err
    two = tmp_path / "two.hid"
    two.write_text(f"R: 50 {MOUSE_HEX}\nN: m\nI: 3 1 2\n")
    code, _, err = run(capsys, str(two), "--device", "3")
    assert code == 2 and "no device 3" in err


def test_hid_needs_an_action(capsys):
    assert main(["hid"]) == 2
    assert "ACTION" in capsys.readouterr().err
