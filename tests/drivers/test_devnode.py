"""node_open_error: what a missing or forbidden device node's error says (node, group, udev rule, what to do)."""

from __future__ import annotations

import errno
import grp
import os

import pytest

from pixelpen.drivers.devnode import node_group, node_open_error, require_module
from pixelpen.errors import ConfigError, LinkError

SPI = {"group": "spi", "udev": 'SUBSYSTEM=="spidev"', "missing": "enable SPI (dtparam=spi=on)"}


def test_a_missing_node_says_how_to_make_it_exist():
    error = node_open_error("/dev/spidev0.0", FileNotFoundError(errno.ENOENT, "No such file"), **SPI)
    assert isinstance(error, LinkError)
    assert str(error) == "/dev/spidev0.0 does not exist: enable SPI (dtparam=spi=on)"


def test_permission_denied_names_the_group_and_the_udev_rule():
    error = node_open_error("/dev/spidev-not-here", PermissionError(errno.EACCES, "Permission denied"), **SPI)
    assert str(error) == ("permission denied on /dev/spidev-not-here: add your user to the 'spi' group "
                          "(sudo usermod -aG spi $USER, then log in again) or add a udev rule "
                          'SUBSYSTEM=="spidev", GROUP="spi", MODE="0660"')


def test_the_nodes_own_group_is_named_unless_it_is_root(tmp_path):
    node = tmp_path / "spidev0.0"
    node.write_bytes(b"")
    others = [g for g in grp.getgrall() if g.gr_gid != 0]
    if not others:
        pytest.skip("no group but root on this machine")
    try:
        os.chown(node, -1, others[0].gr_gid)
    except PermissionError:
        pytest.skip("only root may give a file to another group")
    assert node_group(str(node), "spi") == others[0].gr_name
    assert f"'{others[0].gr_name}' group" in str(node_open_error(str(node), PermissionError(13, "no"), **SPI))
    os.chown(node, -1, 0)
    assert node_group(str(node), "spi") == "spi"  # root's group is no one's to join
    assert node_group(str(tmp_path / "absent"), "i2c") == "i2c"


def test_other_errors_keep_the_os_words_and_what_prefixes_every_message():
    busy = node_open_error("/dev/i2c-1", OSError(errno.EBUSY, "Device or resource busy"), **SPI)
    assert str(busy) == "/dev/i2c-1: cannot open: [Errno 16] Device or resource busy"
    missing = node_open_error("/dev/gpiochip3", FileNotFoundError(2, "x"), what="GPIO line 5", **SPI)
    assert str(missing).startswith("GPIO line 5: /dev/gpiochip3 does not exist: ")


def test_a_missing_library_says_what_to_install(monkeypatch):
    assert require_module("errno", needed_by="x", install="x") is errno
    monkeypatch.setitem(__import__("sys").modules, "spidev", None)  # what an absent package looks like to import
    with pytest.raises(ConfigError) as caught:
        require_module("spidev", needed_by="SPI panels", install="spidev")
    assert str(caught.value) == "SPI panels need the spidev package: pip install spidev"
    with pytest.raises(ConfigError, match=r"^GPIO lines need gpiod 2: pip install 'gpiod>=2\.1'$"):
        require_module("no_such_module_here", needed_by="GPIO lines", package="gpiod 2", install="'gpiod>=2.1'")
