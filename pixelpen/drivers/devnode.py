"""What a driver needs from the host (its Python library, an openable device node), and errors saying how to get it.

:func:`require_module` imports a driver's optional library or says what to install; :func:`node_open_error`
turns the OSError of opening a node (``/dev/spidev0.0``, ``/dev/i2c-1``, ``/dev/gpiochip0``) into a
LinkError that names the node and says what to do: how to make it exist, or which group may open it
(the node's own group when a non-root group owns it, else the conventional one) and the udev rule.
"""

from __future__ import annotations

import grp
import importlib
import os
from types import ModuleType

from pixelpen.errors import ConfigError, LinkError


def require_module(name: str, *, needed_by: str, install: str, package: str = "") -> ModuleType:
    """``import name``, or ConfigError "<needed_by> need <package>: pip install <install>" when it is missing."""
    try:
        return importlib.import_module(name)
    except ImportError:
        raise ConfigError(f"{needed_by} need {package or f'the {name} package'}: pip install {install}") from None


def node_group(node: str, default: str) -> str:
    """The group owning ``node`` when it is a group other than root, else ``default`` (the usual one)."""
    try:
        name = grp.getgrgid(os.stat(node).st_gid).gr_name
    except (OSError, KeyError):
        return default
    return default if name == "root" else name


def node_open_error(node: str, error: OSError, *, missing: str, group: str, udev: str, what: str = "") -> LinkError:
    """The LinkError for ``error`` raised opening ``node``.

    ``missing`` says how to make the node exist (FileNotFoundError); on PermissionError the message names
    the group to join (see :func:`node_group`) and the udev rule ``udev, GROUP="<group>", MODE="0660"``
    (``udev`` is its match, ``SUBSYSTEM=="spidev"``); any other error keeps the OS's words.  ``what``
    prefixes the message (``"GPIO line 5"``).
    """
    prefix = f"{what}: " if what else ""
    if isinstance(error, FileNotFoundError):
        return LinkError(f"{prefix}{node} does not exist: {missing}")
    if isinstance(error, PermissionError):
        owner = node_group(node, group)
        return LinkError(f"{prefix}permission denied on {node}: add your user to the '{owner}' group "
                         f"(sudo usermod -aG {owner} $USER, then log in again) or add a udev rule "
                         f'{udev}, GROUP="{owner}", MODE="0660"')
    return LinkError(f"{prefix}{node}: cannot open: {error}")
