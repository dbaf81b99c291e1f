"""Who a device is: the identity an input device keeps across unplugging and plugging in again.

Transports (hidapi, pyusb, evdev, the hotplug monitor) build it from what enumeration tells; events
(:mod:`pixelpen.devices.hid.events`) carry it.  It lives with the drivers so that both can use it.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True, slots=True)
class DeviceId:
    """Who sent an event: bus, vendor/product IDs, serial, name, interface, and where it is now."""

    bus: str
    """``usb``, ``bluetooth``, ``i2c``, ``virtual`` (simulators and recordings) or ``unknown``."""
    vendor_id: int
    product_id: int
    serial: str = ""
    name: str = ""
    interface: int = -1
    """The USB interface number (-1 when the transport does not say)."""
    path: str = field(default="", compare=False)
    """Where the device is reached now (a hidraw node, a libusb path); it changes across replug."""

    @property
    def key(self) -> str:
        """The identity that survives unplugging and plugging in again (``usb:046d:c52b:SERIAL:1``)."""
        return f"{self.bus}:{self.vendor_id:04x}:{self.product_id:04x}:{self.serial}:{self.interface}"

    def __str__(self) -> str:
        serial = f" {self.serial}" if self.serial else ""
        return f"{self.name or 'HID device'} ({self.bus} {self.vendor_id:04x}:{self.product_id:04x}{serial})"
