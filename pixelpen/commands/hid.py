"""The pixelpen hid (dump a report descriptor) command (being written)."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    """Add pixelpen hid (dump a report descriptor) to the ``pixelpen`` parser."""
