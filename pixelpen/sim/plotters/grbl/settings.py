"""GRBL's ``$`` settings: numbers, defaults and kinds, the checks ``$n=value`` passes, the ``$$`` listing."""

from __future__ import annotations

from pixelpen.sim.plotters.grbl.modal import STATUS, fmt_float

__all__ = ["DEFAULT_SETTINGS", "MAX_STEP_RATE_HZ", "checked_setting", "default_settings", "settings_report"]

MAX_STEP_RATE_HZ = 30000.0

DEFAULT_SETTINGS: dict[int, tuple[float, str]] = {
    0: (10, "int"), 1: (25, "int"), 2: (0, "int"), 3: (0, "int"), 4: (0, "int"), 5: (0, "int"),
    6: (0, "int"), 10: (1, "int"), 11: (0.010, "float"), 12: (0.002, "float"), 13: (0, "int"),
    20: (0, "int"), 21: (0, "int"), 22: (0, "int"), 23: (3, "int"), 24: (25.0, "float"),
    25: (500.0, "float"), 26: (250, "int"), 27: (1.0, "float"), 30: (1000.0, "rpm"), 31: (0.0, "rpm"),
    32: (0, "int"),
    100: (80.0, "float"), 101: (80.0, "float"), 102: (80.0, "float"),
    110: (5000.0, "float"), 111: (5000.0, "float"), 112: (1000.0, "float"),
    120: (1000.0, "float"), 121: (1000.0, "float"), 122: (500.0, "float"),
    130: (300.0, "float"), 131: (200.0, "float"), 132: (10.0, "float"),
}
"""$ settings of the simulated plotter: number -> (default, kind); kind "int" (uint8), "float" or "rpm"."""

_BOOL_SETTINGS = frozenset({4, 5, 6, 13, 20, 21, 22, 32})


def default_settings(travel: tuple[float, float]) -> dict[int, float]:
    """The settings after ``$RST=$``: GRBL's defaults with the plotter's X and Y travel ($130, $131)."""
    settings = {k: float(v) for k, (v, _) in DEFAULT_SETTINGS.items()}
    settings[130], settings[131] = float(travel[0]), float(travel[1])
    return settings


def checked_setting(settings: dict[int, float], n: int, value: float) -> tuple[int, float]:
    """settings_store_global_setting's checks: (status code, the value as stored)."""
    if value < 0.0:
        return STATUS["negative_value"], value
    if n not in DEFAULT_SETTINGS:
        return STATUS["invalid_statement"], value
    if n in (100, 101, 102) and value * settings[n + 10] > MAX_STEP_RATE_HZ * 60:
        return STATUS["max_step_rate"], value
    if n in (110, 111, 112) and value * settings[n - 10] > MAX_STEP_RATE_HZ * 60:
        return STATUS["max_step_rate"], value
    if n == 0 and int(value) < 3:
        return STATUS["step_pulse_min"], value
    if n == 20 and int(value) and not int(settings[22]):
        return STATUS["soft_limit_needs_homing"], value
    if DEFAULT_SETTINGS[n][1] == "int":
        value = float(int(value) & 0xFF)
        if n in _BOOL_SETTINGS:
            value = 1.0 if value else 0.0
    return 0, value


def settings_report(settings: dict[int, float]) -> bytes:
    """The ``$$`` listing, one ``$n=value`` line per setting in GRBL's order."""
    lines = []
    for n, (_, kind) in DEFAULT_SETTINGS.items():
        v = settings[n]
        text = str(int(v)) if kind == "int" else fmt_float(v, 0 if kind == "rpm" else 3)
        lines.append(f"${n}={text}\r\n")
    return "".join(lines).encode()
