"""udev rule text (written by hand from udev(7) syntax and systemd's uaccess tag) and the permission diagnosis.

The diagnosis is fed a fake ``stat`` (owner, group, mode of the node), the user's uid and groups, and a fake
sysfs tree, so every case runs without the node.
"""

from __future__ import annotations

import os
import stat

import pytest

from pixelpen.drivers.udev import ids_of, node_of, permission_diagnosis, rule_line, rules_file, udev_rule
from pixelpen.errors import InvalidArgument

NAMES = {0: "root", 46: "plugdev", 100: "input"}


def fake_stat(mode, uid=0, gid=0):
    def stat_fn(path):
        return os.stat_result((stat.S_IFCHR | mode, 1, 5, 1, uid, gid, 0, 0, 0, 0))

    return stat_fn


def missing(path):
    raise FileNotFoundError(path)


def diagnose(path, mode, uid=0, gid=0, *, me=1000, groups=(1000,), **kw):
    return permission_diagnosis(path, stat=fake_stat(mode, uid, gid), uid=me, groups=groups,
                                group_name=lambda g: NAMES.get(g, str(g)), **kw)


# ---- rules ----------------------------------------------------------------------------------------

def test_rule_lines_by_node_and_access():
    assert rule_line(0x046D, 0xC52B, "hidraw") == \
        'KERNEL=="hidraw*", SUBSYSTEM=="hidraw", ATTRS{idVendor}=="046d", ATTRS{idProduct}=="c52b", TAG+="uaccess"'
    assert rule_line(0x046D, 0xC52B, "usb", access="group") == (
        'SUBSYSTEM=="usb", ENV{DEVTYPE}=="usb_device", ATTRS{idVendor}=="046d", ATTRS{idProduct}=="c52b", '
        'MODE="0660", GROUP="plugdev"')
    assert rule_line(0x056A, 0x0357, "input", access="world") == \
        'SUBSYSTEM=="input", KERNEL=="event*", ATTRS{idVendor}=="056a", ATTRS{idProduct}=="0357", MODE="0666"'


def test_bluetooth_rule_matches_the_hid_device_name():
    # a Bluetooth HID device is named 0005:046D:B01A.0003 in sysfs; it has no USB parent with idVendor
    assert rule_line(0x046D, 0xB01A, "hidraw", usb=False) == \
        'KERNEL=="hidraw*", SUBSYSTEM=="hidraw", KERNELS=="*:046D:B01A.*", TAG+="uaccess"'


def test_udev_rule_block_and_whole_file():
    block = udev_rule(0x1209, 0x0001, name="simulated mouse")
    lines = block.splitlines()
    assert lines[0].startswith("# 1209:0001 simulated mouse: hidraw") and len(lines) == 3
    assert lines[1].startswith('KERNEL=="hidraw*"') and lines[2].startswith('SUBSYSTEM=="usb"')
    text = rules_file([(0x1209, 0x0001, ""), (0x046D, 0xC52B, "")], nodes=("hidraw",))
    assert text.startswith("# /etc/udev/rules.d/70-pixelpen.rules")
    assert "udevadm control --reload-rules" in text and text.count('KERNEL=="hidraw*"') == 2


@pytest.mark.parametrize(("args", "kwargs", "message"), [
    ((0x10000, 1), {}, "vendor ID"),
    ((1, -1), {}, "product ID"),
    ((1, 2), {"access": "root"}, "access"),
    ((1, 2), {"access": "group", "group": 'x", RUN+="evil'}, "group name"),
    ((1, 2), {"nodes": ("serial",)}, "node kind"),
])
def test_rule_arguments_are_checked(args, kwargs, message):
    with pytest.raises(InvalidArgument, match=message):
        udev_rule(*args, **kwargs)


# ---- which node -------------------------------------------------------------------------------------

def test_node_of_each_kind(tmp_path):
    device = tmp_path / "bus/usb/devices/1-2.3"
    device.mkdir(parents=True)
    (device / "busnum").write_text("1\n")
    (device / "devnum").write_text("7\n")
    assert node_of("/dev/hidraw4") == ("hidraw", "/dev/hidraw4")
    assert node_of("/dev/input/event12") == ("input", "/dev/input/event12")
    assert node_of("/dev/bus/usb/001/007") == ("usb", "/dev/bus/usb/001/007")
    assert node_of("1-2.3:1.0", sysfs=str(tmp_path)) == ("usb", "/dev/bus/usb/001/007")
    assert node_of("sim:mouse:0") == ("", "sim:mouse:0")


def test_ids_from_sysfs(tmp_path):
    hid = tmp_path / "class/hidraw/hidraw4/device"
    hid.mkdir(parents=True)
    (hid / "uevent").write_text("DRIVER=hid-generic\nHID_ID=0005:0000046D:0000B01A\nHID_NAME=MX\n")
    assert ids_of("/dev/hidraw4", sysfs=str(tmp_path)) == (0x046D, 0xB01A, False)  # bus 5: Bluetooth
    usb = tmp_path / "bus/usb/devices/3-1"
    usb.mkdir(parents=True)
    (usb / "idVendor").write_text("056a\n")
    (usb / "idProduct").write_text("0357\n")
    assert ids_of("3-1:1.0", sysfs=str(tmp_path)) == (0x056A, 0x0357, True)
    assert ids_of("/dev/hidraw9", sysfs=str(tmp_path)) is None


# ---- diagnosis ---------------------------------------------------------------------------------------

def test_root_only_node_names_the_missing_hidraw_rule():
    text = diagnose("/dev/hidraw4", 0o600, vendor_id=0x046D, product_id=0xC52B)
    assert "/dev/hidraw4 is root:root mode 0600" in text and "no udev rule grants this user access" in text
    assert 'KERNEL=="hidraw*", SUBSYSTEM=="hidraw", ATTRS{idVendor}=="046d", ATTRS{idProduct}=="c52b"' in text
    assert "/etc/udev/rules.d/70-pixelpen.rules" in text and "udevadm trigger" in text


def test_root_only_usb_node_names_the_usb_rule(tmp_path):
    device = tmp_path / "bus/usb/devices/1-2"
    device.mkdir(parents=True)
    for name, value in (("busnum", "1"), ("devnum", "9"), ("idVendor", "1209"), ("idProduct", "0001")):
        (device / name).write_text(value)
    text = diagnose("1-2:1.0", 0o664, sysfs=str(tmp_path))  # usbfs default: world may read, not write
    assert text.startswith("/dev/bus/usb/001/009 is root:root mode 0664")
    assert 'SUBSYSTEM=="usb", ENV{DEVTYPE}=="usb_device", ATTRS{idVendor}=="1209", ATTRS{idProduct}=="0001"' in text


def test_unknown_ids_leave_placeholders_and_say_so():
    text = diagnose("/dev/hidraw4", 0o600, sysfs="/nonexistent")
    assert 'ATTRS{idVendor}=="VVVV", ATTRS{idProduct}=="PPPP"' in text and "lsusb" in text


def test_bluetooth_node_gets_the_kernels_rule(tmp_path):
    hid = tmp_path / "class/hidraw/hidraw2/device"
    hid.mkdir(parents=True)
    (hid / "uevent").write_text("HID_ID=0005:0000046D:0000B01A\n")
    text = diagnose("/dev/hidraw2", 0o600, sysfs=str(tmp_path))
    assert 'KERNELS=="*:046D:B01A.*"' in text


def test_group_rule_present_but_user_not_in_the_group():
    text = diagnose("/dev/hidraw4", 0o660, gid=46, groups=(1000, 100))
    assert "group 'plugdev'" in text and "usermod -aG plugdev" in text and "KERNEL==" not in text


def test_modes_that_allow_access_say_it_is_not_a_rule():
    assert "not a missing udev rule" in diagnose("/dev/hidraw4", 0o660, gid=46, groups=(46,))
    assert "not a missing udev rule" in diagnose("/dev/hidraw4", 0o666)
    assert "not a missing udev rule" in diagnose("/dev/hidraw4", 0o600, uid=1000)
    assert "not a missing udev rule" in diagnose("/dev/hidraw4", 0o600, me=0)


def test_a_missing_node():
    text = permission_diagnosis("/dev/hidraw99", stat=missing, uid=1000, groups=())
    assert "/dev/hidraw99 does not exist" in text


def test_ssh_sessions_are_told_about_uaccess():
    assert "local seat" in diagnose("/dev/hidraw4", 0o600, vendor_id=1, product_id=2)
