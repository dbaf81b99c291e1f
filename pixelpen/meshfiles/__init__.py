"""Mesh files: Wavefront OBJ and STL (binary and ASCII) read into ``pixelpen.geometry.mesh.Mesh``.

Imports only ``pixelpen.geometry``, ``pixelpen.errors`` and the leaves.  Every reader checks its
:class:`Limits` before allocating for what a file announces and raises a
:class:`~pixelpen.errors.ParseError` naming the file and the line and column (text) or byte offset (binary)
of the first problem; docs/meshfiles.md has the details and the measured speed.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import BinaryIO

from pixelpen.errors import InvalidArgument, InvalidArgumentType, ParseError
from pixelpen.geometry.mesh import Mesh
from pixelpen.meshfiles.limits import LIMITS, Limits
from pixelpen.meshfiles.obj import read_obj
from pixelpen.meshfiles.stl import is_binary_stl, read_stl

__all__ = ["FORMATS", "LIMITS", "Limits", "read_mesh", "read_obj", "read_stl"]

FORMATS = ("obj", "stl")
"""The formats :func:`read_mesh` reads."""


def read_mesh(path_or_file: str | os.PathLike[str] | BinaryIO, *, format: str | None = None,
              limits: Limits = LIMITS) -> Mesh:
    """The mesh in a file (a path or a binary file object); ``format`` "obj" or "stl", else from suffix or content."""
    if format is not None and format not in FORMATS:
        raise InvalidArgument(f"format must be one of {', '.join(FORMATS)} or None, not {format!r}")
    data, source = _read_bytes(path_or_file, limits)
    kind = format or _format_of(source, data)
    return read_obj(data, source, limits=limits) if kind == "obj" else read_stl(data, source, limits=limits)


def _read_bytes(path_or_file: str | os.PathLike[str] | BinaryIO, limits: Limits) -> tuple[bytes, str]:
    """The file's bytes and its name, refusing one larger than ``limits.max_bytes`` before reading it."""
    if isinstance(path_or_file, (str, os.PathLike)):
        source = str(path_or_file)
        try:
            with open(path_or_file, "rb") as stream:
                limits.check("max_bytes", os.fstat(stream.fileno()).st_size, "bytes in the file", source)
                data = stream.read(limits.max_bytes + 1)
        except OSError as exc:
            raise ParseError(f"cannot read the mesh file: {exc.strerror or exc}", source=source) from None
    elif hasattr(path_or_file, "read"):
        source = str(getattr(path_or_file, "name", "<mesh stream>"))
        data = path_or_file.read(limits.max_bytes + 1)
        if not isinstance(data, bytes):
            raise InvalidArgumentType(f"path_or_file must be opened in binary mode, it read {type(data).__name__}")
    else:
        raise InvalidArgumentType(f"path_or_file must be a path or a binary file, not {type(path_or_file).__name__}")
    limits.check("max_bytes", len(data), "bytes in the file (or more)", source)
    return data, source


def _format_of(source: str, data: bytes) -> str:
    """"obj" or "stl" from the name's suffix, else from the content (a binary STL's size, or ``solid``)."""
    suffix = Path(source).suffix.lower().lstrip(".")
    if suffix in FORMATS:
        return suffix
    if is_binary_stl(data) or data.lstrip()[:5] == b"solid":
        return "stl"
    return "obj"
