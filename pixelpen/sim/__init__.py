"""Simulators written from the devices' documentation, reached through the same transports as real hardware."""
