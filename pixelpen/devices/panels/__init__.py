"""Raster panels behind a slow bus: SSD1306-family OLEDs, MIPI-DCS TFTs, the Linux framebuffer."""
