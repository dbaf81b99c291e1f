"""Tests of pixelpen.meshfiles."""
