"""``pixelpen udev-rules``: rules printed for VID:PIDs and the HID simulators' IDs; bad arguments exit 2 saying why."""

from __future__ import annotations

from pixelpen.cli import main
from pixelpen.clock import SimulatedClock
from pixelpen.sim.base import create_simulator


def run(capsys, *argv):
    status = main(["udev-rules", *argv])
    out, err = capsys.readouterr()
    return status, out, err


def test_rules_for_one_device(capsys):
    status, out, _ = run(capsys, "046d:c52b")
    assert status == 0
    assert out.splitlines()[0] == ("# /etc/udev/rules.d/70-pixelpen.rules: lets the user open these HID devices "
                                   "without root (pixelpen udev-rules).")
    assert 'KERNEL=="hidraw*", SUBSYSTEM=="hidraw", ATTRS{idVendor}=="046d", ATTRS{idProduct}=="c52b", ' \
           'TAG+="uaccess"' in out
    assert 'SUBSYSTEM=="usb", ENV{DEVTYPE}=="usb_device", ATTRS{idVendor}=="046d", ATTRS{idProduct}=="c52b", ' \
           'TAG+="uaccess"' in out


def test_group_access_nodes_and_bluetooth(capsys):
    status, out, _ = run(capsys, "046D:B01A", "--access", "group", "--group", "input", "--nodes", "hidraw,input",
                         "--bluetooth")
    assert status == 0
    assert 'KERNEL=="hidraw*", SUBSYSTEM=="hidraw", KERNELS=="*:046D:B01A.*", MODE="0660", GROUP="input"' in out
    assert 'SUBSYSTEM=="input", KERNEL=="event*", KERNELS=="*:046D:B01A.*"' in out
    assert 'SUBSYSTEM=="usb"' not in out


def test_a_device_named_twice_gets_one_block(capsys):
    _, out, _ = run(capsys, "046d:c52b", "046D:C52B")
    assert out.count('KERNEL=="hidraw*"') == 1


def test_all_sims_lists_each_hid_simulators_ids(capsys):
    status, out, _ = run(capsys, "--all-sims")
    assert status == 0
    sim = create_simulator("mouse", clock=SimulatedClock())
    vid, pid = sim.info["vendor_id"], sim.info["product_id"]
    sim.close()
    assert f'ATTRS{{idVendor}}=="{vid:04x}", ATTRS{{idProduct}}=="{pid:04x}"' in out
    assert "simulated mouse" in out and "hp7475a" not in out


def test_bad_ids_name_the_field(capsys):
    status, _, err = run(capsys, "046d:zz")
    assert status == 2 and "product ID" in err
    status, _, err = run(capsys, "/dev/hidraw0")
    assert status == 2 and "expected VID:PID" in err
    status, _, err = run(capsys, "046d:c52b:SERIAL")
    assert status == 2 and "without serial" in err


def test_nothing_asked_for_and_bad_nodes(capsys):
    status, _, err = run(capsys)
    assert status == 2 and "name at least one device" in err
    status, _, err = run(capsys, "046d:c52b", "--nodes", "hidraw,serial")
    assert status == 2 and "serial" in err and "choose from hidraw, usb, input" in err
