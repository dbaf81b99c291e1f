"""drivers/ moves bytes for every device family: it imports neither sim/, devices/ nor display/ (walked with ast)."""

from __future__ import annotations

import ast
from pathlib import Path

import pixelpen.drivers

FORBIDDEN = ("pixelpen.sim", "pixelpen.devices", "pixelpen.display")


def _imports(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names.add(node.module)
    return names


def test_drivers_import_no_simulator_device_or_display_module():
    folder = Path(pixelpen.drivers.__file__).parent
    bad = {
        f"{path.name}: {name}"
        for path in folder.rglob("*.py")
        for name in _imports(path)
        if name.startswith(FORBIDDEN)
    }
    assert not bad
