"""Simulated HID input devices: report descriptors from the spec, firmware-style report packing, scripted hand motion.

``descriptors`` holds the report descriptors (bytes, item by item); ``models`` packs each model's reports as
its firmware would and registers the ``sim:mouse`` … ``sim:keyboard`` simulators; ``motion`` scripts the
hand; ``device.HidSim`` is the ReportDevice they share.  Nothing here imports ``pixelpen.devices``.
"""
