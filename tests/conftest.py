"""Suite-wide set-up: CI runs hypothesis derandomized; no test reads the developer's own configuration file."""

from __future__ import annotations

import os

import pytest
from hypothesis import settings

settings.register_profile("ci", derandomize=True)  # CI: the same examples every run; developers' runs explore
if os.environ.get("CI"):
    settings.load_profile("ci")


@pytest.fixture(autouse=True)
def _no_user_configuration(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PIXELPEN_CONFIG", "")  # a test that wants a configuration file sets its own
