"""Recorded input devices, read and written in the formats of the tools that record them (hid-recorder, evemu)."""
