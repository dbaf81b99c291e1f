"""What one mesh file may make the readers do: sizes checked before anything of that size is allocated."""

from __future__ import annotations

from dataclasses import dataclass, fields

from pixelpen.errors import ConfigError, ParseError

__all__ = ["LIMITS", "Limits"]


@dataclass(frozen=True)
class Limits:
    """The most a mesh file may hold; beyond one is a ParseError naming the limit and where it was passed."""

    max_bytes: int = 256 * 2**20
    """The file's size (256 MiB: about 10 million OBJ triangles or 5 million binary STL facets); reading
    takes about eight times the file's size in memory at its peak."""
    max_vertices: int = 20_000_000
    """Vertices (OBJ ``v`` lines, or distinct STL vertices), and likewise OBJ ``vn`` and ``vt`` lines."""
    max_faces: int = 20_000_000
    """Triangles after polygons are fanned (an STL facet is one)."""
    max_polygon_vertices: int = 2048
    """Corners of one OBJ ``f`` polygon."""
    max_line_chars: int = 65_536
    """Bytes of one line of a text file (the longest polygon of ``max_polygon_vertices`` corners fits)."""

    def __post_init__(self) -> None:
        for item in fields(self):
            value = getattr(self, item.name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f"mesh file limit {item.name} must be a positive integer, not {value!r}")

    def check(self, name: str, count: int, what: str, source: str, *, line: int | None = None,
              offset: int | None = None) -> None:
        """Raise a ParseError when ``count`` ``what`` pass the limit ``name`` (at ``line`` or byte ``offset``)."""
        limit = getattr(self, name)
        if count > limit:
            raise ParseError(f"{count:,} {what}, more than the limit {name}={limit:,}", source=source, line=line,
                             offset=offset)


LIMITS = Limits()
"""The default limits (pass ``limits=Limits(...)`` to a reader to change them)."""
