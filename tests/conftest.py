"""Suite-wide fixtures: no test reads the developer's own pixelpen configuration file."""

from __future__ import annotations

import pytest


@pytest.fixture(autouse=True)
def _no_user_configuration(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PIXELPEN_CONFIG", "")  # a test that wants a configuration file sets its own
