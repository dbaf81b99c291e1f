"""The house rules of docs/architecture.md, read from the source with ast: which room may import which, module sizes."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "pixelpen"

LEAVES = ("errors", "urls", "options", "colour", "clock", "tomltext")
"""Top-level modules everyone may import; they import only each other."""

FORBIDDEN: dict[str, tuple[str, ...]] = {
    "sim": ("devices", "display", "input", "commands", "cli"),
    "raster": ("display", "devices", "drivers", "sim", "input", "commands", "cli"),
    "vector": ("display", "devices", "drivers", "sim", "input", "commands", "cli"),
    "geometry": ("display", "devices", "drivers", "sim", "input", "commands", "cli", "raster", "vector", "profiles"),
    "meshfiles": ("display", "devices", "drivers", "sim", "input", "commands", "cli", "raster", "vector", "profiles"),
    "profiles": ("display", "devices", "drivers", "sim", "input", "commands", "cli", "raster", "vector"),
    "drivers": ("devices", "display", "sim", "input", "commands", "cli"),
    "display": ("devices", "drivers", "sim", "input", "commands", "cli"),
    "devices": ("commands", "cli", "input"),
    "input": ("sim", "commands", "cli"),
}
"""Room -> rooms (first component below ``pixelpen``) it must never import, not even inside a function."""

MAX_LINES = 600
LONG_REASON = "Longer than 600 lines because"
"""A module over MAX_LINES says why in its docstring, starting with these words."""


def _modules() -> list[Path]:
    return sorted(p for p in PACKAGE.rglob("*.py") if "data" not in p.relative_to(PACKAGE).parts)


def _name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(source: str, module: str, is_package: bool) -> list[tuple[int, str]]:
    """(line, absolute module name) of every import in ``source`` of ``module``, relative ones resolved."""
    package = module.split(".") if is_package else module.split(".")[:-1]
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package[: len(package) - (node.level - 1)]
                base = ".".join(anchor + ([node.module] if node.module else []))
            found.append((node.lineno, base))
            found += [(node.lineno, f"{base}.{alias.name}") for alias in node.names if base == "pixelpen"]
    return sorted(found)


def _file_imports(path: Path) -> list[tuple[int, str]]:
    return _imports(path.read_text(encoding="utf-8"), _name(path), path.name == "__init__.py")


def _room(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[0] == "pixelpen" else None


def test_rooms_import_only_what_the_architecture_allows() -> None:
    broken = []
    for path in _modules():
        here = _room(_name(path))
        if here in LEAVES:
            allowed = set(LEAVES)
            for line, target in _file_imports(path):
                there = _room(target)
                if there is not None and there not in allowed:
                    broken.append(f"{path.relative_to(PACKAGE.parent)}:{line}: leaf {here} imports {target}")
            continue
        for line, target in _file_imports(path):
            there = _room(target)
            if here in FORBIDDEN and there in FORBIDDEN[here]:
                broken.append(f"{path.relative_to(PACKAGE.parent)}:{line}: {here}/ imports {target}")
    assert not broken, "import rules broken (docs/architecture.md, 'Import rules'):\n" + "\n".join(broken)


def test_imports_inside_functions_and_relative_ones_are_seen() -> None:
    source = "def f():\n    from ...devices import hpgl\n    import pixelpen.display.base\nfrom . import sheet\n"
    found = [target for _, target in _imports(source, "pixelpen.sim.plotters.probe", is_package=False)]
    assert found == ["pixelpen.devices", "pixelpen.display.base", "pixelpen.sim.plotters"]
    assert [t for _, t in _imports("from .. import sim\n", "pixelpen.display", is_package=True)] == [
        "pixelpen", "pixelpen.sim"]


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(PACKAGE.parent)))
def test_a_long_module_says_why(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    lines = text.count("\n")
    if lines <= MAX_LINES:
        return
    doc = ast.get_docstring(ast.parse(text)) or ""
    assert LONG_REASON in doc, f"{path.name} has {lines} lines: split it, or say why in its docstring ({LONG_REASON!r})"
