"""The pixelpen record-input command (being written)."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    """Add pixelpen record-input to the ``pixelpen`` parser."""
