"""Simulated HID input devices: report descriptors from the spec, firmware-style report packing, scripted hand motion.

``descriptors`` holds the report descriptors (bytes, item by item, each with its report layout); ``models`` packs
each model's reports as its firmware would and registers the ``sim:mouse`` … ``sim:keyboard`` simulators;
``motion`` scripts the hand; ``device.HidSim`` is the ReportDevice they share; ``replay`` plays a hid-recorder
recording through it.  Nothing here imports ``pixelpen.devices`` (docs/input-simulators.md).
"""
