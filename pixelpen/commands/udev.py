"""The pixelpen udev-rules command (being written)."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    """Add pixelpen udev-rules to the ``pixelpen`` parser."""
